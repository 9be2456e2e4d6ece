"""InverseDynamicsSolver: the weighted whole-body inverse-dynamics QP as an entity."""

from __future__ import annotations

import numpy as np

import dgraph as dg
from dgraph.entities.contacts.constraint import ContactConstraint
from dgraph.entities.named_inputs import declare_named_inputs
from dgraph.entities.robot.robot_state import RobotState, load_model, plugged_model, unactuated_dofs
from dgraph.entities.solvers.inverse_dynamics_qp import (
    DEFAULT_EPS_ABS,
    POWER_TOLERANCE,
    SOLVED,
    InverseDynamicsQP,
    Passivity,
    QPSolution,
    TaskRowsError,
)
from dgraph.entities.tasks.equation import TaskEquation


@dg.register
class InverseDynamicsSolver(dg.Entity):
    """Torque control from weighted tasks and rigid contacts (thesis Eq. 4.14, "TSID torque").

    Solves, every tick, for accelerations ``a`` and contact forces ``f``
    (:mod:`~dgraph.entities.solvers.inverse_dynamics_qp`):
    ``min sum_i w_i ||A_i a - b_i||^2 + sum_c w_c ||f_c||^2`` subject to the floating-base
    dynamics, the contacts' motion constraints, friction pyramids, normal-force bounds and the
    torque limits, then recovers ``tau = M_j a + h_j - (J_c^T T)_j f`` (Eq. 2.4). The torque
    limits enter the QP only on ticks where the answer without them would exceed one
    (``torque_limited``); the answer is the same either way.

    When the QP fails (infeasible, iteration limit, non-finite data), ``status`` says why
    (0 solved, 1 max iterations, 2 primal infeasible, 3 dual infeasible, 4 not finite,
    5 other) and ``tau`` is the fallback ``g_j(q) - fallback_damping v_j``, clipped to the
    torque limits: gravity compensation with joint damping, never an exception.

    Passive mode (``passive: true``, thesis Eq. 5.34): an input ``passivity`` (an
    :class:`~dgraph.entities.energy.EnergyTank`'s ``passivity``) scales every task vector and
    force reference by ``beta gamma`` and adds the row ``-v_j^T tau >= H_dot``. A tank that is
    disabled hands over scale 1 and no bound: the QP is then the plain one, bit for bit. When
    no torque within the limits can deliver the bound (``H_dot > sum |v_j| tau_max``), or the
    passive QP fails, it is solved without the passivity row (``passivity_relaxed`` is true for
    that tick: the tank, integrated from the delivered power, pays for it), and only if that
    fails too does the fallback act.

    Parameters: ``model`` (sizes the ports; the same robot as the RobotModel), ``tasks`` and
    ``contacts`` (names of the inputs to declare, usually the names of the task and contact
    entities plugged into them), ``eps_abs`` (ProxQP absolute tolerance), ``max_iterations``,
    ``acceleration_weight`` (regularisation ``eps ||a||^2``), ``fallback_damping``.
    Inputs: ``robot`` (RobotModel state), one input per task (a Task's ``equation``), one per
    contact (a Contact6d's ``contact``).
    Outputs: ``solution`` (everything below, computed once), ``tau`` (actuated torques),
    ``acceleration`` (nv), ``contact_wrenches`` (one row ``[force, torque]`` per contact,
    world axes at the contact frame; zeros when inactive), ``normal_force_total`` (sum of the
    world-z contact forces), ``status``, ``passivity_relaxed``, ``torque_limited``,
    ``iterations`` and ``solve_time`` (s, assembly and every ProxQP solve of the tick).
    """

    model = dg.Param("talos", kind="object", doc="robot name or pinocchio.Model (sizes the ports)")
    tasks = dg.Param((), kind="str_list", doc="task input names")
    contacts = dg.Param((), kind="str_list", doc="contact input names")
    eps_abs = dg.Param(DEFAULT_EPS_ABS, kind="float", minimum=1e-12, maximum=1e-3,
                       doc="ProxQP absolute tolerance (also the torque-limit margin)")
    max_iterations = dg.Param(1000, kind="int", minimum=1, doc="ProxQP iteration limit")
    acceleration_weight = dg.Param(1e-6, kind="float", minimum=0.0, doc="regularisation of a")
    fallback_damping = dg.Param(1.0, kind="float", minimum=0.0, doc="joint damping of the fallback torque")
    passive = dg.Param(False, kind="bool", doc="declare a passivity input (an energy tank's, Eq. 5.34)")

    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")

    def configure(self) -> None:
        """Size the outputs from the model and declare one input per task and per contact."""
        model = load_model(self.model, self.name)
        self.nv = model.nv
        self.n_unactuated = unactuated_dofs(model)
        self.na = self.nv - self.n_unactuated
        self.n_contacts = len(self.contacts)
        self._qp = InverseDynamicsQP(self.nv, self.n_unactuated, model.effortLimit[self.n_unactuated:],
                                     eps_abs=self.eps_abs, max_iterations=self.max_iterations,
                                     acceleration_weight=self.acceleration_weight)
        declare_named_inputs(self, [(self.tasks, TaskEquation, "equation of task"),
                                    (self.contacts, ContactConstraint, "constraint of contact")],
                             reserved=("passivity",))
        if self.passive:
            self.declare("passivity", dg.Input(dtype=Passivity, doc="task scale and storage-rate bound of a tank"))

    def setup(self) -> None:
        """Collect the task and contact inputs."""
        self._task_inputs = [getattr(self, n) for n in self.tasks]
        self._contact_inputs = [getattr(self, n) for n in self.contacts]

    def check(self) -> list[str]:
        """The plugged robot model must be the size of ``model``."""
        model = plugged_model(self.robot)
        if model is not None and model.nv != self.nv:
            return [f"its model has nv = {self.nv} but the robot plugged into {self.robot.full_name} has nv = "
                    f"{model.nv}"]
        return []

    def _read(self, t: int) -> tuple[list[TaskEquation], list[ContactConstraint]]:
        return [inp(t) for inp in self._task_inputs], [inp(t) for inp in self._contact_inputs]

    def _bad_equation(self, tasks: list[TaskEquation], t: int, cause: TaskRowsError) -> dg.SpecError:
        """The error naming the task input whose equation did not fit its block of the QP."""
        name = self._task_inputs[cause.index].name
        try:
            self._check_equation(name, tasks[cause.index], t)
        except dg.SpecError as exc:
            return exc
        return dg.SpecError(f"{self.name}.{name} at tick {t}: {cause}", entity=self.name, signal=name)

    def _check_equation(self, name: str, equation: TaskEquation, t: int) -> None:
        """``A`` (m x nv), ``b`` (m), ``w`` (m) >= 0, or a ``SpecError`` naming the input."""
        rows = equation.matrix.shape[0] if equation.matrix.ndim == 2 else -1
        problem = None
        if equation.matrix.ndim != 2 or equation.matrix.shape[1] != self.nv:
            problem = f"task matrix has shape {equation.matrix.shape}, the robot has nv = {self.nv}"
        elif equation.vector.shape != (rows,) or equation.weight.shape != (rows,):
            problem = (f"{rows} rows but a vector of shape {equation.vector.shape} and weights of shape "
                       f"{equation.weight.shape}")
        elif (equation.weight < 0).any():
            problem = "negative weights (the cost would not be convex)"
        if problem is not None:
            raise dg.SpecError(f"{self.name}.{name} at tick {t}: {problem}", entity=self.name, signal=name)

    def _reachable(self, passivity: Passivity) -> bool:
        """Whether some torque within the limits delivers ``-v_j^T tau >= H_dot`` (at most
        ``sum |v_j| tau_max``; a necessary condition, to within ``POWER_TOLERANCE``)."""
        if passivity.power_bound is None:
            return True
        largest = float(np.abs(passivity.velocity[self.n_unactuated:]) @ self._qp.effort_limit)
        return passivity.power_bound <= largest + POWER_TOLERANCE

    def fallback_torque(self, state: RobotState) -> np.ndarray:
        """``g_j(q) - d v_j``, clipped to the torque limits."""
        nu = self.n_unactuated
        tau = state.gravity_torque()[nu:] - self.fallback_damping * state.v[nu:]
        return np.clip(tau, -self._qp.effort_limit, self._qp.effort_limit)

    @dg.output(dtype=QPSolution)
    def solution(self, t: int) -> QPSolution:
        """Solve the QP at ``t`` (or fall back)."""
        state: RobotState = self.robot(t)
        tasks, contacts = self._read(t)
        active = [row for row, contact in enumerate(contacts) if contact.active]
        passivity = self.passivity(t) if self.passive else None
        active_contacts = [contacts[r] for r in active]
        relax = passivity is not None and not self._reachable(passivity)
        if relax:  # no torque within the limits delivers the bound: ProxQP would only run to its limit
            passivity = Passivity(passivity.scale, None, passivity.velocity)
        try:  # a task whose rows do not fit its block (shape, negative weights) is named here
            solution = self._qp.solve(state.mass_matrix, state.bias_forces, tasks, active_contacts, t, passivity)
        except TaskRowsError as exc:
            raise self._bad_equation(tasks, t, exc) from exc
        if solution.status != SOLVED and passivity is not None and passivity.power_bound is not None:
            relax = True
            relaxed = Passivity(passivity.scale, None, passivity.velocity)
            solution = self._qp.solve(state.mass_matrix, state.bias_forces, tasks, active_contacts, t, relaxed)
        solution.passivity_relaxed = relax
        solution.contact_rows = active
        if solution.status != SOLVED:
            solution.tau = self.fallback_torque(state)
        return solution

    @dg.output(shape=("na",), depends=("solution",))
    def tau(self, t: int) -> np.ndarray:
        """Actuated joint torques."""
        return self.solution(t).tau

    @dg.output(shape=("nv",), depends=("solution",))
    def acceleration(self, t: int) -> np.ndarray:
        """Generalized accelerations ``a`` (zeros after a failed solve)."""
        return self.solution(t).acceleration

    @dg.output(shape=("n_contacts", 6), depends=("solution",))
    def contact_wrenches(self, t: int) -> np.ndarray:
        """One ``[force, torque]`` row per declared contact (world axes; zeros if inactive)."""
        solution = self.solution(t)
        wrenches = np.zeros((self.n_contacts, 6))
        for row, contact, forces in zip(solution.contact_rows, solution.contacts, solution.forces, strict=True):
            wrenches[row] = contact.world_wrench(forces)
        return wrenches

    @dg.output(shape=(), depends=("contact_wrenches",))
    def normal_force_total(self, t: int) -> float:
        """Sum of the contacts' world-z forces (N)."""
        return float(sum(self.contact_wrenches(t)[:, 2].tolist()))  # a few contacts: Python's sum is cheapest

    @dg.output(shape=(), dtype="int", depends=("solution",))
    def status(self, t: int) -> int:
        """0 when solved; see the class docstring for the failure codes."""
        return self.solution(t).status

    @dg.output(shape=(), dtype="bool", depends=("solution",))
    def passivity_relaxed(self, t: int) -> bool:
        """True when the passive QP failed and was solved without its passivity row."""
        return self.solution(t).passivity_relaxed

    @dg.output(shape=(), dtype="bool", depends=("solution",))
    def torque_limited(self, t: int) -> bool:
        """True when a torque limit binds (the QP was solved a second time, with the limits)."""
        return self.solution(t).torque_limited

    @dg.output(shape=(), dtype="int", depends=("solution",))
    def iterations(self, t: int) -> int:
        """ProxQP iterations (of both solves when a torque limit binds)."""
        return self.solution(t).iterations

    @dg.output(shape=(), depends=("solution",))
    def solve_time(self, t: int) -> float:
        """Wall time of assembly and solve (s)."""
        return self.solution(t).solve_time
