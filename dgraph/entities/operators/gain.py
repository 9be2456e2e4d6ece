"""Gain: a scalar, diagonal or matrix gain applied to a vector."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.entities.operators.shape import shape_problem, vector_shape
from dgraph.params import MAX_SIZE


@dg.register
class Gain(dg.Entity):
    """``output = gain * input`` with a scalar or diagonal gain, or ``gain @ input`` for a matrix.

    Parameters: ``size`` (None for scalars). Inputs: ``input``; ``gain`` (default 1; a
    scalar, a vector of ``size`` for a diagonal gain, or a ``size x size`` matrix).
    Outputs: ``output``.
    """

    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="vector size (None: scalar)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, size: int | None = None) -> None: ...
    input = dg.Input(shape=vector_shape, doc="the signal to scale")
    gain = dg.Input(shape=None, default=1.0, doc="scalar, diagonal (vector) or matrix gain")

    def constant_problem(self, name: str, value: Any) -> str | None:
        """A constant gain is a scalar, or (vectors) ``size`` values or a ``size x size`` matrix."""
        if name != "gain":
            return None
        return shape_problem(value, [()] if self.size is None else [(), (self.size,), (self.size, self.size)])

    @dg.output(shape=vector_shape, depends=("input", "gain"))
    def output(self, t: int) -> Any:
        """The scaled input."""
        k = self.gain(t)
        u = self.input(t)
        if isinstance(k, np.ndarray) and k.ndim == 2:
            return k @ u
        return k * u
