"""ZmpPatternGenerator: the CoM, ZMP and DCM references of a footstep plan, re-planned by a LIPM MPC."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.control.status import Status
from dgraph.entities.references.minimum_jerk import minimum_jerk
from dgraph.entities.stabilizers.lipm import GRAVITY
from dgraph.entities.walking.footsteps import FootstepPlan
from dgraph.entities.walking.lipm_mpc import MAX_EDGES, LipmMpc, LipmTrajectory, MpcResult, pad_polygon
from dgraph.signals.value_types import value_type

WINDOW_EPSILON = 1e-9
"""Re-plan windows are counted with this slack, so a tick on a multiple of the period up to
rounding opens its window (tick 145 at 1 ms: 0.145 / 0.005 = 28.999999999999996)."""


@value_type
class ComPlan:
    """The plan a :class:`ZmpPatternGenerator` follows at a tick (read-only for readers).

    ``trajectory`` starts at tick ``start_tick`` (the tick of the re-plan that made it);
    ``replan_tick`` is the latest re-plan, whose ``status``, ``iterations`` and ``solve_time``
    are those given (a failed re-plan keeps the previous trajectory and its start).
    """

    __slots__ = ("iterations", "replan_tick", "solve_time", "start_tick", "status", "trajectory")

    def __init__(self, trajectory: LipmTrajectory, start_tick: int, replan_tick: int, status: Status,
                 iterations: int, solve_time: float):
        self.trajectory, self.start_tick, self.replan_tick = trajectory, start_tick, replan_tick
        self.status, self.iterations, self.solve_time = status, iterations, solve_time


class SupportPolygons:
    """The support polygon of every phase of one plan, shrunk by ``margin`` and padded to
    ``MAX_EDGES`` rows, and the phase of any plan time (as ``FootstepPlan.phase_at``)."""

    def __init__(self, plan: FootstepPlan, margin: float):
        self.plan = plan
        padded = [pad_polygon(*plan.support_polygon(0.5 * (phase.start + phase.end), margin))
                  for phase in plan.phases]
        self.edges = np.stack([edges for edges, _ in padded])
        self.offsets = np.stack([offsets for _, offsets in padded])
        self.starts = np.array([phase.start for phase in plan.phases])

    def at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The padded polygons ``(edges (n, M, 2), offsets (n, M))`` at plan ``times`` (n,): those
        of the last phase starting at or before each time (the first before 0)."""
        phases = np.maximum(np.searchsorted(self.starts, times, side="right") - 1, 0)
        return self.edges[phases], self.offsets[phases]


