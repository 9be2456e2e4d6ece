"""Selector: pick components of a vector."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.params import MAX_SIZE


@dg.register
class Selector(dg.Entity):
    """``output = input[indices]``.

    Parameters: ``size`` (input size), ``indices`` (components to keep, in order).
    Inputs: ``input`` (size). Outputs: ``output`` (len(indices)).
    """

    size = dg.Param(kind="int", minimum=1, maximum=MAX_SIZE, doc="size of the input vector")
    indices = dg.Param(kind="int_list", doc="indices of the kept components")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, size: int, indices: Sequence[int]) -> None: ...
    input = dg.Input(shape=("size",))

    def configure(self) -> None:
        """Check the indices against the input size."""
        bad = [i for i in self.indices if not -self.size <= i < self.size]
        if bad or not self.indices:
            raise dg.ParamError(f"{self.name}: indices {bad or '[]'} invalid for size {self.size}",
                             entity=self.name)
        self._index = np.array(self.indices, dtype=int)
        self.n_out = len(self.indices)

    @dg.output(shape=("n_out",), depends=("input",))
    def output(self, t: int) -> Any:
        """The selected components."""
        return self.input(t)[self._index]
