"""The weighted inverse-dynamics QP (thesis Eq. 4.14), assembled in one pass into preallocated
buffers and solved by ProxQP.

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
     -v_j^T tau >= H_dot                                   passivity (only with a bound)
     tau_min - h_j <= M_j a - (J_c^T T)_j f <= tau_max - h_j   torque limits (when one binds)
```

``f*_c`` is a contact's force reference (a force task's, thesis Eq. 4.12; 0 otherwise). The
passive mode of thesis Eq. 5.34 scales every task vector and force reference by
``s = beta gamma`` (Eq. 5.24) and adds the passivity row, ``-v_j^T tau >= H_dot`` with
``tau = M_j a + h_j - (J_c^T T)_j f``; with ``s = 1`` and no bound the problem is the plain one,
bit for bit.

**Layout** (the way TSID lays out its formulation): each task owns a fixed block of rows of one
stacked matrix, each contact fixed columns of ``x`` and fixed rows of the equalities, so a tick
copies every task's and contact's rows into their blocks and forms the cost with one product,
``H_aa = (sqrt(2 W) A)^T (sqrt(2 W) A)``, instead of one product per task. Nothing is allocated
in steady state (``tests/entities/test_inverse_dynamics.py`` counts it with ``tracemalloc``).

**Torque limits only when one binds**: the QP is first solved without the ``n_a`` torque-limit
rows (66 inequalities become 34 for TALOS on two feet: a quarter of the solve time). If the
torques it gives respect every limit (to ``eps_abs``), that answer is also the optimum with
the limits (adding constraints that the optimum satisfies does not move it); otherwise the QP
is solved again with them (``QPSolution.torque_limited``).
"""

from __future__ import annotations

import itertools
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
DEFAULT_EPS_ABS = 1e-6
"""ProxQP's absolute tolerance: on recorded TALOS ticks it changes ``tau`` by at most ~1e-2 N m
against 1e-9, with half the iterations (``bench/qp_tolerance.py``, docs/benchmarks.md)."""

SOLVED, MAX_ITERATIONS, PRIMAL_INFEASIBLE, DUAL_INFEASIBLE, NOT_FINITE, NOT_SOLVED = range(6)
STATUS_NAMES = ("solved", "max_iterations", "primal_infeasible", "dual_infeasible", "not_finite", "not_solved")
_PROXQP_STATUS = {
    "PROXQP_SOLVED": SOLVED,
    "PROXQP_MAX_ITER_REACHED": MAX_ITERATIONS,
    "PROXQP_PRIMAL_INFEASIBLE": PRIMAL_INFEASIBLE,
    "PROXQP_DUAL_INFEASIBLE": DUAL_INFEASIBLE,
}


_largest = np.maximum.reduce
"""The largest entry of an array (the ufunc itself: ``ndarray.max`` adds microseconds of wrapping)."""


def proxqp_status(results: object) -> int:
    """The module's status code for ProxQP ``results`` (``NOT_FINITE`` for a "solved" answer
    with non-finite entries)."""
    status = _PROXQP_STATUS.get(results.info.status.name, NOT_SOLVED)
    if status == SOLVED and not math.isfinite(np.vdot(results.x, results.x)):
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
    ``forces`` are zeros. ``iterations`` and ``solve_time`` add up every ProxQP solve of the
    tick; ``torque_limited`` says the torque limits bound the answer (a second solve with them).
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
    torque_limited: bool = False


