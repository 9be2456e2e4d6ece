"""The weighted inverse-dynamics QP (thesis Eq. 4.14), assembled in one pass into preallocated
buffers and solved by ProxQP.

Variables ``x = [a, f]``: generalized accelerations ``a`` (nv) and the force variables ``f``
of the active contacts. Torques are not variables: the actuated rows of the dynamics give
them back, ``tau = M_j a + h_j - (J_c^T T)_j f`` (thesis Eq. 2.4), so the QP keeps only the
``n_u`` unactuated (floating-base) rows as equalities (the constraint rows are
:class:`~dgraph.control.inverse_dynamics.constraints.ConstraintRows`; the task part of the
cost, :class:`~dgraph.control.inverse_dynamics.task_rows.TaskRows`). ``bench/id_formulations.py`` compares
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
``H_aa = (sqrt(2 W) A)^T (sqrt(2 W) A)``, instead of one product per task. The problem
``(H, g, A, b, C, l, u)`` of one set of active contacts lives in one buffer (one finiteness
check); nothing is allocated in steady state (``tests/entities/test_inverse_dynamics.py``
counts it with ``tracemalloc``).

**Torque limits only when one binds**: the QP is first solved without the ``n_a`` torque-limit
rows (66 inequalities become 34 for TALOS on two feet: a quarter of the solve time). If the
torques it gives respect every limit (to ``eps_abs``), that answer is also the optimum with
the limits (adding constraints that the optimum satisfies does not move it); otherwise the QP
is solved again with them (``QPSolution.torque_limited``).
"""

from __future__ import annotations

import math
import time

import numpy as np

from dgraph.control.contact import ContactConstraint
from dgraph.control.equation import TaskEquation
from dgraph.control.inverse_dynamics.constraints import ConstraintRows
from dgraph.control.inverse_dynamics.task_rows import TaskRows
from dgraph.control.passivity import Passivity
from dgraph.control.proxqp import INFINITY, WarmStartedQP
from dgraph.control.solutions import QPSolution
from dgraph.control.status import NOT_FINITE, SOLVED, Status

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
FINITE_CHUNK = 8192
"""Numbers per dot product of the finiteness check: OpenBLAS uses one thread up to 10,000."""
_largest = np.maximum.reduce
"""The largest entry of an array, NaN if one is NaN (the ufunc itself: ``ndarray.max`` adds
microseconds of wrapping)."""


class ForceCost:
    """One active contact's part of the cost: ``w_c ||f_c - s f*_c||^2_{M_c}``, i.e. ``2 w_c M_c``
    in its block of ``H`` and ``-2 w_c s M_c f*_c`` in its part of ``g`` (views, made once)."""

    def __init__(self, hessian: np.ndarray, gradient: np.ndarray, columns: slice, contact: ContactConstraint):
        self.hessian = hessian[columns, columns]
        self.gradient = gradient[columns]
        self.reference_metric: np.ndarray | None = None  # -2 w_c M, when the contact has a metric
        self.has_reference = False  # a force reference was written into the gradient
        self.written: tuple[object, ...] = ()  # the constant values last written
        self.write_constant(contact)

    def write_constant(self, contact: ContactConstraint) -> None:
        """The regularisation ``2 w_c M_c`` (constant: written again only when the contact hands
        over another weight or metric)."""
        metric = contact.metric()
        np.multiply(metric, 2.0 * contact.force_weight, out=self.hessian)
        self.reference_metric = None if contact.force_metric is None else -2.0 * contact.force_weight * metric
        self.written = (contact.force_weight, contact.force_metric)

    def write(self, contact: ContactConstraint, scale: float) -> None:
        """The force reference ``-2 w_c s M_c f*_c`` into the gradient (and the constant part
        again if the contact hands over another weight or metric: it is in ``H``, which ProxQP
        gets every tick, so no row is marked changed)."""
        if contact.force_weight != self.written[0] or contact.force_metric is not self.written[1]:
            self.write_constant(contact)
        if contact.force_reference is not None:  # -2 w_c s M f*
            if self.reference_metric is None:
                np.multiply(contact.force_reference, -2.0 * contact.force_weight * scale, out=self.gradient)
            else:
                np.dot(self.reference_metric, contact.force_reference, out=self.gradient)
                self.gradient *= scale
            self.has_reference = True
        elif self.has_reference:
            self.gradient.fill(0.0)
            self.has_reference = False


