"""The weighted inverse-dynamics QP (thesis Eq. 4.14), assembled in one pass into preallocated
buffers and solved by ProxQP.

Variables ``x = [a, f]``: generalized accelerations ``a`` (nv) and the force variables ``f``
of the active contacts. Torques are not variables: the actuated rows of the dynamics give
them back, ``tau = M_j a + h_j - (J_c^T T)_j f`` (thesis Eq. 2.4), so the QP keeps only the
``n_u`` unactuated (floating-base) rows as equalities. ``bench/id_formulations.py`` compares
this with ``tau`` kept as variables (94 instead of 62 variables for TALOS on two feet; the
solve takes 1.9 times as long, docs/control.md).

```
min  sum_i ||A_i a - s b_i||^2_{W_i} + sum_c w_c ||f_c - s f*_c||^2_{M_c} + eps ||a||^2
s.t. M_u a - (J_c^T T)_u f = -h_u                         floating-base dynamics
     J_c a = rhs_c                                         each active contact
     l_c <= C_c f_c <= u_c                                 friction pyramids, normal force
     -v_j^T tau >= H_dot                                   passivity (only with a bound)
     tau_min - h_j <= M_j a - (J_c^T T)_j f <= tau_max - h_j   torque limits (when one binds)
```

``f*_c`` is a contact's force reference (a force task's, thesis Eq. 4.12; 0 otherwise), ``M_c``
its force metric (the identity, or for a sole's 6D wrench the least corner-force norm). The
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

import math
import time
from dataclasses import dataclass, field

import numpy as np
import proxsuite

from dgraph.entities.contacts.constraint import ContactConstraint
from dgraph.entities.tasks.equation import TaskEquation
from dgraph.signals.value_types import value_type

INFINITY = 1e20
"""ProxQP's bound for 'no bound'."""
POWER_TOLERANCE = 1e-9
"""W: a passivity bound this close to what the velocity allows counts as met (rounding noise)."""
PROXIMAL_RHO = 1e-8
"""ProxQP's proximal parameter on the primal variables (its default is 1e-6): on recorded TALOS
sway ticks at eps_abs 1e-6 it takes 1.6 iterations instead of 2.0 and lands ~60 times closer to
the exact optimum (``bench/qp_tolerance.py``, docs/benchmarks.md)."""
DEFAULT_EPS_ABS = 1e-6
"""ProxQP's absolute tolerance: with ``PROXIMAL_RHO``, on recorded TALOS sway ticks ``tau`` is
within ~5e-5 N m of the exact optimum (1e-9: 2e-6 N m, with 1.3x the iterations); from a cold
start within 1e-6 N m there, 1e-5 N m at perturbed states (``bench/qp_tolerance.py``,
docs/benchmarks.md, ``tests/entities/test_inverse_dynamics.py``)."""

SOLVED, MAX_ITERATIONS, PRIMAL_INFEASIBLE, DUAL_INFEASIBLE, NOT_FINITE, NOT_SOLVED = range(6)
STATUS_NAMES = ("solved", "max_iterations", "primal_infeasible", "dual_infeasible", "not_finite", "not_solved")
_PROXQP_STATUS = {getattr(proxsuite.proxqp.QPSolverOutput, name): status for name, status in (
    ("PROXQP_SOLVED", SOLVED),
    ("PROXQP_MAX_ITER_REACHED", MAX_ITERATIONS),
    ("PROXQP_PRIMAL_INFEASIBLE", PRIMAL_INFEASIBLE),
    ("PROXQP_DUAL_INFEASIBLE", DUAL_INFEASIBLE),
)}
"""Our status code of each ProxQP status (by the enum itself: reading its name costs more)."""


FINITE_CHUNK = 8192
"""Numbers per dot product of the finiteness check: OpenBLAS uses one thread up to 10,000."""
_largest = np.maximum.reduce
"""The largest entry of an array, NaN if one is NaN (the ufunc itself: ``ndarray.max`` adds
microseconds of wrapping)."""


def proxqp_status(results: object) -> int:
    """The module's status code for ProxQP ``results`` (``NOT_FINITE`` for a "solved" answer
    with non-finite entries)."""
    status = _PROXQP_STATUS.get(results.info.status, NOT_SOLVED)
    if status == SOLVED and not math.isfinite(np.vdot(results.x, results.x)):
        return NOT_FINITE
    return status