class WarmStartedQP:
    """One ProxQP dense problem of fixed size, solved tick after tick.

    Warm-started from the solution of the latest earlier tick, with the preconditioner of its
    first solve (the problem's scaling hardly changes between ticks; recomputing it doubles the
    solve time). Solving again at the same tick (a graph with its cache off) starts from the
    same guess: ProxQP then gives the same answer bit for bit. After a failure the next solve
    starts cold, with a new preconditioner (never from a failed iterate).
    """

    def __init__(self, n: int, n_eq: int, n_in: int, eps_abs: float, max_iterations: int):
        qp = proxsuite.proxqp.dense.QP(n, n_eq, n_in)
        qp.settings.eps_abs = eps_abs
        qp.settings.eps_rel = 0.0
        qp.settings.max_iter = max_iterations
        qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START
        self.qp = qp
        self.initialised = False
        self.has_solution = False  # the latest buffers hold a solution
        self.latest = (np.zeros(n), np.zeros(n_eq), np.zeros(n_in))
        self.guess = (np.zeros(n), np.zeros(n_eq), np.zeros(n_in))
        self.guess_tick: int | None = None
        self.has_guess = False

    def _prepare_guess(self, tick: int | None, start: tuple[np.ndarray, ...] | None) -> None:
        """This tick's guess: ``start`` if given, else the latest solution of an earlier tick
        (the two sets of buffers swap: the new solution overwrites the older one)."""
        if start is not None:
            x, y, z = self.guess
            np.copyto(x, start[0])
            np.copyto(y, start[1])
            z[:len(start[2])] = start[2]  # rows the start does not have begin at 0
            z[len(start[2]):] = 0.0
            self.guess_tick, self.has_guess = tick, True
        elif tick is None or tick != self.guess_tick:
            self.guess_tick = tick
            self.has_guess = self.has_solution
            if self.has_solution:
                self.guess, self.latest = self.latest, self.guess

    def solve(self, problem: tuple[np.ndarray, ...], tick: int | None,
              start: tuple[np.ndarray, ...] | None = None) -> tuple[int, int]:
        """ProxQP on ``problem`` = ``(H, g, A, b, C, lower, upper)``: ``(status, iterations)``; a
        solution lands in :attr:`latest`. ``start`` = ``(x, y, z)`` replaces the warm start (``z``
        may be shorter than this problem's: a solution without its last rows)."""
        self._prepare_guess(tick, start)
        qp = self.qp
        if self.initialised:
            qp.update(*problem, update_preconditioner=False)
        else:
            qp.init(*problem)
            self.initialised = True
        if self.has_guess:
            qp.solve(*self.guess)
        else:
            qp.solve()
        results = qp.results
        info = results.info
        status = _PROXQP_STATUS.get(info.status.name, NOT_SOLVED)
        if status == SOLVED:
            x, y, z = self.latest
            np.copyto(x, results.x)  # ProxQP's arrays are views of its own memory
            np.copyto(y, results.y)
            np.copyto(z, results.z)
            if not math.isfinite(np.vdot(x, x)):
                status = NOT_FINITE
        self.has_solution = status == SOLVED
        if not self.has_solution:
            self.initialised = False
        return status, int(info.iter)