class Workspace:
    """The problem for one set of active contacts (with or without a passivity row): its
    :class:`ConstraintRows` and cost, in one buffer, the two ProxQP problems over them (without
    and with the torque-limit rows) and views of their blocks.

    ``C`` stacks the contacts' friction rows, the passivity row (if any) and the ``n_a``
    torque rows (``torque_rows``, last); ``free`` solves without the torque rows. The friction
    rows, their bounds and the force regularisation do not change from tick to tick: they are
    written when the workspace is made, or again when a contact hands over different arrays.
    The passivity row, when there is one, is the last row before the torque rows.
    """

    def __init__(self, qp: InverseDynamicsQP, contacts: list[ContactConstraint], passivity_row: bool):
        nv, n_unactuated = qp.nv, qp.n_unactuated
        n = nv + sum(c.n_forces for c in contacts)
        cost = n * n + n
        size = cost + ConstraintRows.size(nv, n_unactuated, contacts, passivity_row)
        self.data = np.zeros(size)  # one block: one finiteness check
        self.H, self.g = self.data[:n * n].reshape(n, n), self.data[n * n:cost]
        self.rows = rows = ConstraintRows(nv, n_unactuated, qp.effort_limit, contacts, passivity_row,
                                          memory=self.data[cost:])
        self.A, self.b, self.C, self.lower, self.upper = rows.A, rows.b, rows.C, rows.lower, rows.upper
        self.n, self.n_free, self.torque_rows = n, rows.n_free, rows.torque_rows
        self.chunks = [self.data[i:i + FINITE_CHUNK] for i in range(0, len(self.data), FINITE_CHUNK)]
        self.hessian_block, self.gradient_block = self.H[:nv, :nv], self.g[:nv]
        self.passivity_row = self.C[rows.n_free - 1] if passivity_row else None
        self.full = (self.H, self.g, self.A, self.b, self.C, self.lower, self.upper)
        free = slice(0, rows.n_free)
        self.without_limits = (self.H, self.g, self.A, self.b, self.C[free], self.lower[free], self.upper[free])
        self.free = WarmStartedQP(n, len(self.b), rows.n_free, eps_abs=qp.eps_abs, max_iterations=qp.max_iterations,
                                  rho=qp.rho)
        self.limited: WarmStartedQP | None = None  # made at the first tick a torque limit binds
        self.free_rows_changed = True  # the rows without the torque limits changed since the free solve
        self.forces = [ForceCost(self.H, self.g, block.columns, contact)
                       for block, contact in zip(rows.contacts, contacts, strict=True)]
        self.tau_excess = np.zeros(qp.n_actuated)

    def limited_qp(self, qp: InverseDynamicsQP) -> WarmStartedQP:
        """The problem with the torque rows (made on first use)."""
        if self.limited is None:
            self.limited = WarmStartedQP(self.n, len(self.b), len(self.lower), eps_abs=qp.eps_abs,
                                         max_iterations=qp.max_iterations, rho=qp.rho)
        return self.limited


