"""MptcSolver: the Modular Passive Tracking Controller (MPTC) over the same tasks and contacts as the ID solver."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.control.feature import FeatureValue
from dgraph.control.mptc import (
    DEFAULT_REGULARISATION,
    Dynamics,
    MptcQP,
    MptcSolution,
    TaskForce,
    task_force,
    weighted_force_residual,
)
from dgraph.control.status import SOLVED
from dgraph.entities.robot.robot_state import RobotState
from dgraph.entities.solvers.torque_solver import TorqueSolver


@dg.register
class MptcSolver(TorqueSolver):
    """Torque control by passive task forces (MPTC; Englsberger et al., RSS 2020; the report
    ``000_f010bfa6716960a7.txt`` Eq. 16-28; :mod:`dgraph.control.mptc`).

    Each task ``k`` (a Task's equation: its feature, gains ``kp``, ``kd`` and weight) becomes a
    mass-spring-damper in its own space with the task inertia ``M_k = (J_k M^-1 J_k^T)^-1``,
    stiffness ``K_k`` and damping ``D_k`` shaped by ``M_k`` from ``kp`` and ``kd`` (a Task with
    ``critical_damping`` damps it critically), through the desired force (report Eq. 16)

    ``f_k,des = T_k g + M_k Q_k q_dot + M_k x*_ddot + (C_k + D_k) x~_dot + K_k x~``

    and one QP over ``u = [tau_j, wrenches of the active contacts]`` blends them:
    ``min 1/2 ||f_des - T U u||^2_W + eps/2 ||u||^2`` with ``W = Lambda^-1 Psi`` (Eq. 24-28),
    ``psi_k`` the task's weight (one value per task; a task of weight 0 is left out), under the
    torque limits, each active contact's friction pyramids and normal-force bounds (its CoP inside
    the sole) and, with ``rigid_contacts``, its motion rows ``J_c q_ddot = rhs_c`` (so the
    commanded wrenches are those a rigid contact can deliver). Contacts are those whose
    ``active`` input is true: plug the contact scheduler's flags, or a measured contact state,
    into the contacts. ``J_dot_k`` (in ``C_k`` only) is ``J_k``'s backward difference over one
    tick (0 at a task's first tick); ``C`` is Pinocchio's Coriolis matrix.

    When the QP fails, ``status`` says why and ``tau`` is the gravity-compensation fallback of
    :class:`~dgraph.entities.solvers.torque_solver.TorqueSolver` (never zero torque on a
    finite state). A task feature that is a rate (angular momentum) has no position error and
    is refused, as is a task whose weights differ between rows or whose Jacobian loses rank.

    Passivity, made visible: per declared task ``task_storage`` ``V_k``, ``task_storage_rate``
    (``-x~_dot^T D_k x~_dot + x~_dot^T f~_k``, its rate along the closed loop) and
    ``task_port_power`` (``x~_dot^T f~_k``), with ``f~_k = f_k,des - T_k U u`` the force error of
    the commanded ``u`` (zeros for a task left out or a failed tick); ``weighted_force_residual``
    ``r = sum_k psi_k J_k^T f~_k`` (zero at the unconstrained optimum: the weighting is chosen for
    it) and ``residual_power`` ``-q_dot^T r``, the power with which the active bounds' multipliers
    feed the weighted storage ``sum_k psi_k V_k`` (``weighted_storage``): 0 when no bound binds.

    Parameters: those of ``TorqueSolver`` (``model``, ``tasks``, ``contacts``,
    ``max_iterations``, ``fallback_damping``), ``eps_abs`` (ProxQP absolute tolerance),
    ``regularisation`` (``eps``), ``rigid_contacts``, ``dt`` (tick period, default the graph's).
    Inputs: ``robot`` (RobotModel state), one per task (a Task's ``equation``), one per contact
    (a contact's ``contact``).
    Outputs: those of ``TorqueSolver`` (``solution``, here a
    :class:`~dgraph.control.mptc.MptcSolution`, ``tau``, ``acceleration``, ``contact_wrenches``,
    ``normal_force_total``, ``status``, ``iterations``, ``solve_time``) and the passivity
    signals above.
    """

    eps_abs = dg.Param(1e-6, kind="float", minimum=1e-12, maximum=1e-3, doc="ProxQP absolute tolerance")
    regularisation = dg.Param(DEFAULT_REGULARISATION, kind="float", minimum=0.0,
                              doc="eps of the strict-convexity term eps/2 ||u||^2")
    rigid_contacts = dg.Param(True, kind="bool", doc="add each active contact's motion rows J_c q_ddot = rhs_c")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", tasks: Sequence[str] = (), contacts: Sequence[str] = (),
            max_iterations: int = 1000, fallback_damping: float = 1.0, eps_abs: float = 1e-06,
            regularisation: float = 1e-06, rigid_contacts: bool = True, dt: float | None = None,
        ) -> None: ...

    def configure(self) -> None:
        """The ports of a torque solver and the QP."""
        super().configure()
        self.n_tasks = len(self.tasks)
        self._qp = MptcQP(self.nv, self.n_unactuated, self.effort_limit, eps_abs=self.eps_abs,
                          max_iterations=self.max_iterations, regularisation=self.regularisation)

    def reset(self) -> None:
        """No task Jacobian seen yet."""
        super().reset()
        self._jacobians: dict[int, list[tuple[int, np.ndarray]]] = {}  # task row: (tick, J_k) of its last two ticks

    def _refuse(self, name: str, t: int, problem: str) -> dg.SpecError:
        return dg.SpecError(f"{self.name}.{name} at tick {t}: {problem}", entity=self.name, signal=name)

    def _jacobian_rate(self, row: int, t: int, jacobian: np.ndarray) -> np.ndarray:
        """``(J_k(t) - J_k(t - 1)) / dt``; zeros when the task had no Jacobian of that shape at ``t - 1``.
        The Jacobians of the task's last two ticks are kept, so that solving ``t`` again (a graph
        with its cache off, a tick run again) gives the same rate."""
        seen = [entry for entry in self._jacobians.get(row, []) if entry[0] < t]
        self._jacobians[row] = [*seen[-1:], (t, jacobian)]
        before = next((j for tick, j in seen if tick == t - 1), None)
        if before is None or before.shape != jacobian.shape:
            return np.zeros_like(jacobian)
        return (jacobian - before) / self.dt

    def _feature(self, name: str, t: int) -> tuple[FeatureValue, Any, Any, float] | None:
        """The task input ``name`` at ``t`` as (feature, kp, kd, psi), or None at weight 0."""
        equation = self.checked_equation(name, t)
        weight = equation.weight
        if not weight.any():
            return None
        if equation.feature is None or equation.kp is None or equation.kd is None:
            raise self._refuse(name, t, "MPTC needs a Task's equation (its feature and gains)")
        if equation.feature.is_rate:
            raise self._refuse(name, t, "its feature is a rate (no position error to store energy in)")
        if (weight != weight[0]).any():
            raise self._refuse(name, t, f"MPTC weights a task by one psi, got per-row weights {weight}")
        return equation.feature, equation.kp, equation.kd, float(weight[0])

    def _task_forces(self, t: int, dynamics: Dynamics) -> tuple[list[TaskForce], list[int]]:
        """The tasks of nonzero weight at ``t`` and their rows among ``tasks``."""
        tasks, rows = [], []
        for row, name in enumerate(self.tasks):
            read = self._feature(name, t)
            if read is None:
                continue
            feature, kp, kd, psi = read
            try:
                tasks.append(task_force(feature, kp, kd, psi, dynamics,
                                        self._jacobian_rate(row, t, feature.jacobian)))
            except np.linalg.LinAlgError as exc:
                raise self._refuse(name, t, "its Jacobian has lost rank (J M^-1 J^T is singular)") from exc
            rows.append(row)
        return tasks, rows

    @dg.output(dtype=MptcSolution)
    def solution(self, t: int) -> MptcSolution:
        """Solve the MPTC QP at ``t`` (or fall back)."""
        state: RobotState = self.robot(t)
        dynamics = Dynamics(state.inverse_mass_matrix, state.coriolis_matrix, state.bias_forces, state.v)
        tasks, task_rows = self._task_forces(t, dynamics)
        contact_rows, contacts = self.active_contacts(t)
        solution = self._qp.solve(dynamics, tasks, contacts, t, self.rigid_contacts)
        solution.contact_rows, solution.task_rows = contact_rows, task_rows
        if solution.status == SOLVED:
            self.keep_state(state)
        else:
            solution.tau = self.fallback_torque(t, state, solution.status)
        return solution

    def _per_task(self, t: int, value: Callable[[TaskForce, np.ndarray], float]) -> np.ndarray:
        """``value(task, force_error)`` per declared task (0 for a task left out, or on a failed tick)."""
        solution: MptcSolution = self.solution(t)
        values = np.zeros(self.n_tasks)
        # a failed tick has no force errors: the zip is empty and every value 0
        for row, task, error in zip(solution.task_rows, solution.tasks, solution.force_errors, strict=False):
            values[row] = value(task, error)
        return values

    @dg.output(shape=("n_tasks",), depends=("solution",))
    def task_storage(self, t: int) -> np.ndarray:
        """``V_k = x~_dot^T M_k x~_dot / 2 + x~^T K_k x~ / 2`` per task (J)."""
        return self._per_task(t, lambda task, _: task.storage())

    @dg.output(shape=("n_tasks",), depends=("solution",))
    def task_storage_rate(self, t: int) -> np.ndarray:
        """``V_k_dot = -x~_dot^T D_k x~_dot + x~_dot^T f~_k`` per task (W)."""
        return self._per_task(t, TaskForce.storage_rate)

    @dg.output(shape=("n_tasks",), depends=("solution",))
    def task_port_power(self, t: int) -> np.ndarray:
        """``x~_dot^T f~_k`` per task (W): what the force error feeds the task."""
        return self._per_task(t, TaskForce.port_power)

    @dg.output(shape=(), depends=("solution", "task_storage"))
    def weighted_storage(self, t: int) -> float:
        """``sum_k psi_k V_k`` (J), from ``task_storage``."""
        solution: MptcSolution = self.solution(t)
        storage = self.task_storage(t)
        return float(sum(task.weight * storage[row] for row, task in zip(solution.task_rows, solution.tasks,
                                                                         strict=True)))

    @dg.output(shape=("nv",), depends=("solution",))
    def weighted_force_residual(self, t: int) -> np.ndarray:
        """``sum_k psi_k J_k^T f~_k`` (nv): zero at the unconstrained optimum (zeros on a failed tick)."""
        solution: MptcSolution = self.solution(t)
        if not solution.force_errors:
            return np.zeros(self.nv)
        return weighted_force_residual(solution.tasks, solution.force_errors)

    @dg.output(shape=(), depends=("weighted_force_residual",))
    def residual_power(self, t: int) -> float:
        """``-q_dot^T sum_k psi_k J_k^T f~_k`` (W): what the active bounds feed ``sum psi_k V_k``."""
        return -float(self.robot(t).v @ self.weighted_force_residual(t))
