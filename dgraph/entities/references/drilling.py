"""DrillingSequence: the finite-state machine of a drilling cycle over a list of holes (thesis Table 6.2)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg

MOVE, APPROACH, RAMP, HOLD, RELEASE, RETRACT, DONE = range(7)
PHASES = ("move", "approach", "ramp", "hold", "release", "retract", "done")
"""Phase names by number (the ``phase`` state)."""
CONTACT_PHASES = (RAMP, HOLD, RELEASE)
"""Phases in which the tool contact and the force task are active."""


def quintic(s: float) -> tuple[float, float, float]:
    """The minimum-jerk profile ``p(s) = 10 s^3 - 15 s^4 + 6 s^5`` on ``s`` clipped to [0, 1], with
    ``p'(s)`` and ``p''(s)`` (zero outside)."""
    if s <= 0.0:
        return 0.0, 0.0, 0.0
    if s >= 1.0:
        return 1.0, 0.0, 0.0
    return (s**3 * (10.0 - 15.0 * s + 6.0 * s * s), 30.0 * s * s * (1.0 - s) ** 2,
            60.0 * s * (1.0 - s) * (1.0 - 2.0 * s))


@dg.register
class DrillingSequence(dg.Entity):
    """Drills a list of holes in a surface of world ``normal``: for each hole ``h_k`` in turn,

    ====== ========== ====================================================================
    phase  duration   what the outputs ask
    ====== ========== ====================================================================
    0 move     ``move``     tool point (pose task) from where it is to the standoff
                            ``s_k = h_k + standoff n`` (minimum jerk)
    1 approach ``approach``+   from ``s_k`` to ``h_k - depth n``, ``depth`` into the surface,
                            then held until the contact is made: ``n . F >= contact_force``
                            for ``contact_time`` s (the surface stops the tool, the pose task
                            presses); no contact ``timeout`` s after the move: the hole is
                            skipped (``missed``), retract
    2 ramp     ``ramp``     contact and force task on, pose task off; normal force reference
                            ``f_slip -> F*`` (minimum-jerk profile)
    3 hold     ``hold``     ``F*`` (the drilling thrust)
    4 release  ``release``  ``F* -> f_slip``, then the contact and the force task go off
    5 retract  ``retract``  pose task on, from where the tool is to ``s_k``; then the next hole
    6 done     --           holds the last standoff
    ====== ========== ====================================================================

    The normal force reference ``f_n`` is kept within the slip/clamp bound of thesis Ch. 6.2,
    ``f_slip <= f_n <= f_clamp`` (its QP row is the contact's ``min_normal_force`` /
    ``max_normal_force``); ``force_reference = f_n n`` (the force on the robot, world axes).

    **Loss of contact** (a hole breaking through, not announced): in ramp and hold, once the
    measured normal force ``n . F`` has reached ``f_slip`` ("armed"), ``n . F < loss_force`` for
    ``loss_time`` s switches to retract at once (from the measured tool point), counts a
    breakthrough and moves on to the next hole (the thesis's "skip the failed hole, log it and
    continue", §6.4).

    **Breakthrough event** (for a simulation): ``breakthrough`` turns true ``break_delay`` s after
    hole ``break_hole``'s phase ``break_phase`` (``"ramp"`` or ``"hold"``) began, while that phase
    lasts: the material giving way after the drill has pushed for a while, an event of the
    sequence rather than a wall-clock time (the phases' start times depend on when each contact is
    made). A simulator removes the hole's patch of surface on it (``MujocoDevice``'s
    ``remove_on``). The loss detection above does not read it: it sees the force vanish.

    Parameters: ``holes`` (n x 3, world, points on the surface), ``normal`` (3, world, from the
    surface towards the robot: the direction of the force on the robot), ``standoff``, ``depth``
    (m), ``force`` (``F*``), ``slip_force``, ``clamp_force``, ``contact_force``, ``loss_force``
    (N), the six durations, ``contact_time``, ``timeout`` and ``loss_time`` (s),
    ``approach_weight`` (the pose task's weight outside contact), ``break_hole`` (-1: none),
    ``break_phase``, ``break_delay``, ``dt``.
    Inputs: ``tool_position`` (3, measured tool point, world), ``measured_force`` (3, force on the
    robot, world).
    States: ``phase``, ``hole`` (index into ``holes``; ``n`` when done), ``phase_tick`` (tick at which
    the phase began), ``origin`` (3, start point of the current move), ``armed``, ``loss_timer``,
    ``breakthroughs`` (count), ``breakthrough_hole`` (the last one's index, -1: none), ``missed``
    (holes skipped).
    Outputs: ``position`` (3), ``velocity``, ``acceleration`` (6, ``[linear, 0]``: a FramePose's
    reference), ``pose_weight``, ``normal_force_reference`` (``f_n``, 0 outside contact),
    ``force_reference`` (3), ``contact_active`` (bool), ``breakthrough`` (bool).
    """

    has_state = True
    holes = dg.Param(kind="vector", doc="hole points on the surface, n x 3 (world, m)")
    normal = dg.Param([-1.0, 0.0, 0.0], kind="vector", doc="surface normal towards the robot (world)")
    standoff = dg.Param(0.03, kind="float", minimum=0.0, doc="distance of the standoff point from the surface (m)")
    depth = dg.Param(0.005, kind="float", minimum=0.0, doc="approach target beyond the surface (m)")
    force = dg.Param(20.0, kind="float", minimum=0.0, doc="F*: normal force held while drilling (N)")
    slip_force = dg.Param(5.0, kind="float", minimum=0.0, doc="f_slip: smallest normal force in contact (N)")
    clamp_force = dg.Param(40.0, kind="float", minimum=0.0, doc="f_clamp: largest normal force (N)")
    contact_force = dg.Param(3.0, kind="float", minimum=0.0, doc="normal force that ends the approach (N)")
    contact_time = dg.Param(0.005, kind="float", minimum=0.0, doc="dwell before the contact is made (s)")
    timeout = dg.Param(1.0, kind="float", minimum=0.0, doc="time after the approach's end without contact before "
                       "the hole is skipped (s)")
    loss_force = dg.Param(2.0, kind="float", minimum=0.0, doc="normal force under which the contact is lost (N)")
    loss_time = dg.Param(0.005, kind="float", minimum=0.0, doc="dwell before a loss is declared (s)")
    move = dg.Param(0.5, kind="float", minimum=1e-3, doc="duration of the move between holes (s)")
    approach = dg.Param(0.3, kind="float", minimum=1e-3, doc="duration of the approach (s)")
    ramp = dg.Param(0.3, kind="float", minimum=1e-3, doc="duration of the force ramp (s)")
    hold = dg.Param(0.5, kind="float", minimum=1e-3, doc="duration of the force hold (s)")
    release = dg.Param(0.2, kind="float", minimum=1e-3, doc="duration of the force release (s)")
    retract = dg.Param(0.3, kind="float", minimum=1e-3, doc="duration of the retract (s)")
    approach_weight = dg.Param(1.0, kind="float", minimum=0.0, doc="pose task weight outside contact")
    break_hole = dg.Param(-1, kind="int", minimum=-1, doc="hole whose surface gives way (breakthrough output; "
                          "-1: none)")
    break_phase = dg.Param("hold", kind="str", choices=("ramp", "hold"), doc="phase of break_hole in which it "
                           "gives way")
    break_delay = dg.Param(0.25, kind="float", minimum=0.0, doc="time after break_phase began at which it gives "
                           "way (s)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, holes: ArrayLike, normal: ArrayLike = (-1.0, 0.0, 0.0), standoff: float = 0.03,
            depth: float = 0.005, force: float = 20.0, slip_force: float = 5.0, clamp_force: float = 40.0,
            contact_force: float = 3.0, contact_time: float = 0.005, timeout: float = 1.0, loss_force: float = 2.0,
            loss_time: float = 0.005, move: float = 0.5, approach: float = 0.3, ramp: float = 0.3, hold: float = 0.5,
            release: float = 0.2, retract: float = 0.3, approach_weight: float = 1.0, break_hole: int = -1,
            break_phase: Literal["ramp", "hold"] = "hold", break_delay: float = 0.25, dt: float | None = None,
        ) -> None: ...

    tool_position = dg.Input(shape=(3,), doc="measured tool point (world, m)")
    measured_force = dg.Input(shape=(3,), doc="measured force on the robot (world, N)")
    phase = dg.State(shape=(), dtype="int", initial=MOVE, doc="0 move, 1 approach, 2 ramp, 3 hold, 4 release, "
                     "5 retract, 6 done")
    hole = dg.State(shape=(), dtype="int", initial=0, doc="index of the current hole")
    phase_tick = dg.State(shape=(), dtype="int", initial=0, doc="tick at which the phase began")
    origin = dg.State(shape=(3,), doc="start point of the current move (world)")
    armed = dg.State(shape=(), dtype="bool", initial=False, doc="the normal force has reached f_slip in this contact")
    loss_timer = dg.State(shape=(), initial=0.0, doc="time the contact (approach) or loss (ramp, hold) "
                          "condition has held (s)")
    breakthroughs = dg.State(shape=(), dtype="int", initial=0, doc="losses of contact so far")
    breakthrough_hole = dg.State(shape=(), dtype="int", initial=-1, doc="hole of the last loss (-1: none)")
    missed = dg.State(shape=(), dtype="int", initial=0, doc="holes skipped: no contact within the timeout")

    def configure(self) -> None:
        """Holes as rows, unit normal, consistent bounds."""
        holes = np.asarray(self.holes, dtype=float)
        if holes.size == 0 or holes.size % 3:
            raise dg.ParamError(f"{self.name}: holes must be n x 3 points, got shape {holes.shape}", entity=self.name)
        self._holes = holes.reshape(-1, 3)
        normal = np.asarray(self.normal, dtype=float)
        if normal.shape != (3,) or not np.linalg.norm(normal) > 1e-9:
            raise dg.ParamError(f"{self.name}: normal must be a non-zero 3-vector", entity=self.name)
        self._normal = normal / np.linalg.norm(normal)
        if not self.slip_force <= self.force <= self.clamp_force:
            raise dg.ParamError(f"{self.name}: need slip_force <= force <= clamp_force, got {self.slip_force}, "
                                f"{self.force}, {self.clamp_force}", entity=self.name)
        if self.loss_force >= self.slip_force or self.contact_force > self.slip_force:
            raise dg.ParamError(f"{self.name}: need loss_force < slip_force and contact_force <= slip_force",
                                entity=self.name)
        self._durations = (self.move, self.approach, self.ramp, self.hold, self.release, self.retract)
        self._break_phase = RAMP if self.break_phase == "ramp" else HOLD
        if self.break_hole >= len(self._holes):
            raise dg.ParamError(f"{self.name}: break_hole {self.break_hole} is not a hole (n = {len(self._holes)})",
                                entity=self.name)

    def reset(self) -> None:
        """Back to the first move (its origin latched from ``tool_position`` at the first tick)."""
        super().reset()
        self.origin.set(np.zeros(3), 0)
        self._latched = False

    # -- the schedule -------------------------------------------------------------------------
    @property
    def n_holes(self) -> int:
        """Number of holes."""
        return len(self._holes)

    def standoff_point(self, hole: int) -> np.ndarray:
        """``s_k = h_k + standoff n``."""
        return self._holes[hole] + self.standoff * self._normal

    def _target(self, phase: int, hole: int) -> np.ndarray:
        """End point of a move phase (pose task), or the point held in contact and when done."""
        if phase == DONE:
            return self.standoff_point(self.n_holes - 1)
        if phase in (MOVE, RETRACT):
            return self.standoff_point(hole)
        return self._holes[hole] - self.depth * self._normal

    def _elapsed(self, t: int) -> float:
        return (t - int(self.phase_tick(t))) * self.dt

    def _origin(self, t: int) -> np.ndarray:
        return self.origin(t) if self._latched or t > 0 else self.tool_position(t)

    # -- the tick transition ------------------------------------------------------------------
    def prepare_state(self, t: int) -> None:
        """Advance the phase: at the end of its duration, or on a loss of contact (ramp, hold)."""
        phase, hole = int(self.phase(t)), int(self.hole(t))
        phase_tick, origin = int(self.phase_tick(t)), self._origin(t)
        armed, timer = bool(self.armed(t)), float(self.loss_timer(t))
        count, broken, missed = int(self.breakthroughs(t)), int(self.breakthrough_hole(t)), int(self.missed(t))
        self._latched_next = True
        next_phase = phase
        elapsed_next = (t + 1 - phase_tick) * self.dt + 1e-6 * self.dt  # slack: n ticks of dt may sum under n dt
        normal_force = float(self._normal @ self.measured_force(t)) if phase in (APPROACH, RAMP, HOLD) else 0.0
        if phase == APPROACH:  # ends on contact (after the move), or skips the hole after the timeout
            timer = timer + self.dt if normal_force >= self.contact_force else 0.0
            if elapsed_next >= self.approach and timer >= self.contact_time:
                next_phase = RAMP
            elif elapsed_next >= self.approach + self.timeout:
                next_phase, missed = RETRACT, missed + 1
        elif phase in (RAMP, HOLD):
            armed = armed or normal_force >= self.slip_force
            timer = timer + self.dt if armed and normal_force < self.loss_force else 0.0
            if armed and timer >= self.loss_time - 1e-6 * self.dt:
                next_phase, count, broken = RETRACT, count + 1, hole
        if next_phase == phase and phase not in (APPROACH, DONE) and elapsed_next >= self._durations[phase]:
            next_phase = phase + 1
        if next_phase != phase:
            if phase == RETRACT:  # the next hole, or done
                hole += 1
                next_phase = MOVE if hole < self.n_holes else DONE
            if next_phase == APPROACH:
                origin = self.standoff_point(hole)
            elif next_phase == RETRACT:  # from where the tool is (after a loss, wherever it went)
                origin = np.array(self.tool_position(t), dtype=float)
            elif next_phase == MOVE:
                origin = self.standoff_point(hole - 1)
            phase_tick, armed, timer = t + 1, False, 0.0
        self.phase.stage(next_phase)
        self.hole.stage(hole)
        self.phase_tick.stage(phase_tick)
        self.origin.stage(np.asarray(origin, dtype=float))
        self.armed.stage(armed)
        self.loss_timer.stage(timer)
        self.breakthroughs.stage(count)
        self.breakthrough_hole.stage(broken)
        self.missed.stage(missed)

    def commit_state(self, t_next: int) -> None:
        """Publish the phase and its data."""
        for state in (self.phase, self.hole, self.phase_tick, self.origin, self.armed, self.loss_timer,
                      self.breakthroughs, self.breakthrough_hole, self.missed):
            state.commit(t_next)
        self._latched = self._latched_next

    # -- outputs ----------------------------------------------------------------------------
    def _move(self, t: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, velocity, acceleration of the pose reference at ``t``: minimum jerk from
        ``origin`` to the phase's target in move, approach and retract; the target held otherwise."""
        phase, hole = int(self.phase(t)), min(int(self.hole(t)), self.n_holes - 1)
        target = self._target(phase, hole)
        if phase not in (MOVE, APPROACH, RETRACT):
            return target, np.zeros(3), np.zeros(3)
        duration = self._durations[phase]
        p, dp, ddp = quintic(self._elapsed(t) / duration)
        origin = self._origin(t)
        delta = target - origin
        return origin + p * delta, dp / duration * delta, ddp / duration**2 * delta

    @dg.output(shape=(3,), depends=("t", "phase", "hole", "phase_tick", "origin", "tool_position"),
               on_demand=("tool_position",))
    def position(self, t: int) -> np.ndarray:
        """``origin + (target - origin) p(s)``, ``s = elapsed / duration`` (the target outside moves)."""
        return self._move(t)[0]

    @dg.output(shape=(6,), depends=("t", "phase", "hole", "phase_tick", "origin", "tool_position"),
               on_demand=("tool_position",))
    def velocity(self, t: int) -> np.ndarray:
        """``[(target - origin) p'(s) / T, 0]``."""
        return np.concatenate([self._move(t)[1], np.zeros(3)])

    @dg.output(shape=(6,), depends=("t", "phase", "hole", "phase_tick", "origin", "tool_position"),
               on_demand=("tool_position",))
    def acceleration(self, t: int) -> np.ndarray:
        """``[(target - origin) p''(s) / T^2, 0]``."""
        return np.concatenate([self._move(t)[2], np.zeros(3)])

    @dg.output(shape=(), depends=("phase",))
    def pose_weight(self, t: int) -> float:
        """``approach_weight`` outside the contact phases, 0 in them."""
        return 0.0 if int(self.phase(t)) in CONTACT_PHASES else float(self.approach_weight)

    @dg.output(shape=(), dtype="bool", depends=("phase",))
    def contact_active(self, t: int) -> bool:
        """True in ramp, hold and release."""
        return int(self.phase(t)) in CONTACT_PHASES

    @dg.output(shape=(), depends=("t", "phase", "phase_tick"))
    def normal_force_reference(self, t: int) -> float:
        """``f_n``: ramp ``f_slip + (F* - f_slip) p(s)``, hold ``F*``, release ``F* - (F* - f_slip) p(s)``,
        clipped to ``[f_slip, f_clamp]``; 0 outside contact."""
        phase = int(self.phase(t))
        if phase not in CONTACT_PHASES:
            return 0.0
        span = self.force - self.slip_force
        if phase == RAMP:
            value = self.slip_force + span * quintic(self._elapsed(t) / self.ramp)[0]
        elif phase == HOLD:
            value = self.force
        else:
            value = self.force - span * quintic(self._elapsed(t) / self.release)[0]
        return float(min(max(value, self.slip_force), self.clamp_force))

    @dg.output(shape=(), dtype="bool", depends=("t", "phase", "hole", "phase_tick"))
    def breakthrough(self, t: int) -> bool:
        """True in hole ``break_hole``'s phase ``break_phase`` from ``break_delay`` s after it began."""
        return (int(self.hole(t)) == self.break_hole and int(self.phase(t)) == self._break_phase
                and self._elapsed(t) >= self.break_delay - 1e-6 * self.dt)

    @dg.output(shape=(3,), depends=("normal_force_reference",))
    def force_reference(self, t: int) -> np.ndarray:
        """``f_n n`` (world, the force on the robot)."""
        return self.normal_force_reference(t) * self._normal

