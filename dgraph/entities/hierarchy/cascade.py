"""The lexicographic cascade: strict-priority least squares with equalities and inequalities.

Levels ``1 ≺ 2 ≺ … ≺ N`` over variables ``x`` (n). Level ``k`` is solved after every level
above it has been fixed at its optimum (thesis Eq. 4.4; Saab et al., thesis Eq. 2.59):

```
(r_k*, s_k*) = argmin_{x, s} ||A_k x - b_k||^2 + ||s||^2
               s.t.  l_k <= C_k x - s <= u_k                    this level's inequalities, relaxed by s
                     A_j x - b_j = r_j*                         every level j above: equalities at their
                     l_j <= C_j x - s_j* <= u_j                 optimal residual, inequalities at their
                                                                optimal slack
```

Both ``r_k* = A_k x* - b_k`` and ``s_k*`` are unique (the cost is strictly convex in them), so
"keep level j optimal" is the same as the two constraints above. How they are kept:

- equalities by **elimination**: ``x = x_{k-1} + Z_{k-1} z`` where ``x_{k-1}`` solves the levels
  above and the orthonormal columns of ``Z_{k-1}`` span the null space of their stacked equality
  matrices; ``Z_k = Z_{k-1} V_0`` with ``V_0`` the null space of ``A_k Z_{k-1}`` (pivoted QR).
  A level whose free space is empty is not solved: it cannot change ``x`` any more;
- inequalities by **their optimal slack**: ``s_j*`` is unique, so a row violated at level j's
  optimum (by more than ``pin_tolerance``) keeps exactly that violation below: it is
  **pinned**, ``C_j,i x = C_j,i x_j``, and eliminated like an equality (a pinned pair of
  conflicting rows would otherwise be a degenerate implicit equality for ProxQP). A row that holds is kept as
  ``min(l_j, C_j x_j) <= C_j x <= max(u_j, C_j x_j)`` (its bounds, widened by the tolerance
  the levels solved since may have used, so that ``x`` stays feasible: no drift).

Each level is first solved in closed form, ``z = (A_k Z)^+ (b_k - A_k x_{k-1})`` (the
minimum-norm least-squares step, from the same QR). When that point satisfies every kept
inequality and the level's own, it is optimal (the cost cannot be lower than the
unconstrained least squares with zero slack). Otherwise a closed-form active set is tried
(:meth:`LexicographicCascade._active_set`: the violated rows pinned within the optimal set of
the least squares, then a primal active set with a sign check of the multipliers; exact, at
most ``active_set_iterations`` working sets): a joint on its limit that a lower level pushes
against needs no QP. When that fails (an own row needing slack, cycling), the level is a
ProxQP problem in ``(z, s)``, with no equality row:

```
min  ||A_k Z z - (b_k - A_k x_{k-1})||^2 + ||s||^2
s.t. min(l_j, C_j x_j) - C_j x_{k-1} <= C_j Z z <= max(u_j, C_j x_j) - C_j x_{k-1}      j < k
     l_k - C_k x_{k-1} <= C_k Z z - s <= u_k - C_k x_{k-1}
```

One ProxQP dense object is kept per structure (the keys of the levels down to this one, the
free dimension and the number of kept rows that can still move), warm-started with the latest
earlier tick's answer of the same structure mapped into the current basis
(``z = Z^T (x_prev_tick - x_{k-1})``) and its multipliers.
"""

from __future__ import annotations

import math
import time
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, field

import numpy as np
import proxsuite
from scipy.linalg import lapack

from dgraph.entities.solvers.inverse_dynamics_qp import INFINITY, NOT_FINITE, SOLVED, proxqp_status
from dgraph.signals.value_types import value_type


