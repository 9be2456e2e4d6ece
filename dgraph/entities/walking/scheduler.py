"""ContactScheduler: the walking phase machine, which says at each tick which feet are contacts of
the QP, which swings, and how contacts are removed and created without force jumps."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import dgraph as dg
from dgraph.entities.references.minimum_jerk import minimum_jerk
from dgraph.entities.walking.footsteps import FootstepPlan


@dataclass(frozen=True)
class FootSchedule:
    """One foot at one tick (see :class:`ContactScheduler` for each field)."""

    contact: bool
    swing: bool
    normal_force_scale: float
    force_weight_scale: float
    motion_weight: float


@dataclass(frozen=True)
class Schedule:
    """Both feet and the phase at one tick."""

    left: FootSchedule
    right: FootSchedule
    phase: int
    progress: float
    double_support: bool


@dg.register
class ContactScheduler(dg.Entity):
    """The contact schedule of a footstep plan (walking notes §1.9, item 2: init DS -> SS -> DS
    -> ... -> final DS), at plan time ``s = t dt - plan.start``, for each foot:

    - ``{side}_contact``: the foot is on the ground in the plan's phase at ``s``, so its contact is
      in the QP (Contact6d ``active``);
    - ``{side}_swing``: the foot swings (the single support of one of its footsteps);
    - ``{side}_normal_force_scale`` (Contact6d ``normal_force_scale``): removal. In the double
      support before a foot's lift-off at ``s_lo`` it falls from 1 to 0 over the last ``T =
      min(transition, double support)`` s, ``1 - m((s - s_lo + T) / T)`` with the minimum-jerk
      ``m(x) = 10 x^3 - 15 x^4 + 6 x^5`` (C2, at most ``1.875 dt / T`` per tick), so the foot
      carries nothing when its contact leaves the QP at lift-off (TSID's
      ``removeRigidContact(name, duration)``); 0 while it swings, else 1;
    - ``{side}_force_weight_scale`` (Contact6d ``force_weight_scale``): creation. From a foot's
      touch-down at ``s_td`` it falls from ``W = force_weight_scale_start`` to 1 over the first
      ``T`` s of the double support, geometrically: ``W^(1 - m((s - s_td) / T))``, so the new
      contact's share of the load grows smoothly instead of jumping (stack-of-tasks/tsid issue
      #88); 1 otherwise. A weight ramped linearly would stay near ``W`` until the last ticks
      and release the force in a few of them, as a decade of the weight moves a decade of the
      force's regularisation;
    - ``{side}_motion_weight`` (a Task's ``weight``): ``swing_weight`` while the foot swings, else
      0: the foot's motion task acts only in its swing (thesis Chapter 5, L6520-6528).

    and ``phase`` (index in ``plan.phases``), ``phase_progress`` ([0, 1]), ``double_support``.
    A zero-length double support has no ramp (the contact changes at once). Both ramps lie in
    double supports, and a foot on the ground in single support has scales 1.

    Parameters: ``transition`` (s,
    default 0.1: no more than any double support > 0 of the plan, else a ParamError at the
    first tick that reads the plan), ``force_weight_scale_start`` (``W``, default 1e3),
    ``swing_weight`` (default 2e3: twice the CoM task's 1e3 of Table 4.2, as the feet tracking
    weight is twice the CoM's in Table 5.3, 100 and 50), ``dt``.
    Input: ``plan`` (FootstepPlan). Everything is computed once per tick (and plan).
    """

    transition = dg.Param(0.1, kind="float", minimum=0.0, doc="duration in s of the contact removal and creation "
                                                              "ramps (<= every double support > 0)")
    force_weight_scale_start = dg.Param(1e3, kind="float", minimum=1.0,
                                        doc="force weight scale of a contact at its touch-down, ramped to 1")
    swing_weight = dg.Param(2e3, kind="float", minimum=0.0, doc="weight of a foot's motion task while it swings")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, transition: float = 0.1, force_weight_scale_start: float = 1000.0,
            swing_weight: float = 2000.0, dt: float | None = None,
        ) -> None: ...

    plan = dg.Input(dtype=FootstepPlan, doc="the footstep plan")

    def setup(self) -> None:
        """No schedule yet; the plan is checked when first read."""
        self._last: tuple[int, FootstepPlan, Schedule] | None = None
        self._checked: FootstepPlan | None = None

    def _check(self, plan: FootstepPlan) -> None:
        """ParamError if ``transition`` exceeds a double support > 0 of ``plan``."""
        for index, phase in enumerate(plan.phases):
            if phase.kind == "double" and 0.0 < phase.duration < self.transition:
                raise dg.ParamError(f"{self.name} ({self.type_name}): parameter 'transition' ({self.transition} s) "
                                    f"exceeds the double support of phase {index} ({phase.duration:g} s)",
                                    entity=self.name)
        self._checked = plan

    def _schedule(self, t: int) -> Schedule:
        """Everything at tick ``t``, computed once per tick and plan."""
        plan = self.plan(t)
        last = self._last
        if last is not None and last[0] == t and last[1] is plan:
            return last[2]
        if plan is not self._checked:
            self._check(plan)
        time = plan.time(t * self.dt)
        index, phase, progress = plan.phase_at(time)
        double = phase.kind == "double"
        lifting = touched = None
        if double:
            phases = plan.phases
            lifting = phases[index + 1].swing_side if index + 1 < len(phases) else None
            touched = phases[index - 1].swing_side if index > 0 else None
        ramp = min(self.transition, phase.duration)
        feet = [self._foot(side, phase.stance, phase.swing_side, ramp, phase.end - time if side == lifting else None,
                           time - phase.start if side == touched else None) for side in ("left", "right")]
        schedule = Schedule(feet[0], feet[1], index, progress, double)
        self._last = (t, plan, schedule)
        return schedule

    def _foot(self, side: str, stance: tuple[str, ...], swing_side: str | None, ramp: float,
              to_lift_off: float | None, since_touch_down: float | None) -> FootSchedule:
        """One foot: ``to_lift_off`` (s) is given in the double support before its lift-off,
        ``since_touch_down`` in the one after its touch-down; ``ramp`` the ramps' duration."""
        contact = side in stance
        normal_scale, weight_scale = (1.0 if contact else 0.0), 1.0
        if ramp > 0.0 and to_lift_off is not None and to_lift_off < ramp:
            normal_scale = minimum_jerk(max(to_lift_off, 0.0) / ramp)[0]
        if ramp > 0.0 and since_touch_down is not None and since_touch_down < ramp:
            weight_scale = self.force_weight_scale_start ** (1.0 - minimum_jerk(max(since_touch_down, 0.0) / ramp)[0])
        swing = swing_side == side
        return FootSchedule(contact, swing, normal_scale, weight_scale, self.swing_weight if swing else 0.0)

    # -- outputs ------------------------------------------------------------------------------
    @dg.output(shape=(), dtype="bool", depends=("plan", "t"))
    def left_contact(self, t: int) -> bool:
        """The left foot is on the ground: its contact is in the QP."""
        return self._schedule(t).left.contact

    @dg.output(shape=(), dtype="bool", depends=("plan", "t"))
    def right_contact(self, t: int) -> bool:
        """The right foot is on the ground: its contact is in the QP."""
        return self._schedule(t).right.contact

    @dg.output(shape=(), dtype="bool", depends=("plan", "t"))
    def left_swing(self, t: int) -> bool:
        """The left foot swings."""
        return self._schedule(t).left.swing

    @dg.output(shape=(), dtype="bool", depends=("plan", "t"))
    def right_swing(self, t: int) -> bool:
        """The right foot swings."""
        return self._schedule(t).right.swing

    @dg.output(shape=(), depends=("plan", "t"))
    def left_normal_force_scale(self, t: int) -> float:
        """Scale of the left contact's normal-force bound, in [0, 1]."""
        return self._schedule(t).left.normal_force_scale

    @dg.output(shape=(), depends=("plan", "t"))
    def right_normal_force_scale(self, t: int) -> float:
        """Scale of the right contact's normal-force bound, in [0, 1]."""
        return self._schedule(t).right.normal_force_scale

    @dg.output(shape=(), depends=("plan", "t"))
    def left_force_weight_scale(self, t: int) -> float:
        """Scale (>= 1) of the left contact's force regularisation weight."""
        return self._schedule(t).left.force_weight_scale

    @dg.output(shape=(), depends=("plan", "t"))
    def right_force_weight_scale(self, t: int) -> float:
        """Scale (>= 1) of the right contact's force regularisation weight."""
        return self._schedule(t).right.force_weight_scale

    @dg.output(shape=(), depends=("plan", "t"))
    def left_motion_weight(self, t: int) -> float:
        """Weight of the left foot's motion task: ``swing_weight`` in its swing, else 0."""
        return self._schedule(t).left.motion_weight

    @dg.output(shape=(), depends=("plan", "t"))
    def right_motion_weight(self, t: int) -> float:
        """Weight of the right foot's motion task: ``swing_weight`` in its swing, else 0."""
        return self._schedule(t).right.motion_weight

    @dg.output(shape=(), dtype="int", depends=("plan", "t"))
    def phase(self, t: int) -> int:
        """Index of the current phase in ``plan.phases``."""
        return self._schedule(t).phase

    @dg.output(shape=(), depends=("plan", "t"))
    def phase_progress(self, t: int) -> float:
        """Progress of the current phase, in [0, 1]."""
        return self._schedule(t).progress

    @dg.output(shape=(), dtype="bool", depends=("plan", "t"))
    def double_support(self, t: int) -> bool:
        """Both feet are on the ground."""
        return self._schedule(t).double_support
