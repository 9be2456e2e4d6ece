"""Saturation: clip a signal between bounds."""

from __future__ import annotations

from typing import Any

import numpy as np

import dgraph as dg
from dgraph.entities.operators.shape import vector_shape
from dgraph.params import MAX_SIZE


@dg.register
class Saturation(dg.Entity):
    """``output = min(max(input, lower), upper)`` component-wise.

    Parameters: ``size`` (None for scalars). Inputs: ``input``; ``lower`` and ``upper``
    (scalars or vectors, default -inf / +inf). Outputs: ``output``.
    """

    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="vector size (None: scalar)")
    input = dg.Input(shape=vector_shape)
    lower = dg.Input(shape=None, default=-np.inf, doc="lower bound (scalar or vector)")
    upper = dg.Input(shape=None, default=np.inf, doc="upper bound (scalar or vector)")

    @dg.output(shape=vector_shape, depends=("input", "lower", "upper"))
    def output(self, t: int) -> Any:
        """The clipped input."""
        u = self.input(t)
        lo, hi = self.lower(t), self.upper(t)
        if self.size is None:
            return float(min(max(u, lo), hi))
        return np.clip(u, lo, hi)
