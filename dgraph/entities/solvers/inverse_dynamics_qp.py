"""The weighted inverse-dynamics QP (thesis Eq. 4.14), assembled in place and solved by ProxQP.

Variables ``x = [a, f]``: generalized accelerations ``a`` (nv) and the force variables ``f``
of the active contacts. Torques are not variables: the actuated rows of the dynamics give
them back, ``tau = M_j a + h_j - (J_c^T T)_j f`` (thesis Eq. 2.4), so the QP keeps only the
``n_u`` unactuated (floating-base) rows as equalities. ``bench/id_formulations.py`` compares
this with ``tau`` kept as variables (94 instead of 62 variables for TALOS on two feet; the
solve takes 1.9 times as long, docs/control.md).

```
min  sum_i ||A_i a - s b_i||^2_{W_i} + sum_c w_c ||f_c - s f*_c||^2 + eps ||a||^2
s.t. M_u a - (J_c^T T)_u f = -h_u                         floating-base dynamics
     J_c a = rhs_c                                         each active contact
     l_c <= C_c f_c <= u_c                                 friction pyramids, normal force
     tau_min - h_j <= M_j a - (J_c^T T)_j f <= tau_max - h_j   torque limits
     -v_j^T tau >= H_dot                                   passivity (only with a bound)
```

``f*_c`` is a contact's force reference (a force task's, thesis Eq. 4.12; 0 otherwise). The
passive mode of thesis Eq. 5.34 scales every task vector and force reference by
``s = beta gamma`` (Eq. 5.24) and adds the passivity row, ``-v_j^T tau >= H_dot`` with
``tau = M_j a + h_j - (J_c^T T)_j f``; with ``s = 1`` and no bound the problem is the plain one,
bit for bit.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import proxsuite

from dgraph.entities.contacts.constraint import ContactConstraint
from dgraph.entities.tasks.equation import TaskEquation

INFINITY = 1e20
"""ProxQP's bound for 'no bound'."""
POWER_TOLERANCE = 1e-9
"""W: a passivity bound this close to what the velocity allows counts as met (rounding noise)."""

SOLVED, MAX_ITERATIONS, PRIMAL_INFEASIBLE, DUAL_INFEASIBLE, NOT_FINITE, NOT_SOLVED = range(6)
STATUS_NAMES = ("solved", "max_iterations", "primal_infeasible", "dual_infeasible", "not_finite", "not_solved")
_PROXQP_STATUS = {
    "PROXQP_SOLVED": SOLVED,
    "PROXQP_MAX_ITER_REACHED": MAX_ITERATIONS,
    "PROXQP_PRIMAL_INFEASIBLE": PRIMAL_INFEASIBLE,
    "PROXQP_DUAL_INFEASIBLE": DUAL_INFEASIBLE,
}


def proxqp_status(results: object) -> int:
    """The module's status code for ProxQP ``results`` (``NOT_FINITE`` for a "solved" answer
    with non-finite entries)."""
    status = _PROXQP_STATUS.get(results.info.status.name, NOT_SOLVED)
    if status == SOLVED and not np.isfinite(results.x).all():
        return NOT_FINITE
    return status


@dataclass(slots=True)
class Passivity:
    """What a passive solve needs from an energy tank (thesis Eq. 5.34): the task scale
    ``beta gamma``, the bound ``H_dot`` on the storage rate (None: no passivity row) and the
    velocity ``v`` of the port ``-v_j^T tau``."""

    scale: float
    power_bound: float | None
    velocity: np.ndarray


@dataclass(slots=True)
class QPSolution:
    """The solver's answer at one tick.

    ``status`` is one of the module constants (``SOLVED`` = 0); when it is not ``SOLVED``,
    ``tau`` is None (the solver entity puts its fallback there) and ``acceleration`` /
    ``forces`` are zeros.
    """

    acceleration: np.ndarray
    tau: np.ndarray | None
    forces: list[np.ndarray]
    status: int
    iterations: int
    solve_time: float
    objective: float = 0.0
    contacts: list[ContactConstraint] = field(default_factory=list)
    contact_rows: list[int] = field(default_factory=list)  # which declared contact each one is (set by the entity)
    passivity_relaxed: bool = False  # solved again without the passivity row (set by the entity)


@dataclass(slots=True)
class _Workspace:
    """Preallocated matrices and the ProxQP object for one set of active contacts.

    The contacts' friction rows, their bounds and the force regularisation do not change from
    tick to tick: they are written when the workspace is made, or again when a contact hands
    over different arrays (``sources`` keeps what was written).
    """

    qp: object
    H: np.ndarray
    g: np.ndarray
    A: np.ndarray
    b: np.ndarray
    C: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    sources: list[tuple[object, ...]] = field(default_factory=list)
    initialised: bool = False
    latest: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # last solution (x, y, z)
    guess: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # warm start of this tick's solves
    tick: int | None = None  # the tick ``guess`` serves
    solved: tuple[list[np.ndarray], QPSolution] | None = None  # the problem solved at ``tick``, its answer


