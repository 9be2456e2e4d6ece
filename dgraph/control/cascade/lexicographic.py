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
minimum-norm least-squares step, from the same QR: :mod:`~dgraph.control.cascade.elimination`).
When that point satisfies every kept inequality and the level's own, it is optimal (the cost
cannot be lower than the unconstrained least squares with zero slack). Otherwise two exact
closed-form algorithms are tried (:mod:`~dgraph.control.cascade.active_set`: the violated rows
pinned within the optimal set of the least squares, then a primal active set with a sign check
of the multipliers): a joint on its limit that a lower level pushes against needs no QP. When
both fail (an own row needing slack, cycling), the level is a ProxQP problem in ``(z, s)``
(:mod:`~dgraph.control.cascade.level_qp`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from dgraph.control.cascade.active_set import ActiveSet
from dgraph.control.cascade.elimination import least_squares
from dgraph.control.cascade.kept_rows import KeptRows, own_rows_hold
from dgraph.control.cascade.level_qp import LevelQP
from dgraph.control.rows import RowBlock
from dgraph.control.solutions import CascadeSolution
from dgraph.control.status import NOT_FINITE, SOLVED, Status


class LexicographicCascade:
    """Solves a stack of :class:`~dgraph.control.rows.RowBlock` levels (highest priority first);
    see the module docstring.

    ``eps_abs`` and ``max_iterations`` are ProxQP's (1e-8: its answer is then polished on its
    active set, exact to rounding; at 1e-9 ProxQP sometimes stalls just above the tolerance);
    ``rank_tolerance``: diagonal entries of the pivoted QR factor of ``(A_k Z)^T`` below
    ``rank_tolerance * max(1, |R_11|)`` count as zero (those directions stay free for the levels
    below); ``feasibility_tolerance``: how far a closed-form step may violate an inequality and
    still be accepted; ``pin_tolerance``: the violation above which a row counts as violated at
    its level's optimum and is pinned (below it, a row at its bound could be a ProxQP rounding of
    an active row, which must not be pinned); ``closed_form`` false sends every level with rows
    to ProxQP (for tests and benchmarks); ``active_set_iterations``: the closed-form active set's
    limit of pinning rounds and of working sets before ProxQP takes the level.
    """

    def __init__(self, *, eps_abs: float = 1e-8, max_iterations: int = 1000, rank_tolerance: float = 1e-9,
                 feasibility_tolerance: float = 1e-9, pin_tolerance: float = 1e-6, closed_form: bool = True,
                 active_set_iterations: int = 20):
        self.pin_tolerance = pin_tolerance
        self.rank_tolerance, self.feasibility_tolerance = rank_tolerance, feasibility_tolerance
        self.closed_form = closed_form
        self._active_set = ActiveSet(rank_tolerance, feasibility_tolerance, active_set_iterations)
        self._level_qp = LevelQP(eps_abs, max_iterations, rank_tolerance, feasibility_tolerance)

    def solve(self, levels: Sequence[RowBlock], n: int, tick: int | None = None) -> CascadeSolution:
        """Solve ``levels`` over ``n`` variables (a level without rows is skipped); never raises on
        a numerical failure.

        ``tick`` selects the warm start: the answers of the latest earlier tick, so solving
        twice at the same tick gives the same answer.
        """
        start = time.perf_counter()
        if not all(level.is_valid() for level in levels):
            return self._failure(levels, n, NOT_FINITE, 0, 0, start)
        x, basis, kept = np.zeros(n), np.eye(n), KeptRows()
        iterations = qp_levels = 0
        for index, level in enumerate(levels):
            if basis.shape[1] == 0:
                break
            if not len(level.equality_vector) and not len(level.lower):
                continue
            equalities = level.equality_matrix
            step, free = least_squares(equalities, level.equality_vector - equalities @ x, basis, self.rank_tolerance)
            candidate = self._closed_form(level, x, basis, x + step, free, kept)
            if candidate is None:
                key = (tuple(lv.key for lv in levels[:index + 1]), basis.shape[1])
                status, its, candidate = self._level_qp.solve(key, level, x, basis, kept, tick)
                iterations, qp_levels = iterations + its, qp_levels + 1
                if status != SOLVED:  # keep what the levels above reached (they all still hold)
                    return self._failure(levels, n, status, iterations, qp_levels, start, x)
            x = candidate
            pinned = kept.add(level, x, self.pin_tolerance)
            basis = free if pinned is None else least_squares(pinned, np.zeros(len(pinned)), free,
                                                              self.rank_tolerance)[1]
        return CascadeSolution(x, SOLVED, iterations, qp_levels, time.perf_counter() - start, levels)

    def _closed_form(self, level: RowBlock, x: np.ndarray, basis: np.ndarray, candidate: np.ndarray,
                     free: np.ndarray, kept: KeptRows) -> np.ndarray | None:
        """The level's optimum without ProxQP: its least-squares step ``candidate`` when that
        meets every row, else the active set's answer; ``None``: ProxQP takes the level."""
        if not self.closed_form:
            return None
        tolerance = self.feasibility_tolerance
        if own_rows_hold(level, candidate, tolerance) and kept.hold(candidate, tolerance):
            return candidate
        return self._active_set.solve(level, x, basis, candidate, free, kept)

    def _failure(self, levels: Sequence[RowBlock], n: int, status: Status, iterations: int, qp_levels: int,
                 start: float, x: np.ndarray | None = None) -> CascadeSolution:
        """``status`` with the solution of the levels above the failed one (zeros when the data
        is not finite); every warm start is dropped (the next tick starts cold)."""
        self._level_qp.forget()
        x = np.zeros(n) if x is None else x
        return CascadeSolution(x, status, iterations, qp_levels, time.perf_counter() - start, levels)
