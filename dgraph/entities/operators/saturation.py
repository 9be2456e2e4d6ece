"""Saturation: clip a signal between bounds."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.entities.operators.shape import shape_problem, vector_shape
from dgraph.params import MAX_SIZE


@dg.register
class Saturation(dg.Entity):
    """``output = min(max(input, lower), upper)`` component-wise.

    Parameters: ``size`` (None for scalars). Inputs: ``input``; ``lower`` and ``upper``
    (scalars or vectors, default -inf / +inf). Outputs: ``output``.
    """

    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="vector size (None: scalar)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, size: int | None = None) -> None: ...
    input = dg.Input(shape=vector_shape)
    lower = dg.Input(shape=None, default=-np.inf, doc="lower bound (scalar or vector)")
    upper = dg.Input(shape=None, default=np.inf, doc="upper bound (scalar or vector)")

    def constant_problem(self, name: str, value: Any) -> str | None:
        """A constant bound is a scalar, or (vectors) ``size`` values."""
        if name not in ("lower", "upper"):
            return None
        return shape_problem(value, [()] if self.size is None else [(), (self.size,)])

    def check(self) -> list[str]:
        """Constant bounds are in order (``lower <= upper``)."""
        lower, upper = self.lower, self.upper
        if lower.source is None and upper.source is None and np.any(np.asarray(lower.value) > upper.value):
            return [f"lower {lower.value} is above upper {upper.value}"]
        return []

    @dg.output(shape=vector_shape, depends=("input", "lower", "upper"))
    def output(self, t: int) -> Any:
        """The clipped input."""
        u = self.input(t)
        lo, hi = self.lower(t), self.upper(t)
        if self.size is None:
            return float(min(max(u, lo), hi))
        return np.clip(u, lo, hi)