class TaskRows:
    """The stacked rows of a list of tasks of fixed sizes (the task part of the cost).

    ``matrix`` (m x nv), ``vector`` and ``weight`` (m) hold every task's block of rows; the cost
    ``sum_i w_i (A a - b)_i^2`` is ``a^T H a / 2 + g^T a`` + const with ``H = (R A)^T (R A)`` and
    ``g = -(R A)^T (s R b)``, ``R = diag(sqrt(2 w))`` (ProxQP minimises ``x^T H x / 2 + g^T x``).
    A task's weights are checked (>= 0) and rooted only when its weight array changes.
    """

    def __init__(self, sizes: tuple[int, ...], nv: int):
        starts = np.cumsum((0, *sizes))
        self.blocks = [slice(int(a), int(b)) for a, b in itertools.pairwise(starts)]
        m = int(starts[-1])
        self.matrix, self.vector, self.weight = np.zeros((m, nv)), np.zeros(m), np.zeros(m)
        self.root, self.root_rows = np.zeros(m), np.zeros((m, nv))  # sqrt(2 w), and repeated along the rows
        self.scaled = np.zeros((m, nv))
        self._scaled_transposed = self.scaled.T
        self.scaled_vector = np.zeros(m)
        self.hessian, self.gradient = np.zeros((nv, nv)), np.zeros(nv)
        self._weights: list[object] = [None] * len(sizes)

    def write(self, tasks: list[TaskEquation]) -> bool:
        """Copy every task's rows into its block; False if a task's weights are negative."""
        matrix, vector, weight, weights = self.matrix, self.vector, self.weight, self._weights
        changed = False
        for index, (task, block) in enumerate(zip(tasks, self.blocks, strict=True)):
            matrix[block] = task.matrix
            vector[block] = task.vector
            if task.weight is not weights[index]:
                weight[block] = task.weight
                weights[index] = task.weight
                changed = True
        if changed:
            if (weight < 0.0).any():
                self._weights = [None] * len(self.blocks)
                return False
            np.multiply(weight, 2.0, out=self.root)
            np.sqrt(self.root, out=self.root)
            self.root_rows[...] = self.root[:, None]  # a product with it needs no broadcast buffer
        return True

    def cost(self, scale: float) -> None:
        """``hessian = (R A)^T (R A)`` and ``gradient = (R A)^T (s R b)`` (the negated ``g``)."""
        np.multiply(self.matrix, self.root_rows, out=self.scaled)
        np.multiply(self.vector, self.root, out=self.scaled_vector)
        if scale != 1.0:
            self.scaled_vector *= scale
        np.dot(self._scaled_transposed, self.scaled, out=self.hessian)  # BLAS, no temporary (matmul has one)
        np.dot(self._scaled_transposed, self.scaled_vector, out=self.gradient)


class _ContactBlock:
    """Where one active contact sits in a workspace: its force columns, its motion rows, and
    views of both in the problem's matrices (made once)."""

    def __init__(self, ws: Workspace, contact: ContactConstraint, column: int, row: int, friction_row: int, nv: int,
                 nu: int):
        k, m = contact.n_forces, len(contact.motion_rhs)
        columns, rows = slice(column, column + k), slice(row, row + m)
        self.columns = columns
        self.generalized = np.zeros((nv, k))  # -J^T T: the columns of the contact's forces in the dynamics
        self.base_part, self.joint_part = self.generalized[:nu], self.generalized[nu:]
        self.dynamics = ws.A[:nu, columns]
        self.torque = ws.torque_rows[:, columns]
        self.motion_matrix = ws.A[rows, :nv]
        self.motion_rhs = ws.b[rows]
        self.force_gradient = ws.g[columns]
        self.force_hessian = ws.H[columns, columns]
        friction = slice(friction_row, friction_row + len(contact.friction_lower))
        self.friction, self.friction_lower, self.friction_upper = ws.C[friction, columns], ws.lower[friction], \
            ws.upper[friction]
        self.written: tuple[object, ...] = ()  # the constant arrays last written
        self.negated_generator = -contact.force_generator

    def write_constant_rows(self, contact: ContactConstraint) -> None:
        """Friction rows and bounds, force regularisation (constant: written again only when the
        contact hands over other arrays than last time)."""
        self.friction[...] = contact.friction_matrix
        self.friction_lower[...] = np.maximum(contact.friction_lower, -INFINITY)
        self.friction_upper[...] = np.minimum(contact.friction_upper, INFINITY)
        self.force_hessian[...] = np.diag(np.full(contact.n_forces, 2.0 * contact.force_weight))
        self.negated_generator = -contact.force_generator
        self.written = (contact.friction_matrix, contact.friction_lower, contact.friction_upper,
                        contact.force_weight, contact.force_generator)

    def write(self, contact: ContactConstraint) -> None:
        """The contact's columns of the dynamics and torque rows, and its motion rows."""
        written = self.written
        if (contact.friction_matrix is not written[0] or contact.friction_lower is not written[1]
                or contact.friction_upper is not written[2] or contact.force_weight != written[3]
                or contact.force_generator is not written[4]):
            self.write_constant_rows(contact)
        np.dot(contact.jacobian.T, self.negated_generator, out=self.generalized)
        self.dynamics[...] = self.base_part
        self.torque[...] = self.joint_part
        self.motion_matrix[...] = contact.jacobian
        self.motion_rhs[...] = contact.motion_rhs