@dg.register
class ZmpPatternGenerator(dg.Entity):
    """The walking pattern generator: the LIPM MPC of :mod:`~dgraph.entities.walking.lipm_mpc`
    re-planned every ``period`` seconds along a footstep plan, its trajectory sampled every tick.

    Plan time: ``tau = t dt - plan.start`` (the footstep planner's ``start``). At the first tick, then at every
    tick where ``tau`` crosses a multiple of ``period`` (thesis: the WPG re-plans its whole
    horizon every 5 ms, L1552-1554), the MPC plans ``N = horizon`` samples of ``T = sampling``
    from the state ``x0 = [c0, c_dot0, c_ddot0]`` (per horizontal axis)::

        c0     = f c_meas     + (1 - f) c_plan(tau)        f = feedback in [0, 1]
        c_dot0 = f c_dot_meas + (1 - f) c_dot_plan(tau)
        c_ddot0 = c_ddot_plan(tau)

    (``c_plan`` the previous plan at this tick; at the first tick there is none and
    ``x0 = [c_meas, c_dot_meas, 0]``). ``feedback = 1`` re-plans from the estimated CoM state, as the
    issue asks (the MPC then closes the loop on the CoM); 0 runs the plan open loop (a
    stabiliser must then track it). The ZMP reference of sample ``k`` is
    ``plan.zmp_reference(tau + k T)``, its polygon ``plan.support_polygon(tau + k T, margin)``
    (the polygon of its phase; between samples the ZMP is not constrained, as in every
    sampled MPC), the CoM velocity reference 0: the plan carries none, and the term
    ``alpha ||c_dot||^2`` only damps (alpha = 5 against beta = 1e3; measured on the 20 cm and
    60 cm straight walks re-planned every 5 ms, the RMS ZMP error is 13.3 and 39.7 mm along x
    with it and with a velocity reference averaged over a stride alike). Before the plan's start and
    after the plan's end the references are constant and the polygons the double support's: the
    MPC plans standing.

    Between re-plans every output is the last plan evaluated exactly (constant jerk
    ``u`` over each sample: ``c`` cubic in time), with ``h = com_height``, ``omega = sqrt(g/h)``,
    ``h`` the CoM height above the support::

        com_position = [c, g + h]        com_velocity = [c_dot, g_dot]  com_acceleration = [c_ddot, g_ddot]
        zmp = [c - c_ddot / omega^2, z_p]                 (Eq. 2.22)  zmp_velocity = [c_dot - u / omega^2, z_p_dot]
        dcm = [c + c_dot / omega, g + h]                  (Eq. 2.27)  dcm_velocity = [c_dot + c_ddot / omega, g_dot]

    with ``g(tau)`` the plan's support height (``FootstepPlan.support_height``: a minimum-jerk
    profile through the stance soles' heights, from the middle of one single support to the
    middle of the next, so the CoM climbs stairs and platforms with the feet; constant on flat
    ground) and ``z_p(tau)`` the height of the plane the ZMP is constrained in
    (``FootstepPlan.zmp_height``: the stance sole's in single support, linear between the two
    soles' in a double support between two heights; the polygons are the soles projected onto
    it, see ``FootstepPlan``). The MPC keeps ``omega`` of the constant ``h``: the vertical CoM
    acceleration ``g_ddot`` it neglects is below 0.16 m/s^2 (1.6 % of g) on the 10 cm stairs.

    A CoM height ``h`` other than the estimate's ``h0`` at the first re-plan (tick ``t0``) is
    reached in ``D = height_transition`` s, by minimum jerk ``s(x) = 10 x^3 - 15 x^4 + 6 x^5``,
    ``x = (t - t0) dt / D`` (``D = 0``: at once)::

        com_position_z = dcm_z = g + h + (h0 - h) (1 - s(x))
        com_velocity_z = dcm_velocity_z = -(h0 - h) s'(x) / D      com_acceleration_z = -(h0 - h) s''(x) / D^2

    while the MPC plans with ``h`` (``omega``) throughout: the transition is for the standing
    start, within the plan's initial double support. A walk that strides further than the legs
    reach from the robot's standing height needs it (graphs/talos_walk_60cm.yaml: the 60 cm walk
    is out of TALOS's reach at half-sitting's 0.877 m).

    A failed re-plan (infeasible polygons, iteration limit, non-finite state) raises nothing: the
    tick is reported degraded and the previous plan is kept, evaluated at the time elapsed since
    it started; ``status`` says why. If the very first re-plan fails, the plan is the state
    ``x0`` with zero jerk.

    Parameters: ``period`` (s between re-plans, default 0.005), ``sampling`` (T, s, default
    0.1), ``horizon`` (N, default 16), ``alpha``, ``beta``, ``gamma`` (weights of the CoM
    velocity, ZMP and jerk terms: 5, 1e3, 5e-4, jrl-walkgen's), ``margin`` (m the polygons
    shrink by, default 0.02; placo uses 0.025), ``com_height`` (h, m above the ground; None: the
    estimated CoM's at the first tick), ``height_transition`` (D, s, default 0), ``feedback`` (f,
    default 1), ``dt`` (default: the graph's).
    Inputs: ``plan`` (FootstepPlan), ``estimated_com_position``, ``estimated_com_velocity`` (3).
    Outputs: ``com_plan`` (the :class:`ComPlan` followed), ``com_position``, ``com_velocity``,
    ``com_acceleration``, ``zmp``, ``zmp_velocity``, ``dcm``, ``dcm_velocity`` (3 each, world
    axes), ``zmp_plane_height`` (``z_p``), ``status``, ``iterations``, ``solve_time`` (of the latest re-plan).
    """

    has_state = True
    period = dg.Param(0.005, kind="float", minimum=1e-6, maximum=1e6, doc="s between re-plans (thesis: 5 ms)")
    sampling = dg.Param(0.1, kind="float", minimum=1e-3, maximum=10.0, doc="MPC sample T in s")
    horizon = dg.Param(16, kind="int", minimum=1, maximum=1000, doc="MPC samples N")
    alpha = dg.Param(5.0, kind="float", minimum=0.0, doc="weight of the CoM velocity term")
    beta = dg.Param(1e3, kind="float", minimum=0.0, doc="weight of the ZMP reference term")
    gamma = dg.Param(5e-4, kind="float", minimum=1e-12, doc="weight of the jerk term (> 0)")
    margin = dg.Param(0.02, kind="float", minimum=0.0, maximum=1.0, doc="m the support polygons shrink by")
    com_height = dg.Param(None, kind="float", minimum=1e-3, maximum=100.0,
                          doc="CoM height above the ground in m (None: the estimate's at the first tick)")
    height_transition = dg.Param(0.0, kind="float", minimum=0.0, maximum=1e3,
                                 doc="s the CoM takes from the estimate's height at the first tick to com_height "
                                     "(minimum jerk; 0: at once)")
    feedback = dg.Param(1.0, kind="float", minimum=0.0, maximum=1.0,
                        doc="share of the estimated CoM state in the re-plan's initial state (0: open loop)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, period: float = 0.005, sampling: float = 0.1, horizon: int = 16, alpha: float = 5.0,
            beta: float = 1000.0, gamma: float = 0.0005, margin: float = 0.02, com_height: float | None = None,
            height_transition: float = 0.0, feedback: float = 1.0, dt: float | None = None,
        ) -> None: ...

    plan = dg.Input(dtype=FootstepPlan, doc="the footstep plan")
    estimated_com_position = dg.Input(shape=(3,), doc="estimated CoM position (world)")
    estimated_com_velocity = dg.Input(shape=(3,), doc="estimated CoM velocity (world)")

    def reset(self) -> None:
        """No plan yet: the next tick re-plans, with the CoM height and polygons found then."""
        self._committed: ComPlan | None = None
        self._staged: ComPlan | None = None
        self._mpc: LipmMpc | None = None
        self._polygons: SupportPolygons | None = None
        self._references_key: tuple[int, ComPlan] | None = None
        self._references = np.zeros((7, 3))
        self._height = 0.0
        self._height_change: tuple[int, float] = (0, 0.0)

    # -- re-planning ----------------------------------------------------------------------------
    def _window(self, plan: FootstepPlan, t: int) -> int:
        """The index of the re-plan window of tick ``t`` (in ``plan``'s time)."""
        return math.floor(plan.time(t * self.dt) / self.period + WINDOW_EPSILON)

    @dg.output(dtype=ComPlan, depends=("t", "plan", "estimated_com_position", "estimated_com_velocity"),
               on_demand=True)
    def com_plan(self, t: int) -> ComPlan:
        """The plan followed at ``t``: a new one at a re-plan tick, else the committed one."""
        committed = self._committed
        plan = self.plan(t)
        if committed is not None and self._window(plan, t) == self._window(plan, committed.replan_tick):
            return committed
        return self._replan(t, committed)

    def _replan(self, t: int, previous: ComPlan | None) -> ComPlan:
        """Solve the MPC at ``t`` from the state of the module docstring; keep ``previous`` on failure."""
        plan = self.plan(t)
        polygons = self._support_polygons(plan)
        measured = np.array([self.estimated_com_position(t), self.estimated_com_velocity(t)])
        mpc = self._solver(plan, measured, t)
        planned = None if previous is None else self._planned_state(previous, t)
        initial = self._initial_state(measured, planned)
        times = plan.time(t * self.dt) + self.sampling * np.arange(1, self.horizon + 1)
        shift = 0 if previous is None else round((t - previous.start_tick) * self.dt / self.sampling)
        result = mpc.solve(initial, plan.zmp_reference(times), np.zeros((self.horizon, 2)), polygons.at(times),
                           tick=t, shift=shift)
        return self._adopt(t, result, previous, initial)

    def _adopt(self, t: int, result: MpcResult, previous: ComPlan | None, initial: np.ndarray) -> ComPlan:
        """The new plan, or on failure the previous one (reported; the state ``x0`` with zero
        jerk if there is none)."""
        if result.trajectory is not None:
            return ComPlan(result.trajectory, t, t, result.status, result.iterations, result.solve_time)
        kept = "kept the previous plan" if previous is not None else "planned the initial state with zero jerk"
        self.report_fault(t, "com_plan", f"re-plan failed: {Status(result.status).name}", kept)
        if previous is None:
            trajectory = LipmTrajectory.from_jerks(initial, np.zeros((self.horizon, 2)), self.sampling,
                                                   self._mpc.omega)
            return ComPlan(trajectory, t, t, result.status, result.iterations, result.solve_time)
        return ComPlan(previous.trajectory, previous.start_tick, t, result.status, result.iterations,
                       result.solve_time)

    def _planned_state(self, previous: ComPlan, t: int) -> np.ndarray:
        """``[c, c_dot, c_ddot]`` (3, 2) of ``previous`` at tick ``t``."""
        return previous.trajectory.sample((t - previous.start_tick) * self.dt)[:3]

    def _initial_state(self, measured: np.ndarray, planned: np.ndarray | None) -> np.ndarray:
        """``x0`` (3, 2): the blend of the measured and planned position and velocity, the planned
        acceleration (0 without a plan)."""
        initial = np.zeros((3, 2))
        initial[:2] = measured[:, :2]
        if planned is not None:
            feedback = self.feedback
            initial[:2] = feedback * initial[:2] + (1.0 - feedback) * planned[:2]
            initial[2] = planned[2]
        return initial

    def _support_polygons(self, plan: FootstepPlan) -> SupportPolygons:
        """The polygons of ``plan`` (computed when the plan changes); a ``ParamError`` if the
        margin leaves no polygon."""
        if self._polygons is None or self._polygons.plan is not plan:
            try:
                self._polygons = SupportPolygons(plan, self.margin)
            except ValueError as exc:
                raise dg.ParamError(f"{self.name} ({self.type_name}): parameter 'margin': {exc}",
                                    entity=self.name) from None
        return self._polygons

    def _solver(self, plan: FootstepPlan, measured: np.ndarray, t: int) -> LipmMpc:
        """The MPC, made at the first re-plan ``t`` (its CoM height: the parameter, else the
        estimate's height above the ground then, whose difference to it the transition removes)."""
        if self._mpc is None:
            ground = plan.ground_height()
            height = self.com_height if self.com_height is not None else measured[0, 2] - ground
            if not height > 0:
                raise dg.ParamError(f"{self.name} ({self.type_name}): the CoM height above the ground must be > 0, "
                                    f"got {height}",
                                    entity=self.name)
            self._mpc = LipmMpc(height, sampling=self.sampling, horizon=self.horizon, alpha=self.alpha,
                                beta=self.beta, gamma=self.gamma, max_edges=MAX_EDGES, gravity=GRAVITY)
            self._reference_maps(self._mpc.omega, height)
            self._height_change = (t, measured[0, 2] - ground - height)
        return self._mpc

    def _reference_maps(self, omega: float, height: float) -> None:
        """The horizontal references as ``horizontal @ [c, c_dot, c_ddot, u]``: the rows of
        :meth:`_sample` (the equations of the class docstring); the CoM height ``h``."""
        inverse, inverse_square = 1.0 / omega, 1.0 / omega**2
        self._horizontal = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0],
                                     [1.0, 0.0, -inverse_square, 0.0], [0.0, 1.0, 0.0, -inverse_square],
                                     [1.0, inverse, 0.0, 0.0], [0.0, 1.0, inverse, 0.0]])
        self._height = height

    # -- tick transition ------------------------------------------------------------------------
    def prepare_state(self, t: int) -> None:
        """Make (or keep) the plan of tick ``t``, whoever reads the outputs."""
        self._staged = self.com_plan(t)

    def commit_state(self, t_next: int) -> None:
        """The plan of the tick just done is the one later ticks start from."""
        self._committed = self._staged

    # -- references -----------------------------------------------------------------------------
    def _sample(self, t: int) -> np.ndarray:
        """The seven references of tick ``t`` (rows: CoM position, velocity, acceleration, ZMP, ZMP
        velocity, DCM, DCM velocity), computed once per tick and plan."""
        com_plan = self.com_plan(t)
        key = self._references_key
        if key is not None and key[0] == t and key[1] is com_plan:
            return self._references
        references = np.empty((7, 3))
        references[:, 2] = self._vertical(t)
        references[:, :2] = self._horizontal @ com_plan.trajectory.sample((t - com_plan.start_tick) * self.dt)
        self._references_key, self._references = (t, com_plan), references
        return references

    def _vertical(self, t: int) -> list[float]:
        """The seven vertical references of tick ``t`` (the class docstring's z components)."""
        plan = self.plan(t)
        time = plan.time(t * self.dt)
        ground, ground_rate, ground_acceleration = plan.support_height(time)
        zmp_height, zmp_rate = plan.zmp_height_at(time)
        com = ground + self._height
        vertical = [com, ground_rate, ground_acceleration, zmp_height, zmp_rate, com, ground_rate]
        self._add_height_transition(t, vertical)
        return vertical

    def _add_height_transition(self, t: int, vertical: list[float]) -> None:
        """Add to the seven vertical references what remains of the height transition at ``t``
        (the class docstring's ``(h0 - h) (1 - s(x))`` and its derivatives)."""
        first_tick, change = self._height_change
        duration = self.height_transition
        elapsed = (t - first_tick) * self.dt
        if change == 0.0 or elapsed >= duration:
            return
        s, ds, dds = minimum_jerk(max(elapsed, 0.0) / duration)
        for row in (0, 5):
            vertical[row] += change * (1.0 - s)
        for row in (1, 6):
            vertical[row] -= change * ds / duration
        vertical[2] -= change * dds / duration**2

    @dg.output(shape=(3,), depends=("t", "com_plan"), labels=("x", "y", "z"))
    def com_position(self, t: int) -> np.ndarray:
        """Planned CoM ``[c, g + h]`` (z in the height transition: the class docstring)."""
        return self._sample(t)[0]

    @dg.output(shape=(3,), depends=("t", "com_plan"), labels=("x", "y", "z"))
    def com_velocity(self, t: int) -> np.ndarray:
        """Planned CoM velocity ``[c_dot, g_dot]`` (z in the height transition: the class docstring)."""
        return self._sample(t)[1]

    @dg.output(shape=(3,), depends=("t", "com_plan"), labels=("x", "y", "z"))
    def com_acceleration(self, t: int) -> np.ndarray:
        """Planned CoM acceleration ``[c_ddot, g_ddot]`` (z: as ``com_velocity``)."""
        return self._sample(t)[2]

    @dg.output(shape=(3,), depends=("t", "com_plan"), labels=("x", "y", "z"))
    def zmp(self, t: int) -> np.ndarray:
        """Planned ZMP ``[c - c_ddot / omega^2, z_p]`` (Eq. 2.22; ``z_p`` the plane it is in)."""
        return self._sample(t)[3]

    @dg.output(shape=(), depends=("t", "com_plan"))
    def zmp_plane_height(self, t: int) -> float:
        """``z_p``: the height of the plane the planned ZMP is in (m; for a ZMP estimator's plane)."""
        return float(self._sample(t)[3, 2])

    @dg.output(shape=(3,), depends=("t", "com_plan"), labels=("x", "y", "z"))
    def zmp_velocity(self, t: int) -> np.ndarray:
        """Its time derivative ``[c_dot - u / omega^2, z_p_dot]``."""
        return self._sample(t)[4]

    @dg.output(shape=(3,), depends=("t", "com_plan"), labels=("x", "y", "z"))
    def dcm(self, t: int) -> np.ndarray:
        """Planned DCM ``[c + c_dot / omega, g + h]`` (Eq. 2.27; z: the CoM's)."""
        return self._sample(t)[5]

    @dg.output(shape=(3,), depends=("t", "com_plan"), labels=("x", "y", "z"))
    def dcm_velocity(self, t: int) -> np.ndarray:
        """Its time derivative ``[c_dot + c_ddot / omega, g_dot]`` (z: the CoM's)."""
        return self._sample(t)[6]

    @dg.output(shape=(), dtype="int", depends=("com_plan",))
    def status(self, t: int) -> int:
        """Status of the latest re-plan (0 solved; see :class:`~dgraph.control.status.Status`)."""
        return int(self.com_plan(t).status)

    @dg.output(shape=(), dtype="int", depends=("com_plan",))
    def iterations(self, t: int) -> int:
        """ProxQP iterations of the latest re-plan."""
        return self.com_plan(t).iterations

    @dg.output(shape=(), depends=("com_plan",))
    def solve_time(self, t: int) -> float:
        """Wall time of the latest re-plan's assembly and solve (s)."""
        return self.com_plan(t).solve_time

