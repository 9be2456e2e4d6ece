"""Delay: the input one tick later; the legal way to close a loop inside a graph."""

from __future__ import annotations

from typing import TYPE_CHECKING

from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.discrete.state_shape import initial_state, state_shape
from dgraph.params import MAX_SIZE


@dg.register
class Delay(dg.Entity):
    """One-tick delay: ``output(t + 1) = input(t)``, ``output(0) = initial``.

    Parameters: ``size`` (None for scalars), ``initial`` (default 0).
    Inputs: ``input``. States: ``output``.
    """

    has_state = True
    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="vector size (None: scalar)")
    initial = dg.Param(None, kind="vector", doc="output before the first tick (default 0)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, size: int | None = None, initial: ArrayLike | None = None) -> None: ...
    input = dg.Input(shape=state_shape)
    output = dg.State(shape=state_shape, doc="the input of the previous tick")

    def reset(self) -> None:
        """Output the initial value."""
        self.output.set(initial_state(self), 0)

    def prepare_state(self, t: int) -> None:
        """Sample the input at ``t``."""
        self.output.stage(self.input(t))

    def commit_state(self, t_next: int) -> None:
        """Publish the sample as the output at ``t + 1``."""
        self.output.commit(t_next)