class InverseDynamicsQP:
    """Builds and solves the QP for a robot with ``nv`` velocities, the first ``n_unactuated``
    of them unactuated (6 for a free-flyer base), and torque limits ``effort_limit``.

    One ProxQP dense object is kept per set of active contacts (the problem's size) and
    warm-started from the previous solution, with the preconditioner of its first solve (the
    problem's scaling hardly changes between ticks; recomputing it doubles the solve time);
    matrices are filled in place.
    """

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, *, eps_abs: float = 1e-9,
                 max_iterations: int = 1000, acceleration_weight: float = 1e-6):
        self.nv, self.nu = nv, n_unactuated
        self.na = nv - n_unactuated
        self.effort_limit = np.asarray(effort_limit, dtype=float)
        self.eps_abs, self.max_iterations = eps_abs, max_iterations
        self.acceleration_weight = acceleration_weight
        self._diagonal = np.diag_indices(nv)
        self._workspaces: dict[tuple[object, ...], _Workspace] = {}

    # -- assembly ----------------------------------------------------------------------------
    def _workspace(self, contacts: list[ContactConstraint], passivity_row: bool) -> _Workspace:
        key = (passivity_row, *((c.name, c.n_forces, len(c.friction_lower), len(c.motion_rhs)) for c in contacts))
        ws = self._workspaces.get(key)
        if ws is None:
            nf = sum(c.n_forces for c in contacts)
            n = self.nv + nf
            n_eq = self.nu + sum(len(c.motion_rhs) for c in contacts)
            n_in = sum(len(c.friction_lower) for c in contacts) + passivity_row + self.na
            qp = proxsuite.proxqp.dense.QP(n, n_eq, n_in)
            qp.settings.eps_abs = self.eps_abs
            qp.settings.eps_rel = 0.0
            qp.settings.max_iter = self.max_iterations
            qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START
            ws = _Workspace(qp, np.zeros((n, n)), np.zeros(n), np.zeros((n_eq, n)), np.zeros(n_eq),
                            np.zeros((n_in, n)), np.zeros(n_in), np.zeros(n_in))
            self._workspaces[key] = ws
        sources = [(c.friction_matrix, c.friction_lower, c.friction_upper, c.force_weight) for c in contacts]
        if len(sources) != len(ws.sources) or any(
                any(a is not b for a, b in zip(new, old, strict=True)) for new, old in zip(sources, ws.sources,
                                                                                          strict=True)):
            self._write_constant_rows(ws, contacts)
            ws.sources = sources
        return ws

    def _write_constant_rows(self, ws: _Workspace, contacts: list[ContactConstraint]) -> None:
        """Friction rows and bounds, force regularisation."""
        row, col = 0, self.nv
        for contact in contacts:
            k, m = contact.n_forces, len(contact.friction_lower)
            ws.C[row:row + m, col:col + k] = contact.friction_matrix
            ws.lower[row:row + m] = np.maximum(contact.friction_lower, -INFINITY)
            ws.upper[row:row + m] = np.minimum(contact.friction_upper, INFINITY)
            ws.H[np.arange(col, col + k), np.arange(col, col + k)] = 2.0 * contact.force_weight
            row, col = row + m, col + k

    def assemble(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, tasks: list[TaskEquation],
                 contacts: list[ContactConstraint], passivity: Passivity | None = None) -> _Workspace:
        """Fill the workspace for this tick's problem (see the module docstring)."""
        nv, nu, na = self.nv, self.nu, self.na
        scale = 1.0 if passivity is None else passivity.scale
        bounded = passivity is not None and passivity.power_bound is not None
        ws = self._workspace(contacts, bounded)
        # cost on a: sum_i A_i^T W_i A_i and -A_i^T W_i b_i (times 2: ProxQP minimises x^T H x / 2 + g^T x)
        hessian, gradient = 2.0 * self.acceleration_weight * np.eye(nv), np.zeros(nv)
        for task in tasks:
            weighted = task.matrix.T * (2.0 * task.weight)
            hessian += weighted @ task.matrix
            gradient -= weighted @ (task.vector if scale == 1.0 else scale * task.vector)
        ws.H[:nv, :nv] = hessian
        ws.g[:nv] = gradient
        self._write_force_references(ws, contacts, scale)
        # dynamics (floating-base rows) and torque rows share [M, -J_c^T T]
        ws.A[:nu, :nv] = mass_matrix[:nu]
        ws.b[:nu] = -bias_forces[:nu]
        ws.C[-na:, :nv] = mass_matrix[nu:]
        limit = self.effort_limit
        ws.lower[-na:] = -limit - bias_forces[nu:]
        ws.upper[-na:] = limit - bias_forces[nu:]
        if contacts:
            generalized = np.hstack([c.jacobian.T @ c.force_generator for c in contacts])
            ws.A[:nu, nv:] = -generalized[:nu]
            ws.C[-na:, nv:] = -generalized[nu:]
            ws.A[nu:, :nv] = np.vstack([c.jacobian for c in contacts])
            ws.b[nu:] = np.concatenate([c.motion_rhs for c in contacts])
        if bounded:
            self._write_passivity_row(ws, passivity, bias_forces)
        return ws

    def _write_passivity_row(self, ws: _Workspace, passivity: Passivity, bias_forces: np.ndarray) -> None:
        """``-v_j^T tau >= H_dot`` with ``tau = (torque rows) x + h_j``, divided by the row's norm
        (the preconditioner is kept from the first solve: a row whose scale follows ``|v|`` would
        drift out of it). A zero row (``v ~ 0``) holds for every ``x`` up to rounding and is
        dropped (a bound out of reach is caught before by the entity)."""
        velocity = passivity.velocity[self.nu:]
        row = -velocity @ ws.C[-self.na:]
        bound = passivity.power_bound + velocity @ bias_forces[self.nu:]
        norm = math.sqrt(row @ row)
        if norm > 1e-12:
            ws.C[-self.na - 1] = row / norm
            ws.lower[-self.na - 1] = bound / norm
        else:  # v ~ 0: -v_j^T tau ~ 0 for every tau, and H_dot is rounding noise (the entity relaxes larger ones)
            ws.C[-self.na - 1] = 0.0
            ws.lower[-self.na - 1] = -INFINITY
        ws.upper[-self.na - 1] = INFINITY

    def _write_force_references(self, ws: _Workspace, contacts: list[ContactConstraint], scale: float) -> None:
        """``-2 w_c s f*_c`` in the gradient of the contacts that have a force reference."""
        col = self.nv
        for contact in contacts:
            if contact.force_reference is not None:
                ws.g[col:col + contact.n_forces] = (-2.0 * contact.force_weight * scale) * contact.force_reference
            col += contact.n_forces

    # -- solving -----------------------------------------------------------------------------
    def solve(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, tasks: list[TaskEquation],
              contacts: list[ContactConstraint], tick: int | None = None,
              passivity: Passivity | None = None) -> QPSolution:
        """Assemble, solve, and recover ``tau``; never raises on a numerical failure (then
        ``status`` says why and ``tau`` is None: the caller chooses the fallback).

        The warm start is the solution of the latest earlier tick: solving again at the same
        ``tick`` (a graph with its cache off) starts from the same guess and gives the same
        answer bit for bit.
        """
        start = time.perf_counter()
        ws = self.assemble(mass_matrix, bias_forces, tasks, contacts, passivity)
        problem = [ws.H, ws.g, ws.A, ws.b, ws.C, ws.lower, ws.upper]
        if tick is None or tick != ws.tick:
            ws.guess, ws.tick, ws.solved = ws.latest, tick, None
        elif ws.solved is not None and all(np.array_equal(a, b) for a, b in zip(problem, ws.solved[0], strict=True)):
            return ws.solved[1]  # the same problem again in this tick: the same answer
        finite = all(math.isfinite(np.vdot(m, m)) for m in (ws.H, ws.g, ws.A, ws.b, ws.C[-self.na - 1:], ws.lower))
        status, iterations = self.run(ws, ws.guess) if finite else (NOT_FINITE, 0)
        if status != SOLVED:
            return QPSolution(np.zeros(self.nv), None, [np.zeros(c.n_forces) for c in contacts], status,
                              iterations, time.perf_counter() - start, contacts=contacts)
        x = ws.latest[0]
        acceleration, forces = x[:self.nv], self._split_forces(x, contacts)
        tau = ws.C[-self.na:] @ x + bias_forces[self.nu:]  # torque rows are [M_j, -(J^T T)_j]
        solution = QPSolution(acceleration, tau, forces, SOLVED, iterations, time.perf_counter() - start,
                              float(ws.qp.results.info.objValue), contacts)
        if tick is not None:
            ws.solved = ([m.copy() for m in problem], solution)
        return solution

    def run(self, ws: _Workspace, guess: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> tuple[int, int]:
        """ProxQP on an assembled workspace, warm-started from ``guess`` (``x, y, z``) or cold:
        ``(status, iterations)``. A solution is kept in ``ws.latest``; after a failure the next
        run starts cold (never from a failed iterate)."""
        qp = ws.qp
        if ws.initialised:
            qp.update(ws.H, ws.g, ws.A, ws.b, ws.C, ws.lower, ws.upper, update_preconditioner=False)
        else:
            qp.init(ws.H, ws.g, ws.A, ws.b, ws.C, ws.lower, ws.upper)
            ws.initialised = True
        if guess is None:
            qp.solve()
        else:
            qp.solve(*guess)
        results = qp.results
        status = proxqp_status(results)
        if status == SOLVED:
            ws.latest = (results.x.copy(), results.y.copy(), results.z.copy())
        else:
            ws.initialised, ws.latest = False, None
        return status, int(results.info.iter)

    def _split_forces(self, x: np.ndarray, contacts: list[ContactConstraint]) -> list[np.ndarray]:
        forces, col = [], self.nv
        for contact in contacts:
            forces.append(x[col:col + contact.n_forces])
            col += contact.n_forces
        return forces
