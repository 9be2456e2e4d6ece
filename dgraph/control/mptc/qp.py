"""The MPTC quadratic program (report Eq. 20-28): the task forces blended over the joint torques
and the contact wrenches, solved by ProxQP.

Variables ``u = [tau_j, f_1, ..., f_c]``: the actuated torques and the force variables of each
active contact (a sole's four corner forces, a point's force), mapped to generalized forces by
``U = [S, J_1^T G_1, ..., J_c^T G_c]`` (``S`` selects the actuated rows; ``G_c`` is the
contact's force generator). The stacked task forces are ``f = T U u`` with ``T = [T_1; ...]``,
and the QP is

```
min  1/2 ||f_des - T U u||^2_W + eps/2 ||u||^2          W = Lambda^-1 Psi  (Eq. 24-28)
s.t. J_c M^-1 (U u - h) = rhs_c                        each active contact is rigid (optional)
     l_c <= F_c f_c <= u_c                             friction pyramids, normal-force bounds (CoP inside the sole)
     -tau_max <= tau_j <= tau_max                      torque limits
```

With ``A_k = J_k M^-1 U`` the task force is ``f_k = M_k A_k u`` and ``W`` makes the cost
``sum_k psi_k/2 (f_k,des - M_k A_k u)^T M_k^-1 (f_k,des - M_k A_k u)``, i.e. Hessian
``sum_k psi_k A_k^T M_k A_k`` and gradient ``-sum_k psi_k A_k^T f_k,des``. At the unconstrained
optimum the gradient vanishes: ``U^T M^-1 sum_k psi_k J_k^T f~_k = 0``, hence
``sum_k psi_k J_k^T f~_k = 0`` when ``U`` has full row rank (the conflicts then do no net work
on ``q_dot``, the notes' §4.2). Active constraints add their multipliers to that balance:
:func:`~dgraph.control.mptc.task_force.weighted_force_residual` measures what is left.

Beyond the report (the notes' §4.5): only active contacts get wrench columns (no zero columns in
single support); the rigid-contact rows make the commanded wrenches the ones the physics can
deliver (the report holds a stance foot only by a soft foot task); ``eps`` makes the problem
strictly convex (the internal forces between two feet cost nothing otherwise).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from dgraph.control.contact import ContactConstraint
from dgraph.control.mptc.task_force import Dynamics, TaskForce
from dgraph.control.proxqp import INFINITY, WarmStartedQP, dense_qp, proxqp_status
from dgraph.control.solutions import QPSolution
from dgraph.control.status import NOT_FINITE, SOLVED, Status
from dgraph.signals.value_types import value_type

DEFAULT_REGULARISATION = 1e-6
"""``eps``: small beside the task Hessian (TALOS: entries of order 1e-2 to 1 per unit psi) and
enough to make the internal forces between two soles well posed."""
RETRY_REGULARISATION = 1e-5
"""``eps`` of the second solve after a failed one. From a warm start ProxQP reported some feasible
MPTC problems primal infeasible (the first ticks of an early touchdown with a narrow normal-force
band); a fresh solve with this ``eps`` solved them."""
PROXIMAL_RHO = 1e-8
"""ProxQP's proximal parameter on the primal variables (as the inverse-dynamics QP's)."""


@value_type
@dataclass(slots=True)
class MptcSolution(QPSolution):
    """A :class:`QPSolution` with the MPTC tasks of the tick: ``tasks`` (a
    :class:`TaskForce` per task of nonzero weight), ``task_rows`` (which declared task each is),
    ``force_errors`` (``f~_k = f_k,des - f_k`` at the commanded torques and wrenches; empty
    when the solve failed) and ``retried`` (the warm-started solve failed and a fresh one, with
    ``RETRY_REGULARISATION``, gave the answer or the final status)."""

    tasks: list[TaskForce] = field(default_factory=list)
    task_rows: list[int] = field(default_factory=list)
    force_errors: list[np.ndarray] = field(default_factory=list)
    retried: bool = False


def generalized_force_map(n_unactuated: int, nv: int, contacts: list[ContactConstraint]) -> np.ndarray:
    """``U = [S, J_1^T G_1, ...]`` (nv x n_u): the generalized force of ``u = [tau_j, f_1, ...]``."""
    selection = np.zeros((nv, nv - n_unactuated))
    selection[n_unactuated:] = np.eye(nv - n_unactuated)
    return np.hstack([selection, *(c.jacobian.T @ c.force_generator for c in contacts)])


class MptcQP:
    """The MPTC QP of one robot (module docstring): ``nv`` velocities, ``n_unactuated`` of them
    unactuated, the torque limits ``effort_limit``; one warm-started ProxQP problem per set of
    sizes (the active contacts change them)."""

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, *, eps_abs: float,
                 max_iterations: int, regularisation: float = DEFAULT_REGULARISATION):
        self.nv, self.n_unactuated, self.effort_limit = nv, n_unactuated, effort_limit
        self.eps_abs, self.max_iterations, self.regularisation = eps_abs, max_iterations, regularisation
        self._problems: dict[tuple[int, int, int], WarmStartedQP] = {}

    def problem(self, dynamics: Dynamics, tasks: list[TaskForce], contacts: list[ContactConstraint],
                rigid_contacts: bool) -> tuple[np.ndarray, ...]:
        """``(H, g, A, b, C, l, u)`` in ProxQP's form, and ``U``, for the tasks and active contacts."""
        actuation = generalized_force_map(self.n_unactuated, self.nv, contacts)
        mobility = dynamics.inverse_mass_matrix @ actuation  # M^-1 U
        n_u = actuation.shape[1]
        hessian = self.regularisation * np.eye(n_u)
        gradient = np.zeros(n_u)
        for task in tasks:
            task_map = task.jacobian @ mobility  # A_k
            hessian += task.weight * (task_map.T @ task.inertia @ task_map)
            gradient -= task.weight * (task_map.T @ task.desired_force)
        hessian = 0.5 * (hessian + hessian.T)
        equality, target = self._rigid_rows(dynamics, contacts, mobility) if rigid_contacts else (
            np.zeros((0, n_u)), np.zeros(0))
        inequality, lower, upper = self._bounds(contacts, n_u)
        return (hessian, gradient, equality, target, inequality, lower, upper), actuation

    def _rigid_rows(self, dynamics: Dynamics, contacts: list[ContactConstraint],
                    mobility: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``J_c M^-1 U u = rhs_c + J_c M^-1 h`` for every active contact."""
        if not contacts:
            return np.zeros((0, mobility.shape[1])), np.zeros(0)
        free_acceleration = dynamics.inverse_mass_matrix @ dynamics.bias_forces
        rows = [c.jacobian @ mobility for c in contacts]
        targets = [c.motion_rhs + c.jacobian @ free_acceleration for c in contacts]
        return np.vstack(rows), np.concatenate(targets)

    def _bounds(self, contacts: list[ContactConstraint], n_u: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The torque box and each contact's friction and normal-force rows on its own columns
        (an infinite bound becomes ProxQP's ``INFINITY``)."""
        n_actuated = self.nv - self.n_unactuated
        n_rows = n_actuated + sum(c.friction_matrix.shape[0] for c in contacts)
        rows = np.zeros((n_rows, n_u))
        rows[:n_actuated, :n_actuated] = np.eye(n_actuated)
        lower, upper = [-self.effort_limit], [self.effort_limit]
        row, column = n_actuated, n_actuated
        for contact in contacts:
            friction = contact.friction_matrix
            rows[row:row + friction.shape[0], column:column + friction.shape[1]] = friction
            lower.append(contact.friction_lower)
            upper.append(contact.friction_upper)
            row, column = row + friction.shape[0], column + friction.shape[1]
        return rows, np.clip(np.concatenate(lower), -INFINITY, INFINITY), np.clip(np.concatenate(upper), -INFINITY,
                                                                                 INFINITY)

    def solve(self, dynamics: Dynamics, tasks: list[TaskForce], contacts: list[ContactConstraint],
              tick: int | None, rigid_contacts: bool = True) -> MptcSolution:
        """Solve at ``tick``: torques, contact forces, accelerations ``M^-1 (U u - h)``, the task
        force errors; ``tau`` is None when the solve failed (the caller's fallback)."""
        start = time.perf_counter()
        problem, actuation = self.problem(dynamics, tasks, contacts, rigid_contacts)
        sizes = (problem[0].shape[0], problem[2].shape[0], problem[4].shape[0])
        if not all(np.isfinite(part).all() for part in problem):
            return self._failed(NOT_FINITE, 0, start, contacts, tasks)
        qp = self._problems.get(sizes)
        if qp is None:
            qp = self._problems[sizes] = WarmStartedQP(*sizes, eps_abs=self.eps_abs,
                                                        max_iterations=self.max_iterations, rho=PROXIMAL_RHO)
        status, iterations = qp.solve(problem, tick)
        retried = status != SOLVED
        if retried:
            status, more, u = self._retry(problem)
            iterations += more
        else:
            u = qp.latest[0].copy()
        if status != SOLVED:
            return self._failed(status, iterations, start, contacts, tasks)
        generalized_force = actuation @ u
        acceleration = dynamics.inverse_mass_matrix @ (generalized_force - dynamics.bias_forces)
        n_actuated = self.nv - self.n_unactuated
        forces = np.split(u[n_actuated:], np.cumsum([c.n_forces for c in contacts])[:-1]) if contacts else []
        errors = [task.desired_force - task.force(generalized_force) for task in tasks]
        return MptcSolution(acceleration, u[:n_actuated].copy(), list(forces), status, iterations,
                            time.perf_counter() - start, contacts, tasks=tasks, force_errors=errors, retried=retried)

    def _retry(self, problem: tuple[np.ndarray, ...]) -> tuple[Status, int, np.ndarray]:
        """A fresh ProxQP solve (its own preconditioner, no warm start) with ``eps`` at least
        ``RETRY_REGULARISATION``: ``(status, iterations, u)``."""
        hessian, *rest = problem
        extra = max(RETRY_REGULARISATION - self.regularisation, 0.0)
        qp = dense_qp(len(hessian), len(rest[1]), len(rest[3]), eps_abs=self.eps_abs,
                      max_iterations=self.max_iterations, rho=PROXIMAL_RHO)
        qp.init(hessian + extra * np.eye(len(hessian)), *rest)
        qp.solve()
        return proxqp_status(qp.results), int(qp.results.info.iter), qp.results.x.copy()

    def _failed(self, status: int, iterations: int, start: float, contacts: list[ContactConstraint],
                tasks: list[TaskForce]) -> MptcSolution:
        """A failed solve: zero accelerations and forces, no torque (the caller falls back)."""
        return MptcSolution(np.zeros(self.nv), None, [np.zeros(c.n_forces) for c in contacts], status, iterations,
                            time.perf_counter() - start, contacts, tasks=tasks, retried=status != NOT_FINITE)
