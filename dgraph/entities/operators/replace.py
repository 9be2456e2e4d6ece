"""Replace: overwrite some components of a vector."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.params import MAX_SIZE


@dg.register
class Replace(dg.Entity):
    """``output = input`` with ``output[indices] = values``: the inverse of :class:`Selector`.

    E.g. one joint's torque of a whole-body torque vector replaced by what an actuator filter
    makes of it. The input is not modified (the output is a copy).

    Parameters: ``size`` (input size), ``indices`` (replaced components, distinct, in the order
    of ``values``). Inputs: ``input`` (size), ``values`` (len(indices)). Outputs: ``output`` (size).
    """

    size = dg.Param(kind="int", minimum=1, maximum=MAX_SIZE, doc="size of the input vector")
    indices = dg.Param(kind="int_list", doc="indices of the replaced components")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, size: int, indices: Sequence[int]) -> None: ...
    input = dg.Input(shape=("size",), doc="the vector whose components are replaced")
    values = dg.Input(shape=lambda self: (len(self.indices),), doc="the new components, in the order of indices")

    def configure(self) -> None:
        """Check the indices against the input size (a component replaced twice is refused)."""
        bad = [i for i in self.indices if not -self.size <= i < self.size]
        if bad or not self.indices:
            raise dg.ParamError(f"{self.name}: indices {bad or '[]'} invalid for size {self.size}", entity=self.name)
        index = np.array(self.indices, dtype=int) % self.size
        if np.unique(index).size != index.size:
            raise dg.ParamError(f"{self.name}: indices {list(self.indices)} name a component twice", entity=self.name)
        self._index = index

    @dg.output(shape=("size",), depends=("input", "values"))
    def output(self, t: int) -> Any:
        """The input with the components at ``indices`` replaced."""
        out = np.array(self.input(t), dtype=float)
        out[self._index] = self.values(t)
        return out