@value_type
@dataclass(slots=True)
class Passivity:
    """What a passive solve needs from an energy tank (thesis Eq. 5.34): the task scale
    ``beta gamma``, the bound ``H_dot`` on the storage rate (None: no passivity row) and the
    velocity ``v`` of the port ``-v_j^T tau``."""

    scale: float
    power_bound: float | None
    velocity: np.ndarray


@value_type
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
    contacts: list[ContactConstraint] = field(default_factory=list)
    contact_rows: list[int] = field(default_factory=list)  # which declared contact each one is (set by the entity)
    passivity_relaxed: bool = False  # solved again without the passivity row (set by the entity)
    torque_limited: bool = False


class WarmStartedQP:
    """One ProxQP dense problem of fixed size, solved tick after tick.

    Warm-started from the solution of the latest earlier tick, with the preconditioner of its
    first solve (the problem's scaling hardly changes between ticks; recomputing it doubles the
    solve time). Solving again at the same tick (a graph with its cache off) repeats the tick's
    first solve exactly: the same guess, and a new preconditioner again if that one started
    cold, so ProxQP gives the same answer bit for bit. After a failure the next solve starts
    cold, with a new preconditioner (never from a failed iterate). ProxQP's proximal parameter
    is ``rho`` (``PROXIMAL_RHO``). With ``same_inequalities`` the inequality rows and bounds are
    not handed over again (the caller knows they did not change since the last solve).
    """

    def __init__(self, n: int, n_eq: int, n_in: int, eps_abs: float, max_iterations: int,
                 rho: float = PROXIMAL_RHO):
        qp = proxsuite.proxqp.dense.QP(n, n_eq, n_in)
        qp.settings.eps_abs = eps_abs
        qp.settings.eps_rel = 0.0
        qp.settings.max_iter = max_iterations
        qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START
        qp.settings.default_rho = rho
        self.qp = qp
        self.initialised = False
        self.has_solution = False  # the latest buffers hold a solution
        self.latest = (np.zeros(n), np.zeros(n_eq), np.zeros(n_in))
        self.guess = (np.zeros(n), np.zeros(n_eq), np.zeros(n_in))
        self.guess_tick: int | None = None
        self.has_guess = False
        self.cold_tick: int | None = None  # the tick of the last init (a cold start)

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

    def solve(self, problem: tuple[np.ndarray, ...], tick: int | None, start: tuple[np.ndarray, ...] | None = None,
              same_inequalities: bool = False) -> tuple[int, int]:
        """ProxQP on ``problem`` = ``(H, g, A, b, C, lower, upper)``: ``(status, iterations)``; a
        solution lands in :attr:`latest`. ``start`` = ``(x, y, z)`` replaces the warm start (``z``
        may be shorter than this problem's: a solution without its last rows)."""
        self._prepare_guess(tick, start)
        qp = self.qp
        if not self.initialised or (tick is not None and tick == self.cold_tick):
            qp.init(*problem)
            self.initialised, self.cold_tick = True, tick
        elif same_inequalities:
            qp.update(*problem[:4], None, None, None, update_preconditioner=False)
        else:
            qp.update(*problem, update_preconditioner=False)
        if self.has_guess:
            qp.solve(*self.guess)
        else:
            qp.solve()
        results = qp.results
        status = proxqp_status(results)
        if status == SOLVED:
            x, y, z = self.latest
            np.copyto(x, results.x)  # ProxQP's arrays are views of its own memory
            np.copyto(y, results.y)
            np.copyto(z, results.z)
        self.has_solution = status == SOLVED
        if not self.has_solution:
            self.initialised = False
        return status, int(results.info.iter)


class TaskRowsError(ValueError):
    """A task's equation does not fit its block of rows (``index``: its place in the task list)."""

    def __init__(self, index: int, message: str):
        super().__init__(message)
        self.index = index


