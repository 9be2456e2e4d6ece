"""FootContactState: a foot's contact flag for the solver, from the contact plan and the measured force."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg


class ContactThresholds(NamedTuple):
    """The switching rules' constants (see :class:`FootContactState`)."""

    touch_force: float
    release_force: float
    touch_ticks: int
    release_ticks: int
    early_touchdown_progress: float


def next_contact_flag(active_before: bool, held_before: int, planned: bool, swing_progress: float,
                      normal_force: float, thresholds: ContactThresholds) -> tuple[bool, int]:
    """The flag at a tick and the ticks its switching condition has held (the state of the next
    tick), from the flag and that count at the tick before, the plan's flag, the swing's progress
    and the measured normal force at the tick: the rule table of :class:`FootContactState`."""
    if not planned:
        if swing_progress < thresholds.early_touchdown_progress:
            return False, 0  # lift-off and the first part of the swing: the plan rules
        if active_before:
            return True, 0  # an early touch-down holds until the plan's
    if active_before:
        switching, dwell = normal_force <= thresholds.release_force, thresholds.release_ticks
    else:
        switching, dwell = normal_force >= thresholds.touch_force, thresholds.touch_ticks
    held = held_before + 1 if switching else 0
    if held >= dwell:
        return not active_before, 0
    return active_before, held


