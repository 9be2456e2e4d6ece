"""AnchoredContact: what the contacts share: activation, anchoring, the bounds of their friction rows."""

from __future__ import annotations

from typing import Any

import numpy as np

import dgraph as dg
from dgraph.entities.activation import Activatable


class AnchoredContact(Activatable):
    """Mixin for a contact that holds its frame where it was when the contact became active.

    Has the input ``active`` (:class:`~dgraph.entities.activation.Activatable`), the inputs
    ``normal_force_scale`` and ``force_weight_scale`` (a contact scheduler ramps them so that a
    contact is removed and created without a force jump: :meth:`force_terms`), and declares the
    state ``anchor`` (what :meth:`here` returned at the first active tick; ``None`` while inactive,
    staged only when it changes, so a steady contact does not disturb its readers).
    Subclasses define ``here(t)``: where the contact frame is at ``t`` (the placement or the
    point, as a copy), which is what an activation anchors.
    """

    has_state = True

    anchor = dg.State(dtype="object", doc="anchored placement or point; None while inactive")
    _scaled_bounds: tuple[float, np.ndarray, np.ndarray] | None = None  # (scale, lower, upper), the last made
    normal_force_scale = dg.Input(shape=(), default=1.0, minimum=0.0,
                                  doc="multiplies max_normal_force (a contact being removed ramps it to 0)")
    force_weight_scale = dg.Input(shape=(), default=1.0, minimum=0.0,
                                  doc="multiplies force_weight (a contact being created starts high, ramps to 1)")

    def friction_bounds(self, n_faces: int) -> tuple[np.ndarray, np.ndarray]:
        """The bounds of the friction rows: ``n_faces`` faces ``c_i . f <= 0``, then the normal
        force within ``[min_normal_force, max_normal_force]`` (the subclass's parameters;
        ``ParamError`` when crossed)."""
        if self.max_normal_force < self.min_normal_force:
            raise dg.ParamError(f"{self.name}: max_normal_force < min_normal_force", entity=self.name)
        return (np.concatenate([np.full(n_faces, -np.inf), [self.min_normal_force]]),
                np.concatenate([np.zeros(n_faces), [self.max_normal_force]]))

    def force_terms(self, t: int) -> tuple[np.ndarray, np.ndarray, float]:
        """The friction rows' bounds and the force weight at ``t``: the total normal force within
        ``[min(f_min, s f_max), s f_max]`` with ``s = normal_force_scale``, the weight
        ``force_weight * force_weight_scale``. Unscaled, the bounds are the arrays made at
        configure time (the solver writes its constant rows again only when they change); a scale
        makes new arrays, once per distinct value."""
        lower, upper = self._lower, self._upper
        scale = self.normal_force_scale(t)
        if scale != 1.0:
            cached = self._scaled_bounds
            if cached is None or cached[0] != scale:
                upper = upper.copy()
                upper[-1] *= scale
                lower = lower.copy()
                lower[-1] = min(lower[-1], upper[-1])
                cached = self._scaled_bounds = (scale, lower, upper)
            lower, upper = cached[1], cached[2]
        return lower, upper, self.force_weight * self.force_weight_scale(t)

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
