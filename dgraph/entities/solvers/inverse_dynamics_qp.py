"""The weighted inverse-dynamics QP (thesis Eq. 4.14), assembled in place and solved by ProxQP.

Variables ``x = [a, f]``: generalized accelerations ``a`` (nv) and the force variables ``f``
of the active contacts. Torques are not variables: the actuated rows of the dynamics give
them back, ``tau = M_j a + h_j - (J_c^T T)_j f`` (thesis Eq. 2.4), so the QP keeps only the
``n_u`` unactuated (floating-base) rows as equalities. ``bench/id_formulations.py`` compares
this with ``tau`` kept as variables (82 instead of 62 variables for TALOS on two feet).

```
min  sum_i ||A_i a - b_i||^2_{W_i} + sum_c w_c ||f_c||^2 + eps ||a||^2
s.t. M_u a - (J_c^T T)_u f = -h_u                         floating-base dynamics
     J_c a = rhs_c                                         each active contact
     l_c <= C_c f_c <= u_c                                 friction pyramids, normal force
     tau_min - h_j <= M_j a - (J_c^T T)_j f <= tau_max - h_j   torque limits
```
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import proxsuite

from dgraph.entities.contacts.constraint import ContactConstraint
from dgraph.entities.tasks.equation import TaskEquation

INFINITY = 1e20
"""ProxQP's bound for 'no bound'."""

SOLVED, MAX_ITERATIONS, PRIMAL_INFEASIBLE, DUAL_INFEASIBLE, NOT_FINITE, NOT_SOLVED = range(6)
STATUS_NAMES = ("solved", "max_iterations", "primal_infeasible", "dual_infeasible", "not_finite", "not_solved")
_PROXQP_STATUS = {
    "PROXQP_SOLVED": SOLVED,
    "PROXQP_MAX_ITER_REACHED": MAX_ITERATIONS,
    "PROXQP_PRIMAL_INFEASIBLE": PRIMAL_INFEASIBLE,
    "PROXQP_DUAL_INFEASIBLE": DUAL_INFEASIBLE,
}


@dataclass(slots=True)
class QPSolution:
    """The solver's answer at one tick.

    ``status`` is one of the module constants (``SOLVED`` = 0); when it is not ``SOLVED``,
    ``tau`` is the caller's fallback and ``acceleration`` / ``forces`` are zeros.
    """

    acceleration: np.ndarray
    tau: np.ndarray
    forces: list[np.ndarray]
    status: int
    iterations: int
    solve_time: float
    objective: float = 0.0
    contacts: list[ContactConstraint] = field(default_factory=list)


@dataclass(slots=True)
class _Workspace:
    """Preallocated matrices and the ProxQP object for one set of active contacts."""

    qp: object
    H: np.ndarray
    g: np.ndarray
    A: np.ndarray
    b: np.ndarray
    C: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    initialised: bool = False