class InverseDynamicsQP:
    """Builds and solves the QP for a robot with ``nv`` velocities, the first ``n_unactuated``
    of them unactuated (6 for a free-flyer base), and torque limits ``effort_limit``.

    One :class:`Workspace` per set of active contacts (the problem's size), its matrices filled
    in place; one :class:`TaskRows` per list of task sizes and set of steady tasks.
    """

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, *, eps_abs: float = DEFAULT_EPS_ABS,
                 max_iterations: int = 1000, acceleration_weight: float = 1e-6, rho: float = PROXIMAL_RHO):
        self.nv, self.n_unactuated = nv, n_unactuated
        self.n_actuated = nv - n_unactuated
        self.effort_limit = np.asarray(effort_limit, dtype=float)
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
        key = (passivity_row, *ConstraintRows.key(contacts))
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
        rows do not fit its block, or whose weights are negative, raises
        :class:`~dgraph.control.inverse_dynamics.task_rows.TaskRowsError`. ``torque_bounds=False``
        leaves the bounds of the torque rows (:meth:`ConstraintRows.write_torque_bounds`) for the
        ticks that need them."""
        scale = 1.0 if passivity is None else passivity.scale
        bounded = passivity is not None and passivity.power_bound is not None
        ws = self.workspace(contacts, bounded)
        task_rows = self.task_rows(tasks, tick)
        task_rows.write(tasks)
        task_rows.cost(scale, self._regularisation, ws.hessian_block, ws.gradient_block)
        if ws.rows.write(mass_matrix, bias_forces, contacts):
            ws.free_rows_changed = True
        if torque_bounds:
            ws.rows.write_torque_bounds(bias_forces)
        for contact, cost in zip(contacts, ws.forces, strict=True):
            cost.write(contact, scale)
        if bounded:
            self._write_passivity_row(ws, passivity, bias_forces)
            ws.free_rows_changed = True
        return ws

    def _write_passivity_row(self, ws: Workspace, passivity: Passivity, bias_forces: np.ndarray) -> None:
        """``-v_j^T tau >= H_dot`` with ``tau = (torque rows) x + h_j``, divided by the row's norm
        (the preconditioner is kept from the first solve: a row whose scale follows ``|v|`` would
        drift out of it). A zero row (``v ~ 0``) holds for every ``x`` up to rounding and is
        dropped (a bound out of reach is caught before: :meth:`reaches`)."""
        velocity = passivity.velocity[self.n_unactuated:]
        row = ws.passivity_row
        np.matmul(velocity, ws.torque_rows, out=row)
        np.negative(row, out=row)
        bound = passivity.power_bound + velocity @ bias_forces[self.n_unactuated:]
        norm = math.sqrt(row @ row)
        index = ws.n_free - 1
        if norm > 1e-12:
            row /= norm
            ws.lower[index] = bound / norm
        else:  # v ~ 0: -v_j^T tau ~ 0 for every tau, and H_dot is rounding noise (the caller relaxes larger ones)
            row[:] = 0.0
            ws.lower[index] = -INFINITY
        ws.upper[index] = INFINITY

    def reaches(self, passivity: Passivity) -> bool:
        """Whether some torque within the limits delivers ``-v_j^T tau >= H_dot`` (at most
        ``sum |v_j| tau_max``; a necessary condition, to within ``POWER_TOLERANCE``)."""
        if passivity.power_bound is None:
            return True
        largest = float(np.abs(passivity.velocity[self.n_unactuated:]) @ self.effort_limit)
        return passivity.power_bound <= largest + POWER_TOLERANCE

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
            tau = ws.rows.torques(ws.free.latest[0], bias_forces)
            excess = self._excess(ws, tau)
            if excess != excess:  # NaN: h_j is not finite
                return self._failed(NOT_FINITE, iterations, contacts, start)
            limited = excess > self.eps_abs
            if limited:
                status, more = self._solve_with_limits(ws, bias_forces, tick)
                iterations += more
                if status == SOLVED:
                    tau = ws.rows.torques(ws.limited.latest[0], bias_forces)
        if status != SOLVED:
            return self._failed(status, iterations, contacts, start)
        x = (ws.limited if limited else ws.free).latest[0].copy()
        return QPSolution(x[:self.nv], tau, ws.rows.forces(x), SOLVED, iterations,
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

    def _excess(self, ws: Workspace, tau: np.ndarray) -> float:
        """``max_j |tau_j| - tau_max,j``: positive when a limit is exceeded, NaN when ``tau`` has a NaN."""
        excess = ws.tau_excess
        np.abs(tau, out=excess)
        excess -= self.effort_limit
        return float(_largest(excess))

    def _solve_with_limits(self, ws: Workspace, bias_forces: np.ndarray, tick: int | None) -> tuple[Status, int]:
        """The QP with its torque rows, from this tick's answer without them (not written at all
        when ``h_j`` is not finite: bounds of inf in the buffer would fail every later tick)."""
        bias = bias_forces[self.n_unactuated:]
        if not math.isfinite(np.vdot(bias, bias)):
            return NOT_FINITE, 0
        ws.rows.write_torque_bounds(bias_forces)
        return ws.limited_qp(self).solve(ws.full, tick, start=ws.free.latest)

    def _failed(self, status: Status, iterations: int, contacts: list[ContactConstraint], start: float) -> QPSolution:
        return QPSolution(np.zeros(self.nv), None, [np.zeros(c.n_forces) for c in contacts], status, iterations,
                          time.perf_counter() - start, contacts=contacts)