@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class Level:
    """One priority level: ``A x = b`` (``m_e`` rows) and ``l <= C x <= u`` (``m_i`` rows).

    ``key`` names the level's structure (which tasks, how many rows): two levels with the same
    key at the same place in the stack share a ProxQP workspace and its warm start.
    """

    key: Hashable
    equality_matrix: np.ndarray
    equality_vector: np.ndarray
    inequality_matrix: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    def residual(self, x: np.ndarray) -> float:
        """``sqrt(||A x - b||^2 + ||s||^2)`` with ``s`` the inequality violation at ``x``."""
        equality = self.equality_matrix @ x - self.equality_vector
        values = self.inequality_matrix @ x
        violation = values - np.clip(values, self.lower, self.upper)
        return math.sqrt(float(equality @ equality + violation @ violation))

    def is_valid(self) -> bool:
        """Finite matrices and equality targets, bounds without NaN and with ``l <= u``."""
        square = (np.vdot(self.equality_matrix, self.equality_matrix) + np.vdot(self.equality_vector,
                  self.equality_vector) + np.vdot(self.inequality_matrix, self.inequality_matrix))
        return math.isfinite(square) and bool((self.lower <= self.upper).all())


@value_type
@dataclass(slots=True)
class CascadeSolution:
    """The cascade's answer: ``x``, ``status`` (the codes of
    :mod:`~dgraph.entities.solvers.inverse_dynamics_qp`; ``NOT_FINITE`` also for crossed bounds
    ``l > u``; ``x`` is zeros unless ``SOLVED``), ``iterations`` (ProxQP, summed), ``qp_levels``
    (levels that needed ProxQP), ``solve_time`` (s), and the ``levels`` solved."""

    x: np.ndarray
    status: int
    iterations: int
    qp_levels: int
    solve_time: float
    levels: Sequence[Level]

    @property
    def residuals(self) -> np.ndarray:
        """One per level, :meth:`Level.residual` at ``x`` (inf for an invalid level); computed
        on request (the solve itself does not need them)."""
        return np.array([level.residual(self.x) if level.is_valid() else math.inf for level in self.levels])


@dataclass(slots=True)
class _Workspace:
    """A ProxQP object and its matrices for one level structure (see the module docstring)."""

    qp: object
    H: np.ndarray
    g: np.ndarray
    C: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    initialised: bool = False
    latest: tuple[np.ndarray, np.ndarray] | None = None  # last answer: x (full space), inequality multipliers
    guess: tuple[np.ndarray, np.ndarray] | None = None  # the warm start of this tick's solves
    tick: int | None = None  # the tick ``guess`` serves


