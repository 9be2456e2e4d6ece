"""AnchoredContact: the activation and anchoring shared by the contacts."""

from __future__ import annotations

from typing import Any

import dgraph as dg
from dgraph.entities.activation import Activatable


class AnchoredContact(Activatable):
    """Mixin for a contact that holds its frame where it was when the contact became active.

    Has the input ``active`` (:class:`~dgraph.entities.activation.Activatable`) and declares the
    state ``anchor`` (what :meth:`here` returned at the first active tick; ``None`` while inactive,
    staged only when it changes, so a steady contact does not disturb its readers).
    Subclasses define ``here(t)``: where the contact frame is at ``t`` (the placement or the
    point, as a copy), which is what an activation anchors.
    """

    has_state = True

    anchor = dg.State(dtype="object", doc="anchored placement or point; None while inactive")

    def anchor_or_here(self, t: int) -> Any:
        """The anchor, or the current placement before the first anchoring tick."""
        anchor = self.anchor(t)
        return self.here(t) if anchor is None else anchor

    def reset(self) -> None:
        """No anchor until the first active tick."""
        self.anchor.set(None, 0)
        self._changed = False

    def prepare_state(self, t: int) -> None:
        """Anchor at the first active tick; forget the anchor when inactive."""
        anchored = self.anchor(t) is not None
        self._changed = anchored != bool(self.active(t))
        if self._changed:
            self.anchor.stage(None if anchored else self.here(t))

    def commit_state(self, t_next: int) -> None:
        """Publish the anchor if it changed."""
        if self._changed:
            self.anchor.commit(t_next)