@dg.register
class FootContactState(dg.Entity):
    """A foot's contact state for the solver: the contact scheduler's flag, corrected by the
    measured normal force where the foot's real contact differs from the plan (a late or an
    early touch-down, a foot rolling off an edge). The MPTC report takes its contact flags
    ``Gamma_l``, ``Gamma_r`` in ``U = [S, Gamma_l J_lfoot^T, Gamma_r J_rfoot^T]`` from the footstep
    plan alone (report §3.3, L221-223), so on uneven ground U has wrench columns for a foot in the
    air, or none for a loaded one (report §5, L314; walking notes §4.5; issue 15).

    With ``f_n = n . F(t)`` the measured normal force (``F`` the ground's force on the foot,
    world: the ``force`` of an :class:`~dgraph.entities.estimators.ExternalForce` on the ankle
    sensor, ``R f_s - m_foot g``), ``P = planned(t)``, ``x = swing_progress(t)``, ``a`` the flag
    at ``t - 1`` and ``h`` the ticks, up to ``t - 1``, that its switching condition has held,
    the flag at ``t`` (:func:`next_contact_flag`):

    ============================  ===========================  =====================================
    case                          switching condition at t     flag at t
    ============================  ===========================  =====================================
    ``not P``, ``x < x_early``    none                         off at once (lift-off: the swing
                                                               starts on time; a scuff as the foot
                                                               lifts is no contact)
    ``not P``, ``x >= x_early``,  none                         on (an early touch-down holds until
    ``a``                                                      the plan's)
    ``not a``: ``P``, or          ``f_n >= touch_force``       on once it has held ``touch_ticks``
    ``x >= x_early``                                           ticks, ``t`` included (touch-down:
                                                               early, on time, late, or after a
                                                               loss)
    ``a``, ``P``                  ``f_n <= release_force``     off once it has held ``release_ticks``
                                                               ticks (a loss: rolled off an edge)
    ============================  ===========================  =====================================

    ``h`` counts consecutive ticks: it restarts at 0 when the condition fails or the flag
    switches. So a planned stance whose sole is still in the air (a lower floor) stays inactive
    and the solver commands no wrench from it; a foot loaded in the last part of its swing (it
    landed on an obstacle) is a contact before the plan's touch-down. An early contact is not
    released by a low force: until the plan's touch-down it may carry a few newtons only (below),
    so an unloaded sole does not say it has left the ground.
    ``x`` is the scheduler's ``phase_progress``: a foot the plan lifts swings through one
    single-support phase, whose progress is the swing's.

    The contact's ``normal_force_scale`` passes through, changed for an early contact only: the
    plan's, at least ``early_normal_force_scale``. The plan's 0 in the swing would pin the sole's
    corner forces to the single point 0, and ProxQP then reported the feasible MPTC QP
    infeasible at the first ticks of some early contacts (graphs/talos_*_mptc_sensed.yaml); 0.02
    of TALOS's 1000 N is the touch force, and a foot resting on the ground late in its swing
    carries 10-60 N. The swing task may stay on: against the rigid rows of its own sole its cost
    is constant, it no longer moves the foot.

    Thresholds, from the flat 20 cm walk under MPTC (graphs/talos_walk_20cm_mptc.yaml, the ankle
    forces compensated for the 1.6 kg foot): a swinging foot reads within +-3 N (its own
    acceleration and the estimate's tilt) from 10 % to 80 % of its swing, but up to 26 N in the
    first 10 %, the sole leaving the floor (hence ``x_early`` 0.5, the apex, from which the foot
    descends); it meets the floor at 87-91 % of the swing, is loaded by 67-145 N within 10 ticks
    and then rests on it with 10-60 N: ``touch_force`` 20 N held 3 ticks (not a one-sample
    spike), ``release_force`` 5 N. The plan unloads a foot before its lift-off to under 5 N for
    its last 5-6 ticks only, so ``release_ticks`` 20 never releases a stance foot early, and a
    foot that rolls off an edge is released 20 ms after.

    The flag is a function of the inputs at ``t`` and of the states, so a planned lift-off turns
    it off at the tick the plan does and a dwell counts the reading of ``t``; the states take
    the flag and the count of ``t`` at ``t + 1``.

    Parameters: ``normal`` (3, world, the contact normal; normalised), ``touch_force``,
    ``release_force`` (N, ``release < touch``: hysteresis), ``touch_ticks``, ``release_ticks``
    (dwells, ticks), ``early_touchdown_progress`` (``x_early`` in [0, 1]; 1 takes no touch-down
    early), ``early_normal_force_scale``, ``start_active`` (the flag before the first tick: a
    robot starts standing on its feet).
    Inputs: ``planned`` (bool, the scheduler's ``{side}_contact``), ``swing_progress`` ([0, 1]),
    ``force`` (3, N, world), ``planned_normal_force_scale`` (the scheduler's
    ``{side}_normal_force_scale``, default 1).
    Outputs: ``normal_force`` (``f_n``, N), ``active`` (bool, for ``Contact6d.active``),
    ``touchdown`` (bool: the flag turns on at ``t``), ``normal_force_scale`` (for
    ``Contact6d.normal_force_scale``).
    States: ``active_before`` (bool, the flag at ``t - 1``), ``held`` (int, ticks).
    """

    has_state = True
    normal = dg.Param([0.0, 0.0, 1.0], kind="vector", doc="contact normal, world")
    touch_force = dg.Param(20.0, kind="float", minimum=0.0, doc="normal force that makes the contact (N)")
    release_force = dg.Param(5.0, kind="float", minimum=0.0, doc="normal force under which it is lost (N)")
    touch_ticks = dg.Param(3, kind="int", minimum=1, doc="ticks f_n >= touch_force before the contact is made")
    release_ticks = dg.Param(20, kind="int", minimum=1, doc="ticks f_n <= release_force before it is lost")
    early_touchdown_progress = dg.Param(0.5, kind="float", minimum=0.0, maximum=1.0,
                                        doc="swing progress from which a loaded foot is a contact before the plan's")
    early_normal_force_scale = dg.Param(0.02, kind="float", minimum=0.0, maximum=1.0,
                                        doc="least normal-force scale of a foot that touched before the plan's "
                                            "touch-down")
    start_active = dg.Param(True, kind="bool", doc="the flag before the first tick")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, normal: ArrayLike = (0.0, 0.0, 1.0), touch_force: float = 20.0,
            release_force: float = 5.0, touch_ticks: int = 3, release_ticks: int = 20,
            early_touchdown_progress: float = 0.5, early_normal_force_scale: float = 0.02, start_active: bool = True,
        ) -> None: ...

    planned = dg.Input(shape=(), dtype="bool", doc="the plan's flag (the contact scheduler's {side}_contact)")
    swing_progress = dg.Input(shape=(), doc="progress of the foot's swing in [0, 1] (the scheduler's phase_progress)")
    force = dg.Input(shape=(3,), doc="the ground's force on the foot (N, world)")
    planned_normal_force_scale = dg.Input(shape=(), default=1.0, minimum=0.0,
                                          doc="the plan's normal-force scale of the foot's contact (the scheduler's)")
    active_before = dg.State(shape=(), dtype="bool", doc="the flag at t - 1")
    held = dg.State(shape=(), dtype="int", initial=0, doc="ticks the switching condition has held, up to t - 1")

    def configure(self) -> None:
        """Unit normal; hysteresis check."""
        normal = np.asarray(self.normal, dtype=float)
        if normal.shape != (3,) or not np.linalg.norm(normal) > 1e-9:
            raise dg.ParamError(f"{self.name}: normal must be a non-zero 3-vector", entity=self.name)
        if self.release_force >= self.touch_force:
            raise dg.ParamError(f"{self.name}: release_force must be below touch_force", entity=self.name)
        self._normal = normal / np.linalg.norm(normal)
        self._thresholds = ContactThresholds(self.touch_force, self.release_force, self.touch_ticks,
                                             self.release_ticks, self.early_touchdown_progress)

    def reset(self) -> None:
        """The flag before the first tick is ``start_active``; nothing has held."""
        super().reset()
        self.active_before.set(self.start_active, 0)

    def _next(self, t: int) -> tuple[bool, int]:
        """The flag at ``t`` and the count to publish at ``t + 1``."""
        return next_contact_flag(bool(self.active_before(t)), int(self.held(t)), bool(self.planned(t)),
                                 float(self.swing_progress(t)), self.normal_force(t), self._thresholds)

    @dg.output(shape=(), depends=("force",))
    def normal_force(self, t: int) -> float:
        """``f_n = n . F`` (N)."""
        return float(self._normal @ self.force(t))

    @dg.output(shape=(), dtype="bool", depends=("planned", "swing_progress", "normal_force", "active_before", "held"))
    def active(self, t: int) -> bool:
        """The contact flag at ``t`` (the rule table)."""
        return self._next(t)[0]

    @dg.output(shape=(), dtype="bool", depends=("active", "active_before"))
    def touchdown(self, t: int) -> bool:
        """The flag turns on at ``t``."""
        return bool(self.active(t)) and not self.active_before(t)

    @dg.output(shape=(), depends=("active", "planned", "planned_normal_force_scale"))
    def normal_force_scale(self, t: int) -> float:
        """The contact's normal-force scale: the plan's, at least ``early_normal_force_scale`` for an early contact."""
        scale = float(self.planned_normal_force_scale(t))
        if self.active(t) and not self.planned(t):
            return max(scale, self.early_normal_force_scale)
        return scale

    def prepare_state(self, t: int) -> None:
        """Stage the flag and the count of ``t``."""
        active, held = self._next(t)
        self.active_before.stage(active)
        self.held.stage(held)

    def commit_state(self, t_next: int) -> None:
        """Publish them at ``t + 1``."""
        self.active_before.commit(t_next)
        self.held.commit(t_next)


__all__ = ["ContactThresholds", "FootContactState", "next_contact_flag"]