class Workspace:
    """The matrices of the problem for one set of active contacts (with or without a passivity
    row), the two ProxQP problems over them (without and with the torque-limit rows) and views
    of their blocks.

    ``C`` stacks the contacts' friction rows, the passivity row (if any) and the ``n_a``
    torque rows (``torque_rows``, last); ``free`` solves without the torque rows. The friction
    rows, their bounds and the force regularisation do not change from tick to tick: they are
    written when the workspace is made, or again when a contact hands over different arrays.
    The passivity row, when there is one, is the last row before the torque rows.
    """

    def __init__(self, qp: InverseDynamicsQP, contacts: list[ContactConstraint], passivity_row: bool):
        nv, nu, na = qp.nv, qp.nu, qp.na
        n = nv + sum(c.n_forces for c in contacts)
        n_eq = nu + sum(len(c.motion_rhs) for c in contacts)
        n_free = sum(len(c.friction_lower) for c in contacts) + passivity_row
        self.n, self.n_free = n, n_free
        self.H, self.g = np.zeros((n, n)), np.zeros(n)
        self.A, self.b = np.zeros((n_eq, n)), np.zeros(n_eq)
        self.C, self.lower, self.upper = np.zeros((n_free + na, n)), np.zeros(n_free + na), np.zeros(n_free + na)
        self.torque_rows = self.C[n_free:]
        self.torque_lower, self.torque_upper = self.lower[n_free:], self.upper[n_free:]
        self.hessian_block, self.gradient_block = self.H[:nv, :nv], self.g[:nv]
        self.acceleration_diagonal = self.H.reshape(-1)[: nv * (n + 1): n + 1]
        self.base_dynamics, self.base_rhs = self.A[:nu, :nv], self.b[:nu]
        self.torque_acceleration = self.torque_rows[:, :nv]
        self.passivity_row = self.C[n_free - 1] if passivity_row else None
        self.full = (self.H, self.g, self.A, self.b, self.C, self.lower, self.upper)
        self.without_limits = (self.H, self.g, self.A, self.b, self.C[:n_free], self.lower[:n_free],
                               self.upper[:n_free])
        self.free = WarmStartedQP(n, n_eq, n_free, qp.eps_abs, qp.max_iterations)
        self.limited: WarmStartedQP | None = None  # made at the first tick a torque limit binds
        column, row, friction_row = nv, nu, 0
        self.blocks: list[_ContactBlock] = []
        for contact in contacts:
            block = _ContactBlock(self, contact, column, row, friction_row, nv, nu)
            block.write_constant_rows(contact)
            self.blocks.append(block)
            column, row = column + contact.n_forces, row + len(contact.motion_rhs)
            friction_row += len(contact.friction_lower)
        self.tau_excess = np.zeros(na)

    def limited_qp(self, qp: InverseDynamicsQP) -> WarmStartedQP:
        """The problem with the torque rows (made on first use)."""
        if self.limited is None:
            self.limited = WarmStartedQP(self.n, len(self.b), len(self.lower), qp.eps_abs, qp.max_iterations)
        return self.limited


