"""Constant: an output that holds a parameter value."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg


@dg.register
class Constant(dg.Entity):
    """A constant value.

    Parameters: ``value`` (a number, vector or matrix).
    Outputs: ``output = value`` (shape of ``value``); computed once, never stale.
    """

    value = dg.Param(kind="vector", doc="the constant (number, vector or matrix)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, value: ArrayLike) -> None: ...

    def configure(self) -> None:
        """Store the value as a float for a scalar, an array otherwise."""
        self._constant: Any = float(self.value) if self.value.ndim == 0 else self.value
        self.value_shape = np.shape(self.value)

    @dg.output(shape=lambda self: self.value_shape, depends=())
    def output(self, t: int) -> Any:
        """The constant."""
        return self._constant
