"""Switch: route one of n inputs to the output."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import dgraph as dg
from dgraph.entities.operators.shape import vector_shape
from dgraph.params import MAX_PORTS, MAX_SIZE


@dg.register
class Switch(dg.Entity):
    """``output = in_k`` with ``k = selection``; only the selected input is evaluated.

    Parameters: ``n_inputs`` (default 2), ``size`` (None for scalars).
    Inputs: ``selection`` (int, default 0), ``in0 .. in{n-1}``. Outputs: ``output``.
    """

    n_inputs = dg.Param(2, kind="int", minimum=1, maximum=MAX_PORTS, doc="number of inputs")
    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="vector size (None: scalar)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, n_inputs: int = 2, size: int | None = None) -> None: ...
    selection = dg.Input(shape=(), dtype="int", default=0, doc="index of the routed input")

    def configure(self) -> None:
        """Declare the inputs ``in0 .. in{n-1}``."""
        for i in range(self.n_inputs):
            self.declare(f"in{i}", dg.Input(shape=vector_shape))

    def constant_problem(self, name: str, value: Any) -> str | None:
        """A constant selection names one of the inputs."""
        if name == "selection" and not 0 <= value < self.n_inputs:
            return f"expected 0..{self.n_inputs - 1} (one of in0..in{self.n_inputs - 1}), got {value}"
        return None

    @dg.output(shape=vector_shape, on_demand=True)
    def output(self, t: int) -> Any:
        """The selected input."""
        k = self.selection(t)
        if not 0 <= k < self.n_inputs:
            raise dg.ComputeError(f"{self.name}.selection = {k} at tick {t}, expected 0..{self.n_inputs - 1}",
                               entity=self.name, signal="selection")
        return getattr(self, f"in{k}")(t)