class TaskRows:
    """The stacked rows of a list of tasks (the task part of the cost), for fixed task sizes and
    a fixed set of *steady* tasks (whose matrix and weights are the same arrays as last tick).

    ``matrix`` (m x nv), ``vector`` and ``weight`` (m) hold every task's block of rows, the
    moving tasks' first; the cost ``sum_i w_i (A a - b)_i^2`` is ``a^T H a / 2 + g^T a`` + const
    with ``H = (R A)^T (R A)`` and ``g = -(R A)^T (s R b)``, ``R = diag(sqrt(2 w))`` (ProxQP
    minimises ``x^T H x / 2 + g^T x``). The steady tasks' part of ``H`` is formed once (a
    posture task's selection matrix: 32 of TALOS's 41 demo rows), so each tick multiplies only
    the moving rows. A task's weights are checked (>= 0) and rooted only when they change.
    """

    def __init__(self, sizes: tuple[int, ...], steady: tuple[bool, ...], nv: int):
        order = [i for i in range(len(sizes)) if not steady[i]] + [i for i in range(len(sizes)) if steady[i]]
        self.blocks: list[slice] = [slice(0, 0)] * len(sizes)
        self._shapes = [(size, nv) for size in sizes]
        start = 0
        for i in order:
            self.blocks[i] = slice(start, start + sizes[i])
            start += sizes[i]
        m, moving = start, sum(sizes[i] for i in range(len(sizes)) if not steady[i])
        self.matrix, self.vector, self.weight = np.zeros((m, nv)), np.zeros(m), np.zeros(m)
        self.root, self.root_rows = np.zeros(m), np.zeros((m, nv))  # sqrt(2 w), and repeated along the rows
        self.negative_root = np.zeros(m)
        self.scaled, self.scaled_vector = np.zeros((m, nv)), np.zeros(m)
        self._scaled_transposed = self.scaled.T
        self._moving = (self.matrix[:moving], self.root_rows[:moving], self.scaled[:moving], self.scaled[:moving].T)
        self._steady = (self.scaled[moving:], self.scaled[moving:].T)
        self.hessian, self.steady_hessian = np.zeros((nv, nv)), np.zeros((nv, nv))
        self._is_steady = steady
        self._matrices: list[object] = [None] * len(sizes)  # the arrays written into each block
        self._weights: list[object] = [None] * len(sizes)
        self._steady_stale = True

    def write(self, tasks: list[TaskEquation]) -> None:
        """Copy every task's rows into its block (a matrix or weights only when they are other
        arrays than the ones written, and checked then); :class:`TaskRowsError` for a task whose
        arrays do not have the block's shape (nothing is broadcast) or whose weights are negative."""
        matrix, vector, weight, matrices, weights = self.matrix, self.vector, self.weight, self._matrices, self._weights
        reweighted = False
        for index, (task, block, shape) in enumerate(zip(tasks, self.blocks, self._shapes, strict=True)):
            if task.vector.shape != shape[:1]:
                raise TaskRowsError(index, f"a vector of shape {task.vector.shape}, its block has {shape[0]} rows")
            vector[block] = task.vector
            if task.matrix is not matrices[index]:
                if task.matrix.shape != shape:
                    raise TaskRowsError(index, f"a matrix of shape {task.matrix.shape}, its block is {shape}")
                matrix[block] = task.matrix
                matrices[index] = task.matrix
                self._steady_stale |= self._is_steady[index]
            if task.weight is not weights[index]:
                if task.weight.shape != shape[:1] or (task.weight < 0.0).any():
                    weights[index] = None
                    raise TaskRowsError(index, f"weights of shape {task.weight.shape}, negative or not one per row")
                weight[block] = task.weight
                weights[index] = task.weight
                reweighted = True
        if reweighted:
            np.multiply(weight, 2.0, out=self.root)
            np.sqrt(self.root, out=self.root)
            np.negative(self.root, out=self.negative_root)
            self.root_rows[...] = self.root[:, None]  # a product with it needs no broadcast buffer
            self._steady_stale = True

    def cost(self, scale: float, regularisation: np.ndarray, hessian: np.ndarray, gradient: np.ndarray) -> None:
        """``hessian = (R A)^T (R A) + regularisation`` and ``gradient = -(R A)^T (s R b)``, into
        the given arrays (the cost's blocks of the problem). Few numpy calls: in the control loop
        each costs ~2 us whatever its size."""
        matrix, root_rows, scaled, scaled_transposed = self._moving
        np.multiply(matrix, root_rows, out=scaled)
        np.dot(scaled_transposed, scaled, out=self.hessian)  # BLAS, no temporary (matmul has one)
        if self._steady_stale:  # the steady rows' scaled copy and their part of H, once
            np.multiply(self.matrix, self.root_rows, out=self.scaled)
            np.dot(self._steady[1], self._steady[0], out=self.steady_hessian)
            self.steady_hessian += regularisation
            self._steady_stale = False
        self.hessian += self.steady_hessian
        hessian[...] = self.hessian  # into the strided block: a copy (an add into it would buffer)
        np.multiply(self.vector, self.negative_root, out=self.scaled_vector)  # -R b
        if scale != 1.0:
            self.scaled_vector *= scale
        np.dot(self._scaled_transposed, self.scaled_vector, out=gradient)


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
        self.reference_metric: np.ndarray | None = None  # -2 w_c M, when the contact has a metric
        self.force_reference = False  # a force reference was written into the gradient

    def write_constant_rows(self, contact: ContactConstraint) -> None:
        """Friction rows and bounds, force regularisation (constant: written again only when the
        contact hands over other arrays than last time)."""
        self.friction[...] = contact.friction_matrix
        self.friction_lower[...] = np.maximum(contact.friction_lower, -INFINITY)
        self.friction_upper[...] = np.minimum(contact.friction_upper, INFINITY)
        metric = np.eye(contact.n_forces) if contact.force_metric is None else contact.force_metric
        np.multiply(metric, 2.0 * contact.force_weight, out=self.force_hessian)
        self.reference_metric = None if contact.force_metric is None else -2.0 * contact.force_weight * metric
        self.negated_generator = -contact.force_generator
        self.written = (contact.friction_matrix, contact.friction_lower, contact.friction_upper,
                        contact.force_weight, contact.force_generator, contact.force_metric)

    def write(self, contact: ContactConstraint, scale: float) -> bool:
        """The contact's columns of the dynamics and torque rows, its motion rows and its force
        reference ``-2 w_c s f*_c`` in the gradient; True if its constant rows were written again."""
        written = self.written
        rewritten = (contact.friction_matrix is not written[0] or contact.friction_lower is not written[1]
                     or contact.friction_upper is not written[2] or contact.force_weight != written[3]
                     or contact.force_generator is not written[4] or contact.force_metric is not written[5])
        if rewritten:
            self.write_constant_rows(contact)
        np.dot(contact.jacobian.T, self.negated_generator, out=self.generalized)
        self.dynamics[...] = self.base_part
        self.torque[...] = self.joint_part
        self.motion_matrix[...] = contact.jacobian
        self.motion_rhs[...] = contact.motion_rhs
        if contact.force_reference is not None:  # -2 w_c s M f*
            if self.reference_metric is None:
                np.multiply(contact.force_reference, -2.0 * contact.force_weight * scale, out=self.force_gradient)
            else:
                np.dot(self.reference_metric, contact.force_reference, out=self.force_gradient)
                self.force_gradient *= scale
            self.force_reference = True
        elif self.force_reference:
            self.force_gradient.fill(0.0)
            self.force_reference = False
        return rewritten


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
        n_in = n_free + na
        shapes = ((n, n), (n,), (n_eq, n), (n_eq,), (n_in, n), (n_in,), (n_in,))
        self.data = np.zeros(sum(math.prod(shape) for shape in shapes))  # one buffer: one finiteness check
        self.H, self.g, self.A, self.b, self.C, self.lower, self.upper = _views(self.data, shapes)
        self.chunks = [self.data[i:i + FINITE_CHUNK] for i in range(0, len(self.data), FINITE_CHUNK)]
        self.torque_rows = self.C[n_free:]
        self.torque_lower, self.torque_upper = self.lower[n_free:], self.upper[n_free:]
        self.hessian_block, self.gradient_block = self.H[:nv, :nv], self.g[:nv]
        self.base_dynamics, self.base_rhs = self.A[:nu, :nv], self.b[:nu]
        self.torque_acceleration = self.torque_rows[:, :nv]
        self.passivity_row = self.C[n_free - 1] if passivity_row else None
        self.full = (self.H, self.g, self.A, self.b, self.C, self.lower, self.upper)
        self.without_limits = (self.H, self.g, self.A, self.b, self.C[:n_free], self.lower[:n_free],
                               self.upper[:n_free])
        self.free = WarmStartedQP(n, n_eq, n_free, qp.eps_abs, qp.max_iterations, qp.rho)
        self.limited: WarmStartedQP | None = None  # made at the first tick a torque limit binds
        self.free_rows_changed = True  # the rows without the torque limits changed since the free solve
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
            self.limited = WarmStartedQP(self.n, len(self.b), len(self.lower), qp.eps_abs, qp.max_iterations, qp.rho)
        return self.limited


