"""Integrator: forward-Euler integral of its input."""

from __future__ import annotations

from typing import TYPE_CHECKING

from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.discrete.state_shape import initial_state, state_shape
from dgraph.params import MAX_SIZE


@dg.register
class Integrator(dg.Entity):
    """Forward Euler: ``output(t + 1) = output(t) + dt * input(t)``, ``output(0) = initial``.

    Parameters: ``size`` (None for scalars), ``initial`` (default 0), ``dt`` (default: the
    graph's). Inputs: ``input``. States: ``output``.
    """

    has_state = True
    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="vector size (None: scalar)")
    initial = dg.Param(None, kind="vector", doc="initial value (default 0)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, size: int | None = None, initial: ArrayLike | None = None, dt: float | None = None,
        ) -> None: ...
    input = dg.Input(shape=state_shape, doc="the derivative")
    output = dg.State(shape=state_shape, doc="the integral")

    def reset(self) -> None:
        """Start from the initial value."""
        self.output.set(initial_state(self), 0)

    def prepare_state(self, t: int) -> None:
        """Compute ``x + dt u`` at ``t``."""
        self.output.stage(self.output(t) + self.dt * self.input(t))

    def commit_state(self, t_next: int) -> None:
        """Publish the integral at ``t + 1``."""
        self.output.commit(t_next)
