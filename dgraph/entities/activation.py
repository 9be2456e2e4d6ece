"""Activatable: the ``active`` input and its ``activate`` / ``deactivate`` commands."""

from __future__ import annotations

import dgraph as dg


class Activatable:
    """Mixin for a task, contact or constraint that a solver takes or leaves at run time.

    Declares the input ``active`` (bool, default true; plug it, or use the commands
    ``activate`` / ``deactivate``, which set it). What "inactive" means is the entity's: a
    contact adds nothing to its QP, a task leaves its level without rows.
    """

    active = dg.Input(shape=(), dtype="bool", default=True, doc="whether the solver takes it")

    @dg.command
    def activate(self) -> None:
        """Put it back in the solver (from the next read of ``active``)."""
        self.active.set(True)

    @dg.command
    def deactivate(self) -> None:
        """Take it out of the solver."""
        self.active.set(False)