class InverseDynamicsQP:
    """Builds and solves the QP for a robot with ``nv`` velocities, the first ``n_unactuated``
    of them unactuated (6 for a free-flyer base), and torque limits ``effort_limit``.

    One :class:`Workspace` per set of active contacts (the problem's size), its matrices filled
    in place; one :class:`TaskRows` per list of task sizes.
    """

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, *, eps_abs: float = DEFAULT_EPS_ABS,
                 max_iterations: int = 1000, acceleration_weight: float = 1e-6):
        self.nv, self.nu = nv, n_unactuated
        self.na = nv - n_unactuated
        self.effort_limit = np.asarray(effort_limit, dtype=float)
        self._negative_limit = -self.effort_limit
        self.eps_abs, self.max_iterations = eps_abs, max_iterations
        self.acceleration_weight = acceleration_weight
        self._workspaces: dict[tuple[object, ...], Workspace] = {}
        self._task_rows: dict[tuple[int, ...], TaskRows] = {}
        self._passivity_row = np.zeros(0)

    # -- assembly ----------------------------------------------------------------------------
    def workspace(self, contacts: list[ContactConstraint], passivity_row: bool) -> Workspace:
        """The workspace of this set of active contacts (by name and size)."""
        key = (passivity_row, *((c.name, c.n_forces, len(c.friction_lower), len(c.motion_rhs)) for c in contacts))
        ws = self._workspaces.get(key)
        if ws is None:
            ws = self._workspaces[key] = Workspace(self, contacts, passivity_row)
        return ws

    def task_rows(self, tasks: list[TaskEquation]) -> TaskRows:
        """The stacked rows for this list of task sizes."""
        sizes = tuple(len(task.vector) for task in tasks)
        rows = self._task_rows.get(sizes)
        if rows is None:
            rows = self._task_rows[sizes] = TaskRows(sizes, self.nv)
        return rows

    def assemble(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, tasks: list[TaskEquation],
                 contacts: list[ContactConstraint], passivity: Passivity | None = None) -> Workspace:
        """Fill the workspace for this tick's problem (see the module docstring); a task whose
        rows do not fit its block, or whose weights are negative, raises ``ValueError``."""
        scale = 1.0 if passivity is None else passivity.scale
        bounded = passivity is not None and passivity.power_bound is not None
        ws = self.workspace(contacts, bounded)
        rows = self.task_rows(tasks)
        if not rows.write(tasks):
            raise ValueError("negative task weights (the cost would not be convex)")
        rows.cost(scale)
        ws.hessian_block[...] = rows.hessian
        ws.acceleration_diagonal += 2.0 * self.acceleration_weight
        np.negative(rows.gradient, out=ws.gradient_block)
        nu = self.nu
        ws.base_dynamics[...] = mass_matrix[:nu]  # dynamics (floating-base rows) and torque rows share [M, -J_c^T T]
        np.negative(bias_forces[:nu], out=ws.base_rhs)
        ws.torque_acceleration[...] = mass_matrix[nu:]
        np.subtract(self._negative_limit, bias_forces[nu:], out=ws.torque_lower)
        np.subtract(self.effort_limit, bias_forces[nu:], out=ws.torque_upper)
        for contact, block in zip(contacts, ws.blocks, strict=True):
            block.write(contact)
            if contact.force_reference is not None:  # -2 w_c s f*_c
                np.multiply(contact.force_reference, -2.0 * contact.force_weight * scale, out=block.force_gradient)
            else:
                block.force_gradient.fill(0.0)
        if bounded:
            self._write_passivity_row(ws, passivity, bias_forces)
        return ws

    def _write_passivity_row(self, ws: Workspace, passivity: Passivity, bias_forces: np.ndarray) -> None:
        """``-v_j^T tau >= H_dot`` with ``tau = (torque rows) x + h_j``, divided by the row's norm
        (the preconditioner is kept from the first solve: a row whose scale follows ``|v|`` would
        drift out of it). A zero row (``v ~ 0``) holds for every ``x`` up to rounding and is
        dropped (a bound out of reach is caught before by the entity)."""
        velocity = passivity.velocity[self.nu:]
        row = ws.passivity_row
        np.matmul(velocity, ws.torque_rows, out=row)
        np.negative(row, out=row)
        bound = passivity.power_bound + velocity @ bias_forces[self.nu:]
        norm = math.sqrt(row @ row)
        index = ws.n_free - 1
        if norm > 1e-12:
            row /= norm
            ws.lower[index] = bound / norm
        else:  # v ~ 0: -v_j^T tau ~ 0 for every tau, and H_dot is rounding noise (the entity relaxes larger ones)
            row[:] = 0.0
            ws.lower[index] = -INFINITY
        ws.upper[index] = INFINITY

    # -- solving -----------------------------------------------------------------------------
    def solve(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, tasks: list[TaskEquation],
              contacts: list[ContactConstraint], tick: int | None = None,
              passivity: Passivity | None = None) -> QPSolution:
        """Assemble, solve (again with the torque limits if one binds) and recover ``tau``; never
        raises on a numerical failure (then ``status`` says why and ``tau`` is None: the caller
        chooses the fallback)."""
        start = time.perf_counter()
        ws = self.assemble(mass_matrix, bias_forces, tasks, contacts, passivity)
        if not self._finite(ws):
            return self._failed(NOT_FINITE, 0, contacts, start)
        status, iterations = ws.free.solve(ws.without_limits, tick)
        limited = False
        if status == SOLVED:
            tau = self._torques(ws, ws.free.latest[0], bias_forces)
            limited = self._beyond_limits(ws, tau)
            if limited:
                qp = ws.limited_qp(self)  # from this tick's answer without the limits
                status, more = qp.solve(ws.full, tick, start=ws.free.latest)
                iterations += more
                if status == SOLVED:
                    tau = self._torques(ws, qp.latest[0], bias_forces)
        if status != SOLVED:
            return self._failed(status, iterations, contacts, start)
        x = (ws.limited if limited else ws.free).latest[0].copy()
        solution = QPSolution(x[:self.nv], tau, self._split_forces(x, contacts), SOLVED, iterations,
                              time.perf_counter() - start, 0.0, contacts, torque_limited=limited)
        solution.objective = float((ws.limited if limited else ws.free).qp.results.info.objValue)
        return solution

    def _finite(self, ws: Workspace) -> bool:
        """Whether the problem is finite (a NaN or inf makes a squared norm non-finite; the bounds
        are finite up to +-INFINITY, the upper torque bounds exactly when the lower ones are)."""
        vdot = np.vdot
        return math.isfinite(vdot(ws.H, ws.H) + vdot(ws.g, ws.g) + vdot(ws.A, ws.A) + vdot(ws.b, ws.b)
                             + vdot(ws.C, ws.C) + vdot(ws.torque_lower, ws.torque_lower))

    def _torques(self, ws: Workspace, x: np.ndarray, bias_forces: np.ndarray) -> np.ndarray:
        """``tau = (torque rows) x + h_j`` (the torque rows are ``[M_j, -(J^T T)_j]``)."""
        tau = ws.torque_rows @ x
        tau += bias_forces[self.nu:]
        return tau

    def _beyond_limits(self, ws: Workspace, tau: np.ndarray) -> bool:
        """Whether some ``|tau_j|`` exceeds its limit by more than ProxQP's tolerance."""
        excess = ws.tau_excess
        np.abs(tau, out=excess)
        excess -= self.effort_limit
        return bool(_largest(excess) > self.eps_abs)

    def _failed(self, status: int, iterations: int, contacts: list[ContactConstraint], start: float) -> QPSolution:
        return QPSolution(np.zeros(self.nv), None, [np.zeros(c.n_forces) for c in contacts], status, iterations,
                          time.perf_counter() - start, contacts=contacts)

    def _split_forces(self, x: np.ndarray, contacts: list[ContactConstraint]) -> list[np.ndarray]:
        forces, col = [], self.nv
        for contact in contacts:
            forces.append(x[col:col + contact.n_forces])
            col += contact.n_forces
        return forces