def _views(buffer: np.ndarray, shapes: tuple[tuple[int, ...], ...]) -> list[np.ndarray]:
    """Consecutive C-contiguous views of ``buffer`` with the given shapes."""
    views, start = [], 0
    for shape in shapes:
        size = math.prod(shape)
        views.append(buffer[start:start + size].reshape(shape))
        start += size
    return views


class InverseDynamicsQP:
    """Builds and solves the QP for a robot with ``nv`` velocities, the first ``n_unactuated``
    of them unactuated (6 for a free-flyer base), and torque limits ``effort_limit``.

    One :class:`Workspace` per set of active contacts (the problem's size), its matrices filled
    in place; one :class:`TaskRows` per list of task sizes and set of steady tasks.
    """

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, *, eps_abs: float = DEFAULT_EPS_ABS,
                 max_iterations: int = 1000, acceleration_weight: float = 1e-6, rho: float = PROXIMAL_RHO):
        self.nv, self.nu = nv, n_unactuated
        self.na = nv - n_unactuated
        self.effort_limit = np.asarray(effort_limit, dtype=float)
        self._negative_limit = -self.effort_limit
        self._regularisation = np.diag(np.full(nv, 2.0 * acceleration_weight))  # eps ||a||^2
        self.eps_abs, self.max_iterations, self.rho = eps_abs, max_iterations, rho
        self.acceleration_weight = acceleration_weight
        self._workspaces: dict[tuple[object, ...], Workspace] = {}
        self._task_rows: dict[tuple[tuple[int, ...], tuple[bool, ...]], TaskRows] = {}
        self._previous_tasks: list[tuple[object, object]] = []  # each task's matrix and weights at the last tick
        self._steady: tuple[bool, ...] = ()
        self._tasks_tick: int | None = None

    # -- assembly ----------------------------------------------------------------------------
    def workspace(self, contacts: list[ContactConstraint], passivity_row: bool) -> Workspace:
        """The workspace of this set of active contacts (by name and size)."""
        key = (passivity_row, *((c.name, c.n_forces, len(c.friction_lower), len(c.motion_rhs)) for c in contacts))
        ws = self._workspaces.get(key)
        if ws is None:
            ws = self._workspaces[key] = Workspace(self, contacts, passivity_row)
        return ws

    def task_rows(self, tasks: list[TaskEquation], tick: int | None = None) -> TaskRows:
        """The stacked rows for this list of task sizes and this tick's steady tasks: those whose
        matrix and weights are the same arrays as at the previous tick (or, without a tick, the
        previous call); further calls in the same tick keep the tick's first answer."""
        if tick is None or tick != self._tasks_tick:
            previous = self._previous_tasks
            arrays = [(task.matrix, task.weight) for task in tasks]
            self._steady = tuple([a[0] is b[0] and a[1] is b[1] for a, b in zip(arrays, previous, strict=True)]) \
                if len(previous) == len(arrays) else (False,) * len(arrays)
            self._previous_tasks, self._tasks_tick = arrays, tick
        steady = self._steady if len(self._steady) == len(tasks) else (False,) * len(tasks)
        key = (tuple([len(task.vector) for task in tasks]), steady)
        rows = self._task_rows.get(key)
        if rows is None:
            rows = self._task_rows[key] = TaskRows(*key, self.nv)
        return rows

    def assemble(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, tasks: list[TaskEquation],
                 contacts: list[ContactConstraint], passivity: Passivity | None = None,
                 tick: int | None = None, torque_bounds: bool = True) -> Workspace:
        """Fill the workspace for this tick's problem (see the module docstring); a task whose
        rows do not fit its block, or whose weights are negative, raises :class:`TaskRowsError`.
        ``torque_bounds=False`` leaves the bounds of the torque rows (:meth:`write_torque_bounds`)
        for the ticks that need them."""
        scale = 1.0 if passivity is None else passivity.scale
        bounded = passivity is not None and passivity.power_bound is not None
        ws = self.workspace(contacts, bounded)
        rows = self.task_rows(tasks, tick)
        rows.write(tasks)
        rows.cost(scale, self._regularisation, ws.hessian_block, ws.gradient_block)
        nu = self.nu
        ws.base_dynamics[...] = mass_matrix[:nu]  # dynamics (floating-base rows) and torque rows share [M, -J_c^T T]
        np.negative(bias_forces[:nu], out=ws.base_rhs)
        ws.torque_acceleration[...] = mass_matrix[nu:]
        if torque_bounds:
            self.write_torque_bounds(ws, bias_forces)
        for contact, block in zip(contacts, ws.blocks, strict=True):
            if block.write(contact, scale):
                ws.free_rows_changed = True
        if bounded:
            self._write_passivity_row(ws, passivity, bias_forces)
            ws.free_rows_changed = True
        return ws

    def write_torque_bounds(self, ws: Workspace, bias_forces: np.ndarray) -> None:
        """``tau_min - h_j <= (torque rows) x <= tau_max - h_j``, within ``+-INFINITY`` (ProxQP's
        "no bound": a model without a limit on a joint). ``h_j`` must be finite."""
        np.subtract(self._negative_limit, bias_forces[self.nu:], out=ws.torque_lower)
        np.subtract(self.effort_limit, bias_forces[self.nu:], out=ws.torque_upper)
        np.clip(ws.torque_lower, -INFINITY, INFINITY, out=ws.torque_lower)
        np.clip(ws.torque_upper, -INFINITY, INFINITY, out=ws.torque_upper)

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
        ws = self.assemble(mass_matrix, bias_forces, tasks, contacts, passivity, tick, torque_bounds=False)
        if not self._finite(ws):  # h_j, which only the torques and their bounds see, is checked with the torques
            return self._failed(NOT_FINITE, 0, contacts, start)
        status, iterations = ws.free.solve(ws.without_limits, tick, same_inequalities=not ws.free_rows_changed)
        ws.free_rows_changed = False
        limited = False
        if status == SOLVED:
            tau = self._torques(ws, ws.free.latest[0], bias_forces)
            excess = self._excess(ws, tau)
            if excess != excess:  # NaN: h_j is not finite
                return self._failed(NOT_FINITE, iterations, contacts, start)
            limited = excess > self.eps_abs
            if limited:
                status, more = self._solve_with_limits(ws, bias_forces, tick)
                iterations += more
                if status == SOLVED:
                    tau = self._torques(ws, ws.limited.latest[0], bias_forces)
        if status != SOLVED:
            return self._failed(status, iterations, contacts, start)
        x = (ws.limited if limited else ws.free).latest[0].copy()
        return QPSolution(x[:self.nv], tau, self._split_forces(x, contacts), SOLVED, iterations,
                          time.perf_counter() - start, contacts, torque_limited=limited)

    def _finite(self, ws: Workspace) -> bool:
        """Whether the problem is finite: a NaN or inf makes the squared norm of its buffer
        non-finite (the "no bound" of +-INFINITY squares to 1e40, far below overflow). Summed
        over chunks of ``FINITE_CHUNK`` numbers: OpenBLAS runs a longer dot product on several
        threads, which on a busy 2-vCPU machine stalled ticks for milliseconds."""
        total = 0.0
        for chunk in ws.chunks:
            total += np.vdot(chunk, chunk)
        return math.isfinite(total)

    def _torques(self, ws: Workspace, x: np.ndarray, bias_forces: np.ndarray) -> np.ndarray:
        """``tau = (torque rows) x + h_j`` (the torque rows are ``[M_j, -(J^T T)_j]``)."""
        tau = np.dot(ws.torque_rows, x)
        tau += bias_forces[self.nu:]
        return tau

    def _excess(self, ws: Workspace, tau: np.ndarray) -> float:
        """``max_j |tau_j| - tau_max,j``: positive when a limit is exceeded, NaN when ``tau`` has a NaN."""
        excess = ws.tau_excess
        np.abs(tau, out=excess)
        excess -= self.effort_limit
        return float(_largest(excess))

    def _solve_with_limits(self, ws: Workspace, bias_forces: np.ndarray, tick: int | None) -> tuple[int, int]:
        """The QP with its torque rows, from this tick's answer without them (not written at all
        when ``h_j`` is not finite: bounds of inf in the buffer would fail every later tick)."""
        bias = bias_forces[self.nu:]
        if not math.isfinite(np.vdot(bias, bias)):
            return NOT_FINITE, 0
        self.write_torque_bounds(ws, bias_forces)
        return ws.limited_qp(self).solve(ws.full, tick, start=ws.free.latest)

    def _failed(self, status: int, iterations: int, contacts: list[ContactConstraint], start: float) -> QPSolution:
        return QPSolution(np.zeros(self.nv), None, [np.zeros(c.n_forces) for c in contacts], status, iterations,
                          time.perf_counter() - start, contacts=contacts)

    def _split_forces(self, x: np.ndarray, contacts: list[ContactConstraint]) -> list[np.ndarray]:
        forces, col = [], self.nv
        for contact in contacts:
            forces.append(x[col:col + contact.n_forces])
            col += contact.n_forces
        return forces
