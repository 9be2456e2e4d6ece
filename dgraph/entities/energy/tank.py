"""EnergyTank: the global energy tank that makes an inverse-dynamics QP passive (thesis Ch. 5)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

import dgraph as dg
from dgraph.control.contact import ContactConstraint
from dgraph.control.equation import TaskEquation
from dgraph.control.passivity import Passivity
from dgraph.control.solutions import QPSolution
from dgraph.entities.energy.power import (
    TaskBlock,
    stack,
    stiffness,
    task_power,
    task_space_inertia,
    uncontrollable_power,
)
from dgraph.entities.energy.valves import TankLimits, Valves, overflow_valve, valves
from dgraph.entities.named_inputs import declare_named_inputs
from dgraph.entities.robot.robot_state import RobotState, unactuated_dofs
from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)
class EnergyBudget:
    """The tank's budget for one tick, stage 1 of the passive controller (thesis §5.3.3, step
    (1)): what the tasks store and draw, the valves, and the bound the QP keeps."""

    storage: float              # S, sum over the tasks
    storage_rate: float         # S_dot
    controllable_power: float   # B_sigma, tasks and force tasks
    uncontrollable_power: float  # B_phi, gravity, Coriolis and contact forces
    valves: Valves
    power_bound: float          # H_dot = beta gamma S_dot + E_dot
    stiffness: dict[Any, np.ndarray] = field(default_factory=dict)  # P = Lambda K_P per task (or stack)

    @property
    def scale(self) -> float:
        """``beta gamma``, the scale of every task vector (Eq. 5.24)."""
        return self.valves.beta * self.valves.gamma


def task_block(equation: TaskEquation, velocity: np.ndarray) -> TaskBlock:
    """The tank's view of a task. A rate feature (angular momentum, ``k_dot = k_dot* - K (k - k*)``)
    has no position error: its error is ``E_dot`` with ``K_D = K`` and ``K_P = 0`` (so ``S = 0``)."""
    f, kp, kd = equation.feature, equation.kp, equation.kd
    weighted = equation.weight > 0.0
    if not weighted.all():  # rows the QP ignores carry no controlled energy
        rows = np.flatnonzero(weighted)
        f, kp, kd = f.select(rows), kp[rows], kd[rows]
    x_dot = f.jacobian @ velocity
    if f.is_rate:
        zeros = np.zeros_like(f.error)
        return TaskBlock(zeros, f.error, x_dot, f.reference_acceleration, f.drift, zeros, kp, f.jacobian)
    return TaskBlock(f.error, f.error_velocity, x_dot, f.reference_acceleration, f.drift, kp, kd, f.jacobian)


@dg.register
class EnergyTank(dg.Entity):
    """A global energy tank over a set of tasks (thesis Ch. 5, Eqs. 5.5-5.27), for a passive
    :class:`~dgraph.entities.solvers.InverseDynamicsSolver` (``passive: true``, Eq. 5.34).

    Stage 1, every tick, from the measured state and the tasks' equations:

    - storage of the tasks ``S = sum 1/2 E^T Lambda K_P E`` and its rate ``S_dot`` (Eq. 5.11), with
      ``Lambda = (J M^-1 J^T)^+`` per task (Eq. 5.5, ``inertia: per_task``, what the thesis
      simulated) or over the stacked tasks (Eq. 5.10, ``inertia: stacked``) and
      ``d(Lambda K_P)/dt`` by finite difference over one tick (errata E18);
    - controllable power ``B_sigma`` (Eq. 5.18), plus ``(J_F v)^T T_F F_F`` for each contact with
      a force reference (the force task, with ``F_F`` its desired wrench, errata E17);
    - uncontrollable power ``B_phi = v^T (C v + g) - sum_k (J_k v)^T T_k f_k`` (Eq. 5.19), with the
      other contacts' forces ``f_k`` of the previous tick's solution (errata E17);
    - valves ``gamma`` (power limiter, Eq. 5.21), ``beta`` (output, Eq. 5.22), ``alpha``
      (overflow, Eq. 5.23), smoothed over ``band`` joules (:mod:`~dgraph.entities.energy.valves`);
    - planned tank rate ``E_dot = (1 - alpha)(beta gamma B_sigma - B_phi)`` (Eq. 5.20) and the
      bound ``H_dot = beta gamma S_dot + E_dot`` (Eq. 5.26) for the QP row ``H_dot <= -v_j^T tau``.

    After the solve (the tick's state transition) the tank is integrated from the power the
    controller actually delivered, ``-v_j^T tau`` with the solver's ``tau`` (fallback included):
    ``E(t+1) = E(t) + dt (1 - alpha') (-v_j^T tau - beta gamma S_dot)``, where ``alpha'`` is the
    overflow valve (Eq. 5.23) of that actual flow, non-zero only while it fills the tank and
    large enough that one tick never passes ``E_max`` (so ``beta gamma S_dot + E_dot <= -v_j^T
    tau``, Eq. 5.27, with ``beta gamma`` held over the tick, and ``E <= E_max`` without a
    clamp). The energy is stored as ``E = s^2 / 2`` and nothing divides by ``s``. Below, only
    the uncontrollable power can drain the tank once ``beta = 0``: with ``clamp`` the energy is
    kept at ``E_min`` and what the clamp adds is summed in ``correction`` (it is not passive,
    so it is shown, not hidden).

    A task whose weights are all zero is out of the stack (its previous ``Lambda K_P`` is dropped;
    re-adding it starts with ``P_dot = 0``), and so are the rows of a task whose weight is 0;
    inactive contacts are ignored. With ``enabled: false`` everything is computed for the
    record, but the solver gets scale 1 and no bound (the plain QP), and the energy is integrated
    as that QP ran (``beta gamma = 1``), up to the same ``E_max`` but with no floor and no
    clamp: how far below zero it goes is what the plain controller overdrew.

    Parameters: ``tasks``, ``contacts`` (input names), ``maximum_energy`` (5 J),
    ``minimum_energy`` (0.1 J), ``initial_energy`` (3 J, the pushing scenario), ``power_low``
    (-0.5 W), ``band`` (J), ``inertia`` (``per_task`` | ``stacked``), ``enabled``, ``clamp``, ``dt``.
    Inputs: ``robot`` (RobotModel state), one per task (a Task's ``equation``), one per contact
    (a contact's ``contact``), ``solution`` (the solver's ``solution``: ``tau``, contacts and forces).
    States: ``energy`` (J), ``correction`` (J added by the clamp so far), ``previous_stiffness``
    (``Lambda K_P`` of the previous tick, per task), ``contact_frame_wrenches`` (``T_k f_k`` of
    the previous solution, contact frame, by contact name).
    Outputs: ``budget`` (:class:`EnergyBudget`, stage 1), ``passivity`` (for the solver),
    ``alpha``, ``beta``, ``gamma``, ``storage``, ``storage_rate``, ``controllable_power``, ``uncontrollable_power``,
    ``energy_rate`` (planned ``E_dot``), ``power_bound`` (``H_dot``), ``delivered_power``
    (``-v_j^T tau``, W).
    """

    has_state = True

    tasks = dg.Param((), kind="str_list", doc="task input names")
    contacts = dg.Param((), kind="str_list", doc="contact input names")
    maximum_energy = dg.Param(5.0, kind="float", minimum=0.0, doc="E_max (J)")
    minimum_energy = dg.Param(0.1, kind="float", minimum=0.0, doc="E_min (J)")
    initial_energy = dg.Param(3.0, kind="float", minimum=0.0, doc="E(0) (J)")
    power_low = dg.Param(-0.5, kind="float", maximum=0.0, doc="P_low (W, < 0): the tasks' largest draw")
    band = dg.Param(0.1, kind="float", minimum=0.0, doc="smoothing band of beta and alpha (J; 0: hard)")
    inertia = dg.Param("per_task", kind="str", choices=("per_task", "stacked"), doc="Lambda per task or stacked")
    enabled = dg.Param(True, kind="bool", doc="false: compute and record, but leave the solver plain")
    clamp = dg.Param(True, kind="bool", doc="keep E in [E_min, E_max], summing the correction")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, tasks: Sequence[str] = (), contacts: Sequence[str] = (), maximum_energy: float = 5.0,
            minimum_energy: float = 0.1, initial_energy: float = 3.0, power_low: float = -0.5, band: float = 0.1,
            inertia: Literal["per_task", "stacked"] = "per_task", enabled: bool = True, clamp: bool = True,
            dt: float | None = None,
        ) -> None: ...

    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")
    solution = dg.Input(dtype=QPSolution, doc="the solver's solution (tau, contacts, forces), read after the solve")
    energy = dg.State(shape=(), doc="tank energy E = s^2 / 2 (J)")
    correction = dg.State(shape=(), initial=0.0, doc="energy added by the clamp so far (J)")
    previous_stiffness = dg.State(dtype="object", doc="Lambda K_P of the previous tick, per task (or stack)")
    contact_frame_wrenches = dg.State(dtype="object", doc="wrenches T_k f_k of the previous solution (contact frame), "
                                                       "by contact name")

    def configure(self) -> None:
        """Check the limits and declare one input per task and contact, and ``budget``."""
        if not self.minimum_energy < self.maximum_energy:
            raise dg.ParamError(f"{self.name}: minimum_energy must be below maximum_energy", entity=self.name)
        if not self.minimum_energy <= self.initial_energy <= self.maximum_energy:
            raise dg.ParamError(f"{self.name}: initial_energy must be in [minimum_energy, maximum_energy]",
                                entity=self.name)
        if not self.power_low < 0.0:
            raise dg.ParamError(f"{self.name}: power_low must be < 0 W (0 would stop every task that draws power)",
                                entity=self.name)
        if self.band > self.maximum_energy - self.minimum_energy:
            raise dg.ParamError(f"{self.name}: band is wider than [minimum_energy, maximum_energy]", entity=self.name)
        self.limits = TankLimits(self.minimum_energy, self.maximum_energy, self.power_low, self.band)
        names = [*self.tasks, *self.contacts]
        declare_named_inputs(self, [(self.tasks, TaskEquation, "equation of task"),
                                    (self.contacts, ContactConstraint, "constraint of contact")])
        self.declare("budget", dg.Output(type(self)._budget, dtype=EnergyBudget,
                                         depends=("robot", *names, "energy", "previous_stiffness",
                                                  "contact_frame_wrenches"),
                                         doc="stage 1: storage, powers, valves, H_dot bound"))

    def reset(self) -> None:
        """Initial energy, no previous stiffness or contact wrench."""
        super().reset()
        self.energy.set(self.initial_energy, 0)
        self.previous_stiffness.set({}, 0)
        self.contact_frame_wrenches.set({}, 0)

    def setup(self) -> None:
        """Collect the task and contact inputs."""
        self._task_inputs = [getattr(self, n) for n in self.tasks]
        self._contact_inputs = [getattr(self, n) for n in self.contacts]

    # -- stage 1 ------------------------------------------------------------------------------
    def _task_equation(self, inp: dg.Input, t: int) -> TaskEquation:
        """``inp(t)``, which must carry the feature and gains a tank needs (a Task's equation)."""
        value = inp(t)
        if value.feature is None or value.kp is None or value.kd is None:
            raise dg.SpecError(f"{self.name}.{inp.name} at tick {t}: the equation carries no feature and gains "
                               "(plug a Task's equation)", entity=self.name, signal=inp.name)
        return value

    def _blocks(self, velocity: np.ndarray, t: int) -> dict[Any, TaskBlock]:
        """The active tasks' blocks, by name (or one stacked block keyed by the names)."""
        blocks = {}
        for inp in self._task_inputs:
            equation = self._task_equation(inp, t)
            if equation.weight.any():
                blocks[inp.name] = task_block(equation, velocity)
        if self.inertia == "stacked" and blocks:
            return {tuple(blocks): stack(list(blocks.values()))}
        return blocks

    def _budget(self, t: int) -> EnergyBudget:
        """Stage 1 at ``t`` (class docstring): the tasks' storage and powers, the contacts'
        powers, the valves and the bound ``H_dot``."""
        state: RobotState = self.robot(t)
        storage, storage_rate, controllable, stiffnesses = self._task_powers(state, t)
        controllable, contact_power = self._contact_powers(state.v, controllable, t)
        uncontrollable = uncontrollable_power(state.v, state.bias_forces, contact_power)
        tank = valves(float(self.energy(t)), controllable, uncontrollable, self.limits)
        bound = tank.beta * tank.gamma * storage_rate + tank.energy_rate
        return EnergyBudget(storage, storage_rate, controllable, uncontrollable, tank, bound, stiffnesses)

    def _task_powers(self, state: RobotState, t: int) -> tuple[float, float, float, dict[Any, np.ndarray]]:
        """``S``, ``S_dot`` and ``B_sigma`` summed over the active tasks (Eqs. 5.11, 5.18), and
        each task's ``P = Lambda K_P`` (its rate by finite difference from the previous tick's)."""
        v, inverse_mass = state.v, state.inverse_mass_matrix
        previous = self.previous_stiffness(t)
        storage = storage_rate = controllable = 0.0
        stiffnesses = {}
        for key, block in self._blocks(v, t).items():
            inertia = task_space_inertia(block.jacobian, state.mass_matrix, inverse_mass)
            p = stiffnesses[key] = stiffness(block, inertia)
            before = previous.get(key)
            rate = (p - before) / self.dt if before is not None and before.shape == p.shape else np.zeros_like(p)
            power = task_power(block, inertia, rate)
            storage, storage_rate = storage + power.storage, storage_rate + power.storage_rate
            controllable += power.controllable_power
        return storage, storage_rate, controllable, stiffnesses

    def _contact_powers(self, v: np.ndarray, controllable: float, t: int) -> tuple[float, float]:
        """``controllable`` plus ``(J_F v)^T T_F F_F`` of each force task's contact (Eq. 5.18),
        and the power ``sum_k (J_k v)^T T_k f_k`` of the other active contacts' forces of the
        previous solution (Eq. 5.19; errata E17)."""
        contact_power = 0.0
        wrenches = self.contact_frame_wrenches(t)
        for inp in self._contact_inputs:
            contact = inp(t)
            if not contact.active:
                continue
            twist = contact.jacobian @ v
            if contact.force_reference is not None:  # a force task: controllable (Eq. 5.18)
                controllable += float(twist @ (contact.force_generator @ contact.force_reference))
            elif contact.name in wrenches:
                contact_power += float(twist @ wrenches[contact.name])
        return controllable, contact_power

    # -- outputs -------------------------------------------------------------------------------
    @dg.output(dtype=Passivity, depends=("budget", "robot"))
    def passivity(self, t: int) -> Passivity:
        """Scale ``beta gamma`` and bound ``H_dot`` for a passive solver (scale 1, no bound when disabled)."""
        if not self.enabled:
            return Passivity(1.0, None, self.robot(t).v)
        budget = self.budget(t)
        return Passivity(budget.scale, budget.power_bound, self.robot(t).v)

    @dg.output(shape=(), depends=("budget",))
    def alpha(self, t: int) -> float:
        """Overflow valve (Eq. 5.23)."""
        return self.budget(t).valves.alpha

    @dg.output(shape=(), depends=("budget",))
    def beta(self, t: int) -> float:
        """Output valve (Eq. 5.22)."""
        return self.budget(t).valves.beta

    @dg.output(shape=(), depends=("budget",))
    def gamma(self, t: int) -> float:
        """Power limiter (Eq. 5.21)."""
        return self.budget(t).valves.gamma

    @dg.output(shape=(), depends=("budget",))
    def storage(self, t: int) -> float:
        """``S`` (J)."""
        return self.budget(t).storage

    @dg.output(shape=(), depends=("budget",))
    def storage_rate(self, t: int) -> float:
        """``S_dot`` (W)."""
        return self.budget(t).storage_rate

    @dg.output(shape=(), depends=("budget",))
    def controllable_power(self, t: int) -> float:
        """``B_sigma`` (W)."""
        return self.budget(t).controllable_power

    @dg.output(shape=(), depends=("budget",))
    def uncontrollable_power(self, t: int) -> float:
        """``B_phi`` (W)."""
        return self.budget(t).uncontrollable_power

    @dg.output(shape=(), depends=("budget",))
    def energy_rate(self, t: int) -> float:
        """Planned ``E_dot = (1 - alpha)(beta gamma B_sigma - B_phi)`` (W)."""
        return self.budget(t).valves.energy_rate

    @dg.output(shape=(), depends=("budget",))
    def power_bound(self, t: int) -> float:
        """``H_dot``, which the QP keeps below ``-v_j^T tau`` (W)."""
        return self.budget(t).power_bound

    @dg.output(shape=(), depends=("robot", "solution"))
    def delivered_power(self, t: int) -> float:
        """``-v_j^T tau`` of the torque the solver sent (W)."""
        state: RobotState = self.robot(t)
        return -float(state.v[unactuated_dofs(state.model):] @ self.solution(t).tau)

    # -- integration after the solve ----------------------------------------------------------
    def prepare_state(self, t: int) -> None:
        """Integrate the tank from the delivered power; keep ``Lambda K_P`` and the contact wrenches.

        The overflow valve is evaluated again on the actual flow (the QP row bounds it from below
        only, so a tank that planned to drain may fill). A disabled tank's QP ran with scale 1:
        its bookkeeping uses scale 1 too, with the same capacity ``E_max`` and no floor."""
        budget = self.budget(t)
        energy = float(self.energy(t))
        flow = self.delivered_power(t) - (budget.scale if self.enabled else 1.0) * budget.storage_rate
        energy += self.dt * (1.0 - self._overflow(energy, flow)) * flow
        if not math.isfinite(energy):
            raise dg.ComputeError(f"{self.name}: tank energy is not finite at tick {t} (delivered power "
                                  f"{self.delivered_power(t)}, S_dot {budget.storage_rate})", entity=self.name,
                                  signal="energy")
        kept = min(max(energy, self.minimum_energy), self.maximum_energy) if self.clamp and self.enabled else energy
        self.energy.stage(kept)
        self.correction.stage(float(self.correction(t)) + kept - energy)
        self.previous_stiffness.stage(budget.stiffness)
        solution = self.solution(t)
        self.contact_frame_wrenches.stage({c.name: c.force_generator @ f for c, f in
                                           zip(solution.contacts, solution.forces, strict=True)
                                           if c.force_reference is None})

    def _overflow(self, energy: float, flow: float) -> float:
        """``alpha'``: the overflow valve of the actual flow, which also rejects the part of one
        tick's inflow that would pass ``E_max`` (the discrete form of ``alpha = 1`` at ``E_max``;
        rejecting inflow is passive, so no clamp is needed at the top)."""
        if flow <= 0.0:
            return 0.0
        headroom = max(self.maximum_energy - energy, 0.0) / (self.dt * flow)
        return min(1.0, max(overflow_valve(energy, True, self.limits), 1.0 - headroom))

    def commit_state(self, t_next: int) -> None:
        """Publish the new energy, correction, stiffness and contact wrenches."""
        for state in (self.energy, self.correction, self.previous_stiffness, self.contact_frame_wrenches):
            state.commit(t_next)