class InverseDynamicsQP:
    """Builds and solves the QP for a robot with ``nv`` velocities, the first ``n_unactuated``
    of them unactuated (6 for a free-flyer base), and torque limits ``effort_limit``.

    One ProxQP dense object is kept per set of active contacts (the problem's size) and
    warm-started from the previous solution; matrices are filled in place.
    """

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, *, eps_abs: float = 1e-9,
                 max_iterations: int = 1000, acceleration_weight: float = 1e-6):
        self.nv, self.nu = nv, n_unactuated
        self.na = nv - n_unactuated
        self.effort_limit = np.asarray(effort_limit, dtype=float)
        self.eps_abs, self.max_iterations = eps_abs, max_iterations
        self.acceleration_weight = acceleration_weight
        self._workspaces: dict[tuple[int, ...], _Workspace] = {}

    # -- assembly ----------------------------------------------------------------------------
    def _workspace(self, contacts: list[ContactConstraint]) -> _Workspace:
        key = tuple(c.n_forces for c in contacts) + tuple(len(c.friction_lower) for c in contacts)
        ws = self._workspaces.get(key)
        if ws is None:
            nf = sum(c.n_forces for c in contacts)
            n = self.nv + nf
            n_eq = self.nu + 6 * len(contacts)
            n_in = sum(len(c.friction_lower) for c in contacts) + self.na
            qp = proxsuite.proxqp.dense.QP(n, n_eq, n_in)
            qp.settings.eps_abs = self.eps_abs
            qp.settings.eps_rel = 0.0
            qp.settings.max_iter = self.max_iterations
            qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            ws = _Workspace(qp, np.zeros((n, n)), np.zeros(n), np.zeros((n_eq, n)), np.zeros(n_eq),
                            np.zeros((n_in, n)), np.zeros(n_in), np.zeros(n_in))
            self._workspaces[key] = ws
        return ws

    def assemble(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, tasks: list[TaskEquation],
                 contacts: list[ContactConstraint]) -> _Workspace:
        """Fill the workspace for this tick's problem (see the module docstring)."""
        nv, nu = self.nv, self.nu
        ws = self._workspace(contacts)
        H, g, A, b, C, lower, upper = ws.H, ws.g, ws.A, ws.b, ws.C, ws.lower, ws.upper
        H.fill(0.0)
        g.fill(0.0)
        H_aa = H[:nv, :nv]
        for task in tasks:
            weighted = task.matrix * task.weight[:, None]
            H_aa += 2.0 * (task.matrix.T @ weighted)
            g[:nv] -= 2.0 * (weighted.T @ task.vector)
        H_aa[np.diag_indices(nv)] += 2.0 * self.acceleration_weight
        # generalized contact forces J^T T for every contact, side by side: (nv, nf)
        A.fill(0.0)
        C.fill(0.0)
        A[:nu, :nv] = mass_matrix[:nu]
        b[:nu] = -bias_forces[:nu]
        C[-self.na:, :nv] = mass_matrix[nu:]
        row_eq, row_in, col = nu, 0, nv
        for contact in contacts:
            k = contact.n_forces
            forces = slice(col, col + k)
            generalized = contact.jacobian.T @ contact.force_generator
            A[:nu, forces] = -generalized[:nu]
            C[-self.na:, forces] = -generalized[nu:]
            A[row_eq:row_eq + 6, :nv] = contact.jacobian
            b[row_eq:row_eq + 6] = contact.motion_rhs
            m = len(contact.friction_lower)
            C[row_in:row_in + m, forces] = contact.friction_matrix
            lower[row_in:row_in + m] = np.maximum(contact.friction_lower, -INFINITY)
            upper[row_in:row_in + m] = np.minimum(contact.friction_upper, INFINITY)
            H[forces, forces][np.diag_indices(k)] = 2.0 * contact.force_weight
            row_eq, row_in, col = row_eq + 6, row_in + m, col + k
        lower[-self.na:] = -self.effort_limit - bias_forces[nu:]
        upper[-self.na:] = self.effort_limit - bias_forces[nu:]
        return ws

    # -- solving -----------------------------------------------------------------------------
    def solve(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, tasks: list[TaskEquation],
              contacts: list[ContactConstraint], fallback_tau: np.ndarray) -> QPSolution:
        """Assemble, solve, and recover ``tau``; never raises on a numerical failure."""
        start = time.perf_counter()
        ws = self.assemble(mass_matrix, bias_forces, tasks, contacts)
        finite = all(np.isfinite(m).all() for m in (ws.H, ws.g, ws.A, ws.b, ws.C, ws.lower, ws.upper))
        status, iterations = NOT_FINITE, 0
        if finite:
            qp = ws.qp
            if ws.initialised:
                qp.update(ws.H, ws.g, ws.A, ws.b, ws.C, ws.lower, ws.upper)
            else:
                qp.init(ws.H, ws.g, ws.A, ws.b, ws.C, ws.lower, ws.upper)
                ws.initialised = True
            qp.solve()
            info = qp.results.info
            status = _PROXQP_STATUS.get(info.status.name, NOT_SOLVED)
            iterations = int(info.iter)
            x = qp.results.x
            if status == SOLVED and not np.isfinite(x).all():
                status = NOT_FINITE
        if status != SOLVED:
            ws.initialised = False  # never warm-start from a failed solve
            return QPSolution(np.zeros(self.nv), fallback_tau, [np.zeros(c.n_forces) for c in contacts], status,
                              iterations, time.perf_counter() - start, contacts=contacts)
        x = x.copy()
        acceleration, forces = x[:self.nv], self._split_forces(x, contacts)
        tau = ws.C[-self.na:] @ x + bias_forces[self.nu:]  # torque rows are [M_j, -(J^T T)_j]
        return QPSolution(acceleration, tau, forces, SOLVED, iterations, time.perf_counter() - start,
                          float(qp.results.info.objValue), contacts)

    def _split_forces(self, x: np.ndarray, contacts: list[ContactConstraint]) -> list[np.ndarray]:
        forces, col = [], self.nv
        for contact in contacts:
            forces.append(x[col:col + contact.n_forces])
            col += contact.n_forces
        return forces
