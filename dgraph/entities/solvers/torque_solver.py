"""TorqueSolver: what the torque-control solvers share (ports, checks, fallback, the outputs of a QPSolution)."""

from __future__ import annotations

import abc

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.control.contact import ContactConstraint
from dgraph.control.equation import TaskEquation
from dgraph.control.solutions import QPSolution
from dgraph.control.status import Status
from dgraph.entities.named_inputs import declare_named_inputs
from dgraph.entities.robot.loading import load_model
from dgraph.entities.robot.robot_state import RobotState, plugged_model, unactuated_dofs
from dgraph.entities.solver_report import SolverReport


class TorqueSolver(SolverReport, dg.Entity, abc.ABC):
    """Base of the entities that compute joint torques from task equations and contacts on the
    robot state, over the accelerations and the contact forces ``y = [a, f]``
    (:class:`~dgraph.entities.solvers.InverseDynamicsSolver`, weighted;
    :class:`~dgraph.entities.hierarchy.HierarchicalInverseDynamics`, strict priorities), or over
    the torques and contact forces (:class:`~dgraph.entities.solvers.MptcSolver`, task forces).

    A subclass declares its ``eps_abs``, the output ``solution`` (a :class:`QPSolution`, with
    ``tau = M_j a + h_j - (J_c^T T)_j f``, thesis Eq. 2.4, or the fallback when it failed) and,
    in ``reserved_inputs``, the names of the inputs it declares besides the tasks and contacts.

    Parameters: ``model`` (sizes the ports; the same robot as the RobotModel), ``tasks`` and
    ``contacts`` (names of the inputs to declare, usually the names of the task and contact
    entities plugged into them), ``max_iterations``, ``fallback_damping``.
    Inputs: ``robot`` (RobotModel state), one per task (a Task's ``equation``), one per contact
    (a contact's ``contact``).
    Outputs: ``solution``, ``tau`` (actuated torques), ``acceleration`` (nv),
    ``contact_wrenches`` (one row ``[force, torque]`` per contact, world axes at the contact
    frame; zeros when inactive), ``normal_force_total`` (sum of the world-z contact forces),
    ``status`` (a :class:`~dgraph.control.status.Status`: 0 solved, 1 max iterations, 2 primal
    infeasible, 3 dual infeasible, 4 not finite, 5 other), ``iterations`` and ``solve_time``
    (s, assembly and every solve of the tick).

    When a solve fails, ``tau`` is the fallback ``g_j(q) - fallback_damping v_j``, clipped to
    the torque limits: gravity compensation with joint damping, never an exception. It is
    computed from the last robot state that was finite (the state at ``t`` unless bad data
    reached it), so it is always finite; the tick reports a fault naming ``solver.tau``, the
    status and the state used (:mod:`dgraph.faults`).
    """

    reserved_inputs: tuple[str, ...] = ()

    model = dg.Param("talos", kind="name_or_path", doc="robot name, URDF path or pinocchio.Model (sizes the ports)")
    tasks = dg.Param((), kind="str_list", doc="task input names")
    contacts = dg.Param((), kind="str_list", doc="contact input names")
    max_iterations = dg.Param(1000, kind="int", minimum=1, doc="ProxQP iteration limit")
    fallback_damping = dg.Param(1.0, kind="float", minimum=0.0, doc="joint damping of the fallback torque")

    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")

    def configure(self) -> None:
        """Size the outputs from the model and declare one input per task and per contact."""
        model = load_model(self.model, self.name)
        self.nv = model.nv
        self.n_unactuated = unactuated_dofs(model)
        self.n_actuated = self.nv - self.n_unactuated
        self.n_contacts = len(self.contacts)
        self.effort_limit = np.asarray(model.effortLimit[self.n_unactuated:], dtype=float)
        declare_named_inputs(self, [(self.tasks, TaskEquation, "equation of task"),
                                    (self.contacts, ContactConstraint, "constraint of contact")],
                             reserved=self.reserved_inputs)

    def setup(self) -> None:
        """Collect the task and contact inputs."""
        self._task_inputs = [getattr(self, n) for n in self.tasks]
        self._contact_inputs = [getattr(self, n) for n in self.contacts]
        self._gravity_data: pin.Data | None = None

    def reset(self) -> None:
        """No finite state seen yet (the fallback's last resort is zero torque)."""
        super().reset()
        self._last_good: tuple[np.ndarray, np.ndarray] | None = None

    def check(self) -> list[str]:
        """The plugged robot model must be the size of ``model``."""
        model = plugged_model(self.robot)
        if model is not None and model.nv != self.nv:
            return [f"its model has nv = {self.nv} but the robot plugged into {self.robot.full_name} has nv = "
                    f"{model.nv}"]
        return []

    def active_contacts(self, t: int) -> tuple[list[int], list[ContactConstraint]]:
        """The declared contacts active at ``t``: their indices among ``contacts`` and their constraints."""
        contacts = [inp(t) for inp in self._contact_inputs]
        rows = [row for row, contact in enumerate(contacts) if contact.active]
        return rows, [contacts[row] for row in rows]

    def checked_equation(self, name: str, t: int) -> TaskEquation:
        """The task input ``name`` at ``t``: ``A`` (m x nv), ``b`` (m), ``w`` (m) >= 0, or a
        ``SpecError`` naming the input."""
        equation = getattr(self, name)(t)
        problem = equation.problem(self.nv)
        if problem is not None:
            raise dg.SpecError(f"{self.name}.{name} at tick {t}: {problem}", entity=self.name, signal=name)
        return equation

    def keep_state(self, state: RobotState) -> None:
        """Remember ``(q, v)`` of a finite state (one a solve succeeded on, or a finite state the
        fallback used): the fallback's last resort."""
        self._last_good = (state.q.copy(), state.v.copy())

    def fallback_torque(self, t: int, state: RobotState, status: int) -> np.ndarray:
        """``g_j(q) - d v_j``, clipped to the torque limits, on the state at ``t`` or, if that is
        not finite, on the last state kept by :meth:`keep_state` (zero torque if none); the
        fault is reported."""
        q, v, used = state.q, state.v, "the state at this tick"
        if np.isfinite(q).all() and np.isfinite(v).all():
            self.keep_state(state)
        else:
            q, v = self._last_good or (None, None)
            used = "the last finite state" if q is not None else "zero torque: no finite state yet"
        self.report_fault(t, "tau", f"solve failed: {Status(status).name}",
                          f"fallback torque g(q) - d v on {used}")
        if q is None:
            return np.zeros(self.n_actuated)
        gravity = pin.computeGeneralizedGravity(state.model, self._fallback_data(state.model), q)
        n_unactuated = self.n_unactuated
        tau = gravity[n_unactuated:] - self.fallback_damping * v[n_unactuated:]
        return np.clip(tau, -self.effort_limit, self.effort_limit)

    def _fallback_data(self, model: pin.Model) -> pin.Data:
        if self._gravity_data is None:  # made at the first failure: most runs never need it
            self._gravity_data = model.createData()
        return self._gravity_data

    @abc.abstractmethod
    def solution(self, t: int) -> QPSolution:
        """Solve at ``t`` (or fall back): each subclass declares it as an output."""

    @dg.output(shape=("n_actuated",), depends=("solution",))
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
        return self.solution(t).world_wrenches(self.n_contacts)

    @dg.output(shape=(), depends=("contact_wrenches",))
    def normal_force_total(self, t: int) -> float:
        """Sum of the contacts' world-z forces (N)."""
        return float(sum(self.contact_wrenches(t)[:, 2].tolist()))  # a few contacts: Python's sum is cheapest