@dataclass(slots=True)
class _Kept:
    """The relaxed inequalities of the levels already solved."""

    matrices: list[np.ndarray] = field(default_factory=list)
    lower: list[np.ndarray] = field(default_factory=list)
    upper: list[np.ndarray] = field(default_factory=list)
    cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # stacked(), until the next add

    def add(self, level: Level, x: np.ndarray, tolerance: float) -> np.ndarray | None:
        """Keep ``level``'s inequalities that hold at its optimum ``x`` (within ``tolerance``;
        relaxed to include their value there) and return the violated ones, which are pinned."""
        if not len(level.lower):
            return None
        values = level.inequality_matrix @ x
        violated = (values < level.lower - tolerance) | (values > level.upper + tolerance)
        holding = ~violated
        self.cache = None
        self.matrices.append(level.inequality_matrix[holding])
        self.lower.append(np.minimum(level.lower[holding], values[holding]))
        self.upper.append(np.maximum(level.upper[holding], values[holding]))
        return level.inequality_matrix[violated] if violated.any() else None

    def hold(self, x: np.ndarray, tolerance: float) -> bool:
        """Whether ``x`` satisfies every kept row within ``tolerance``."""
        for matrix, lower, upper in zip(self.matrices, self.lower, self.upper, strict=True):
            values = matrix @ x
            if (values < lower - tolerance).any() or (values > upper + tolerance).any():
                return False
        return True

    def stacked(self, columns: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """All kept rows as one ``(C, l, u)``."""
        if self.cache is None:
            self.cache = ((np.vstack(self.matrices), np.concatenate(self.lower), np.concatenate(self.upper))
                          if self.matrices else (np.zeros((0, columns)), np.zeros(0), np.zeros(0)))
        return self.cache


def _holds(level: Level, x: np.ndarray, tolerance: float) -> bool:
    """Whether ``x`` satisfies ``level``'s own inequalities within ``tolerance``."""
    if not len(level.lower):
        return True
    values = level.inequality_matrix @ x
    return not ((values < level.lower - tolerance).any() or (values > level.upper + tolerance).any())


def _level_cost(projected: np.ndarray, target: np.ndarray, own: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                z: np.ndarray) -> float:
    """``||A Z z - target||^2 + ||s||^2`` with ``s`` the violation of the level's own rows."""
    residual = projected @ z - target
    values = own @ z
    violation = values - np.clip(values, lower, upper)
    return float(residual @ residual + violation @ violation)


class LexicographicCascade:
    """Solves a stack of :class:`Level` (highest priority first); see the module docstring.

    ``eps_abs`` and ``max_iterations`` are ProxQP's (1e-8: its answer is then polished on its
    active set, exact to rounding; at 1e-9 ProxQP sometimes stalls just above the tolerance);
    ``rank_tolerance``: diagonal entries of the pivoted
    QR factor of ``(A_k Z)^T`` below ``rank_tolerance * max(1, |R_11|)`` count as zero (those directions stay
    free for the levels below); ``feasibility_tolerance``: how far a closed-form step may
    violate an inequality and still be accepted; ``pin_tolerance``: the violation above which
    a row counts as violated at its level's optimum and is pinned (below it, a row at its bound
    could be a ProxQP rounding of an active row, which must not be pinned); ``closed_form`` false sends every level with
    rows to ProxQP (for tests and benchmarks); ``active_set_iterations``: the closed-form active
    set's limit of pinning rounds and of working sets before ProxQP takes the level.
    """

    def __init__(self, *, eps_abs: float = 1e-8, max_iterations: int = 1000, rank_tolerance: float = 1e-9,
                 feasibility_tolerance: float = 1e-9, pin_tolerance: float = 1e-6, closed_form: bool = True,
                 active_set_iterations: int = 20):
        self.eps_abs, self.max_iterations = eps_abs, max_iterations
        self.active_set_iterations = active_set_iterations
        self.pin_tolerance = pin_tolerance
        self.rank_tolerance, self.feasibility_tolerance = rank_tolerance, feasibility_tolerance
        self.closed_form = closed_form
        self._workspaces: dict[Hashable, _Workspace] = {}

    def solve(self, levels: Sequence[Level], n: int, tick: int | None = None) -> CascadeSolution:
        """Solve ``levels`` over ``n`` variables; never raises on a numerical failure.

        ``tick`` selects the warm start: the answers of the latest earlier tick, so solving
        twice at the same tick gives the same answer.
        """
        start = time.perf_counter()
        if not all(level.is_valid() for level in levels):
            return self._failure(levels, n, NOT_FINITE, 0, 0, start)
        x, basis, kept = np.zeros(n), np.eye(n), _Kept()
        iterations = qp_levels = 0
        for index, level in enumerate(levels):
            if basis.shape[1] == 0:
                break
            if not len(level.equality_vector) and not len(level.lower):
                continue
            equalities = level.equality_matrix
            step, free = self._least_squares(equalities, level.equality_vector - equalities @ x, basis)
            candidate = x + step
            if self.closed_form and not (_holds(level, candidate, self.feasibility_tolerance)
                                         and kept.hold(candidate, self.feasibility_tolerance)):
                candidate = self._active_set(level, x, basis, candidate, free, kept)
            if candidate is None or not self.closed_form:
                key = (tuple(lv.key for lv in levels[:index + 1]), basis.shape[1])
                status, its, candidate = self._solve_qp(key, level, x, basis, kept, tick)
                iterations, qp_levels = iterations + its, qp_levels + 1
                if status != SOLVED:  # keep what the levels above reached (they all still hold)
                    return self._failure(levels, n, status, iterations, qp_levels, start, x)
            x = candidate
            pinned = kept.add(level, x, self.pin_tolerance)
            basis = free if pinned is None else self._least_squares(pinned, np.zeros(len(pinned)), free)[1]
        return CascadeSolution(x, SOLVED, iterations, qp_levels, time.perf_counter() - start, levels)

    def _least_squares(self, matrix: np.ndarray, target: np.ndarray,
                       basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The minimum-norm step ``Z z`` with ``z = argmin ||A Z z - target||``, and the basis
        of the directions that stay free below (orthonormal columns spanning ``Z null(A Z)``).

        A column-pivoted QR of ``(A_k Z)^T = Q R Pi^T`` (LAPACK ``dgeqp3``; an SVD costs 5 to 10
        times more at these sizes) splits ``Z Q`` into the row space of ``A_k Z`` (the first
        ``rank`` columns) and its null space; the step is ``Z Q_1 y`` with
        ``y = argmin ||R_1^T y - Pi^T (b_k - A_k x)||`` (full column rank: a triangular solve when
        the rows are independent, else ``dgels``).
        """
        n = basis.shape[0]
        if not len(target) or not basis.shape[1]:
            return np.zeros(n), basis
        projected = matrix @ basis
        qr, pivots, tau, _, _ = lapack.dgeqp3(projected.T)
        diagonal = np.abs(qr.diagonal())
        rank = int(np.count_nonzero(diagonal > self.rank_tolerance * max(1.0, diagonal[0] if len(diagonal) else 0.0)))
        rotated, _, _ = lapack.dormqr("R", "N", qr[:, :len(tau)], tau, basis, lwork=64 * n)
        if rank == 0:
            return np.zeros(n), rotated
        permuted = target[pivots - 1]
        if rank == len(target):  # independent rows (the usual case): R_1^T is square, triangular
            y, _ = lapack.dtrtrs(qr[:rank, :rank], permuted, trans=1)
        else:
            y = lapack.dgels(np.triu(qr[:rank]).T, permuted)[1][:rank]
        return rotated[:, :rank] @ y, rotated[:, rank:]

    def _min_norm(self, matrix: np.ndarray, target: np.ndarray) -> np.ndarray:
        """``argmin ||M y - t||`` of least norm (LAPACK ``dgelsy``: one complete orthogonal
        factorisation; for the steps that need no null-space basis)."""
        m, n = matrix.shape
        if not m or not n:
            return np.zeros(n)
        rhs = np.zeros((max(m, n), 1))
        rhs[:m, 0] = target
        small = min(m, n)
        _, y, _, _, _ = lapack.dgelsy(matrix, rhs, np.zeros(n, dtype=np.int32), self.rank_tolerance,
                                      max(small + 3 * n + 1, 2 * small + 1) + 64 * n)
        return y[:n, 0]

    def _pinned(self, matrix: np.ndarray, gap: np.ndarray, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`_least_squares` (the step meeting ``matrix step = gap`` in ``basis`` and the
        basis left), with one row by a Householder reflection of ``Z^T c``."""
        if len(gap) != 1:
            return self._least_squares(matrix, gap, basis)
        direction = basis.T @ matrix[0]
        norm = math.sqrt(float(direction @ direction))
        if norm <= self.rank_tolerance * max(1.0, float(np.abs(direction).max(initial=0.0))):
            return np.zeros(len(matrix[0])), basis
        step = basis @ (direction * (gap[0] / norm**2))
        direction[0] += math.copysign(norm, direction[0])  # H = I - 2 u u^T maps Z^T c onto e_0
        direction /= math.sqrt(float(direction @ direction))
        return step, (basis - 2.0 * np.outer(basis @ direction, direction))[:, 1:]

    def _movable(self, matrix: np.ndarray, basis: np.ndarray) -> np.ndarray:
        """Which rows ``basis`` can still move (``C Z != 0``; the others are fixed above and hold
        at ``x`` up to the tolerances of the levels between)."""
        return np.abs(matrix @ basis).max(axis=1, initial=0.0) > self.rank_tolerance * max(
            1.0, float(np.abs(matrix).max(initial=0.0)))

    def _active_set(self, level: Level, x: np.ndarray, basis: np.ndarray, candidate: np.ndarray, free: np.ndarray,
                    kept: _Kept) -> np.ndarray | None:
        """The level in closed form when its least-squares step ``candidate`` violates a row
        (kept or its own); ``None`` sends it to ProxQP. Two exact stages:

        1. the optimal set of the unconstrained least squares is ``candidate + range(free)``: the
           violated rows are pinned at their violated bound and the minimum-norm move in ``free``
           that meets them is taken (at most ``active_set_iterations`` rounds, each pinning the
           rows still violated). A point of that set meeting every row is optimal: its cost is the
           unconstrained minimum and its slack zero. This is the case of a bound that is active by
           construction (a joint on its limit that the tasks need not move: TALOS's grippers).
        2. otherwise a primal active set (Nocedal & Wright, Alg. 16.3) on the level with its own
           rows as hard constraints, from ``x`` (feasible for the kept rows): each working set is
           an equality-constrained least squares solved by elimination (the same pivoted QR), the
           step is cut at the first blocking row, which joins the working set; at a working-set
           optimum the multipliers (least squares on ``Z^T C_W^T lambda = -Z^T grad``) must have
           the sign of their bound, else the most wrong row leaves. It ends at a KKT point (the
           cost is convex) or after ``active_set_iterations`` working sets (degenerate cycling),
           then ProxQP. Its answer is the level's optimum only when its own rows need no slack:
           an own row with a nonzero multiplier, or an own row violated at ``x``, means ProxQP.
        """
        rows, lower, upper = kept.stacked(len(x))
        m_kept = len(lower)
        if len(level.lower):
            rows, lower = np.vstack([rows, level.inequality_matrix]), np.concatenate([lower, level.lower])
            upper = np.concatenate([upper, level.upper])
        tolerance, rounds = self.feasibility_tolerance, self.active_set_iterations
        bounds = np.zeros(len(lower))
        pinned = np.zeros(len(lower), dtype=bool)
        point = candidate
        for _ in range(rounds if free.shape[1] else 1):  # stage 1
            values = rows @ point
            below, above = values < lower - tolerance, values > upper + tolerance
            newly = below | above
            if not newly.any():
                return point
            newly &= ~pinned
            if not newly.any():
                break
            bounds[newly] = np.where(above[newly], upper[newly], lower[newly])
            pinned |= newly
            if not free.shape[1]:
                break
            matrix = rows[pinned]
            gap = bounds[pinned] - matrix @ candidate
            if len(gap) == 1:  # the usual case: one bound, w = N^T c d / |N^T c|^2
                direction = matrix[0] @ free
                square = float(direction @ direction)
                if square <= (self.rank_tolerance * max(1.0, float(np.abs(matrix).max()))) ** 2:
                    break  # the optimal set cannot move that row
                point = candidate + free @ (direction * (gap[0] / square))
            else:
                point = candidate + free @ self._min_norm(matrix @ free, gap)
        movable = np.ones(len(lower), dtype=bool)  # stage 2, on the rows that z can move
        movable[:m_kept] = self._movable(rows[:m_kept], basis)
        rows, lower, upper, bounds = rows[movable], lower[movable], upper[movable], bounds[movable]
        m_kept = int(np.count_nonzero(movable[:m_kept]))
        values = rows @ x
        if (values < lower - tolerance).any() or (values > upper + tolerance).any():
            return None
        matrix, target = level.equality_matrix, level.equality_vector
        working: list[int] = []
        point, optimum = x, candidate
        for _ in range(rounds):
            if working:
                active = np.array(working)
                shift, reduced = self._pinned(rows[active], bounds[active] - rows[active] @ point, basis)
                optimum = point + shift
                optimum = optimum + reduced @ self._min_norm(matrix @ reduced, target - matrix @ optimum)
            else:  # any minimiser of the unconstrained least squares will do
                optimum = candidate
            before, after = rows @ point, rows @ optimum
            outside = (after < lower - tolerance) | (after > upper + tolerance)
            outside[working] = False
            if outside.any():
                index = np.flatnonzero(outside)
                bound = np.where(after[index] > upper[index], upper[index], lower[index])
                change = after[index] - before[index]
                with np.errstate(divide="ignore", invalid="ignore"):
                    fraction = np.where(change != 0.0, (bound - before[index]) / change, 0.0)
                j = int(np.argmin(np.clip(fraction, 0.0, 1.0)))
                point = point + min(max(fraction[j], 0.0), 1.0) * (optimum - point)
                working.append(int(index[j]))
                bounds[index[j]] = bound[j]
                continue
            point = optimum
            if not working:
                return point
            active = np.array(working)
            gradient = basis.T @ (matrix.T @ (matrix @ point - target))
            normals = basis.T @ rows[active].T
            if len(active) == 1:
                multipliers = -(normals[:, 0] @ gradient) / (normals[:, 0] @ normals[:, 0]) * np.ones(1)
            else:
                multipliers = self._min_norm(normals, -gradient)
            sign = np.where(bounds[active] == upper[active], 1.0, -1.0)  # >= 0 at an upper bound
            signed = np.where(lower[active] == upper[active], np.inf, sign * multipliers)
            small = 1e-9 * max(1.0, float(np.abs(multipliers).max()))
            if signed.min() >= -small:
                if (np.abs(multipliers[active >= m_kept]) > small).any():
                    return None  # an own row pushes back: the optimum may need slack there
                return point
            working.pop(int(np.argmin(signed)))
        return None

    def _workspace(self, key: Hashable, n_qp: int, n_in: int, free: int) -> _Workspace:
        ws = self._workspaces.get(key)
        if ws is None:
            qp = proxsuite.proxqp.dense.QP(n_qp, 0, n_in)
            qp.settings.eps_abs = self.eps_abs
            qp.settings.eps_rel = 1e-9  # relative to the data (pulls of 1e3 m/s happen); then polished
            qp.settings.max_iter = self.max_iterations
            qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START
            # every level problem is feasible (z = 0 meets the kept rows, s absorbs its own) and
            # bounded (a least squares): ProxQP's default 1e-4 infeasibility tests gave false alarms
            qp.settings.eps_primal_inf = qp.settings.eps_dual_inf = 1e-12
            ws = _Workspace(qp, np.zeros((n_qp, n_qp)), np.zeros(n_qp), np.zeros((n_in, n_qp)), np.zeros(n_in),
                            np.zeros(n_in))
            slack = np.arange(free, n_qp)
            ws.H[slack, slack] = 2.0  # ||s||^2
            ws.C[np.arange(n_in - len(slack), n_in), slack] = -1.0  # C_k Z z - s
            self._workspaces[key] = ws
        return ws

    def _solve_qp(self, key: Hashable, level: Level, x: np.ndarray, basis: np.ndarray, kept: _Kept,
                  tick: int | None) -> tuple[int, int, np.ndarray]:
        """The level as a ProxQP problem in ``(z, s)``: ``(status, iterations, x)``."""
        free, m_own = basis.shape[1], len(level.lower)
        kept_matrix, kept_lower, kept_upper = kept.stacked(len(x))
        # a kept row that z cannot move (C Z = 0: its directions are fixed above) holds at z = 0 and
        # stays out: rows of 1e-16 wreck ProxQP's equilibration (false infeasibility reports)
        movable = self._movable(kept_matrix, basis)
        kept_matrix, kept_lower, kept_upper = kept_matrix[movable], kept_lower[movable], kept_upper[movable]
        m_kept = len(kept_lower)
        ws = self._workspace((*key, m_kept), free + m_own, m_kept + m_own, free)
        projected = level.equality_matrix @ basis
        ws.H[:free, :free] = 2.0 * projected.T @ projected
        ws.g[:free] = -2.0 * projected.T @ (level.equality_vector - level.equality_matrix @ x)
        for rows, matrix, lower, upper, widest in (
                (slice(0, m_kept), kept_matrix, kept_lower, kept_upper, 0.0),
                (slice(m_kept, None), level.inequality_matrix, level.lower, level.upper, -INFINITY)):
            ws.C[rows, :free] = matrix @ basis
            values = matrix @ x
            # kept rows hold at z = 0 (x satisfies them up to the tolerances of the levels between)
            ws.lower[rows] = np.clip(np.minimum(lower - values, -widest), -INFINITY, INFINITY)
            ws.upper[rows] = np.clip(np.maximum(upper - values, widest), -INFINITY, INFINITY)
        if tick is None or tick != ws.tick:
            ws.guess, ws.tick = ws.latest, tick
        status, iterations = self._run(ws, self._guess(ws, level, x, basis))
        if status != SOLVED:  # never a true infeasibility (see _workspace): once more, cold, for the
            status, more = self._closest_feasible(ws)  # closest feasible point, which is then the optimum
            iterations += more
        if status != SOLVED:
            ws.initialised = False
            return status, iterations, x
        target = level.equality_vector - level.equality_matrix @ x
        solution = x + basis @ self._polish(ws, projected, target, free, m_kept)
        ws.latest = (solution, ws.qp.results.z.copy())
        return status, iterations, solution

    def _closest_feasible(self, ws: _Workspace) -> tuple[int, int]:
        """A cold solve with ProxQP's ``primal_infeasibility_solving``: on a feasible problem
        that ProxQP wrongly calls infeasible (it happens on small degenerate levels, e.g. two
        variables and three rows meeting at the origin) its closest feasible point is the
        optimum, refined by :meth:`_polish` as any other answer."""
        settings = ws.qp.settings
        ws.initialised, settings.primal_infeasibility_solving = False, True
        try:
            status, iterations = self._run(ws, None)
            if ws.qp.results.info.status.name == "PROXQP_SOLVED_CLOSEST_PRIMAL_FEASIBLE" and \
                    np.isfinite(ws.qp.results.x).all():
                status = SOLVED
        finally:
            ws.initialised, settings.primal_infeasibility_solving = False, False
        return status, iterations

    def _polish(self, ws: _Workspace, projected: np.ndarray, target: np.ndarray, free: int, m_kept: int) -> np.ndarray:
        """ProxQP's ``z``, refined on its active set: the kept rows it stops at become equalities
        and the level's own rows it stops at (or beyond) join the least squares, solved exactly
        by the same QR elimination. ProxQP's answer is accurate to ``eps_abs`` in the KKT
        residuals, which a small ``C Z`` can turn into a visibly early stop (1e-6 short of a
        bound); the refined point is kept when it is feasible and no worse."""
        results = ws.qp.results
        z = results.x[:free]
        multipliers = results.z
        at_bound = np.where(multipliers > 0, ws.upper, ws.lower)
        active = np.abs(multipliers) > 1e-10 * max(1.0, float(np.abs(multipliers).max(initial=0.0)))
        kept_rows, own_rows = np.flatnonzero(active[:m_kept]), m_kept + np.flatnonzero(active[m_kept:])
        rows = ws.C[:, :free]
        base, null = self._least_squares(rows[kept_rows], at_bound[kept_rows], np.eye(free))
        objective = np.vstack([projected, rows[own_rows]])
        goal = np.concatenate([target, at_bound[own_rows]])
        refined = base + self._least_squares(objective, goal - objective @ base, null)[0]
        values = rows @ refined
        inactive_own = np.ones(len(values), dtype=bool)
        inactive_own[:m_kept] = False
        inactive_own[own_rows] = False
        must_hold = ~inactive_own
        must_hold[m_kept:] = inactive_own[m_kept:]
        tolerance = self.feasibility_tolerance
        feasible = ((values[must_hold] >= ws.lower[must_hold] - tolerance).all()
                    and (values[must_hold] <= ws.upper[must_hold] + tolerance).all())
        own = (projected, target, rows[m_kept:], ws.lower[m_kept:], ws.upper[m_kept:])
        found = _level_cost(*own, z)
        if feasible and _level_cost(*own, refined) <= found + 1e-9 * (1e-6 + found):  # rounding aside, no worse
            return refined
        return z

    @staticmethod
    def _guess(ws: _Workspace, level: Level, x: np.ndarray,
               basis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The warm start ``(z, s), y, multipliers`` mapped from the latest earlier answer."""
        if ws.guess is None:
            return None
        previous, multipliers = ws.guess
        z = basis.T @ (previous - x)
        values = level.inequality_matrix @ (x + basis @ z)
        slack = values - np.clip(values, level.lower, level.upper)
        return np.concatenate([z, slack]), np.zeros(0), multipliers

    def _run(self, ws: _Workspace, guess: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> tuple[int, int]:
        """ProxQP on the workspace, warm or cold: ``(status, iterations)``. The preconditioner
        is recomputed at every solve (the basis ``Z`` changes from tick to tick)."""
        qp = ws.qp
        if ws.initialised:
            qp.update(ws.H, ws.g, None, None, ws.C, ws.lower, ws.upper)
        else:
            qp.init(ws.H, ws.g, None, None, ws.C, ws.lower, ws.upper)
            ws.initialised = True
        if guess is None:
            qp.solve()
        else:
            qp.solve(*guess)
        return proxqp_status(qp.results), int(qp.results.info.iter)

    def _failure(self, levels: Sequence[Level], n: int, status: int, iterations: int, qp_levels: int,
                 start: float, x: np.ndarray | None = None) -> CascadeSolution:
        """``status`` with the solution of the levels above the failed one (zeros when the data
        is not finite); every warm start is dropped (the next tick starts cold)."""
        for ws in self._workspaces.values():
            ws.initialised, ws.latest, ws.guess = False, None, None
        x = np.zeros(n) if x is None else x
        return CascadeSolution(x, status, iterations, qp_levels, time.perf_counter() - start, levels)
