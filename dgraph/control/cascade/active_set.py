"""A level of the cascade in closed form when its least-squares step violates an inequality: two exact algorithms.

The cascade first takes a level's unconstrained least-squares step (its minimum-norm solution
``candidate``; ``free``: the directions that leave its cost unchanged). When that step violates
a row (kept from the levels above, or the level's own), :class:`ActiveSet` tries, in order:

1. **pinning in the optimal set** (:meth:`ActiveSet.pin_violated`): the optimal set of the
   unconstrained least squares is ``candidate + range(free)``; the violated rows are pinned at
   their violated bound and the minimum-norm move in ``free`` that meets them is taken (at most
   ``iterations`` rounds, each pinning the rows still violated). A point of that set meeting
   every row is optimal: its cost is the unconstrained minimum and its slack zero. This is the
   case of a bound that is active by construction (a joint on its limit that the tasks need not
   move: TALOS's grippers);
2. **a primal active set** (:meth:`ActiveSet.primal_active_set`; Nocedal & Wright, Alg. 16.3)
   on the level with its own rows as hard constraints, from ``x`` (feasible for the kept rows):
   each working set is an equality-constrained least squares solved by elimination, the step is
   cut at the first blocking row, which joins the working set; at a working-set optimum the
   multipliers (least squares on ``Z^T C_W^T lambda = -Z^T grad``) must have the sign of their
   bound, else the most wrong row leaves. It ends at a KKT point (the cost is convex) or after
   ``iterations`` working sets (degenerate cycling). Its answer is the level's optimum only when
   its own rows need no slack: an own row with a nonzero multiplier, or an own row violated at
   ``x``, means the level needs the QP with slack.

Either returns the level's optimum, or ``None``: the cascade then hands the level to ProxQP
(:mod:`~dgraph.control.cascade.level_qp`).
"""

from __future__ import annotations

import numpy as np

from dgraph.control.cascade.elimination import min_norm, movable, pinned_step
from dgraph.control.cascade.kept_rows import KeptRows
from dgraph.control.rows import RowBlock


class ActiveSet:
    """The two closed-form algorithms of the module docstring. ``rank_tolerance`` as the
    cascade's; ``feasibility_tolerance``: how far a point may violate a row and still be
    accepted; ``iterations``: the limit of pinning rounds and of working sets."""

    def __init__(self, rank_tolerance: float, feasibility_tolerance: float, iterations: int):
        self.rank_tolerance, self.feasibility_tolerance, self.iterations = (rank_tolerance, feasibility_tolerance,
                                                                            iterations)

    def solve(self, level: RowBlock, x: np.ndarray, basis: np.ndarray, candidate: np.ndarray, free: np.ndarray,
              kept: KeptRows) -> np.ndarray | None:
        """The level's optimum from the point ``x`` the levels above reached (free directions
        ``basis``), its least-squares step ``candidate`` (free directions below it ``free``) and
        the kept rows, or ``None`` (ProxQP takes the level)."""
        rows, lower, upper = kept.stacked(len(x))
        m_kept = len(lower)
        if len(level.lower):
            rows, lower = np.vstack([rows, level.inequality_matrix]), np.concatenate([lower, level.lower])
            upper = np.concatenate([upper, level.upper])
        point = self.pin_violated(rows, lower, upper, candidate, free)
        if point is not None:
            return point
        return self.primal_active_set(level, rows, lower, upper, m_kept, x, basis, candidate)

    # -- 1. pinning in the optimal set of the least squares --------------------------------------
    def pin_violated(self, rows: np.ndarray, lower: np.ndarray, upper: np.ndarray, candidate: np.ndarray,
                     free: np.ndarray) -> np.ndarray | None:
        """A point of ``candidate + range(free)`` meeting every row ``lower <= rows p <= upper``,
        found by pinning the violated rows at their violated bound, or ``None``."""
        tolerance = self.feasibility_tolerance
        bounds = np.zeros(len(lower))
        pinned = np.zeros(len(lower), dtype=bool)
        point = candidate
        for _ in range(self.iterations if free.shape[1] else 1):
            values = rows @ point
            below, above = values < lower - tolerance, values > upper + tolerance
            newly = below | above
            if not newly.any():
                return point
            newly &= ~pinned
            if not newly.any() or not free.shape[1]:
                return None
            bounds[newly] = np.where(above[newly], upper[newly], lower[newly])
            pinned |= newly
            point = self._pinned_point(rows[pinned], bounds[pinned], candidate, free)
            if point is None:
                return None
        return None

    def _pinned_point(self, matrix: np.ndarray, bounds: np.ndarray, candidate: np.ndarray,
                      free: np.ndarray) -> np.ndarray | None:
        """The minimum-norm move of ``candidate`` in ``free`` with ``matrix p = bounds`` (``None``
        when the optimal set cannot move the single pinned row)."""
        gap = bounds - matrix @ candidate
        if len(gap) == 1:  # the usual case: one bound, w = N^T c d / |N^T c|^2
            direction = matrix[0] @ free
            square = float(direction @ direction)
            if square <= (self.rank_tolerance * max(1.0, float(np.abs(matrix).max()))) ** 2:
                return None
            return candidate + free @ (direction * (gap[0] / square))
        return candidate + free @ min_norm(matrix @ free, gap, self.rank_tolerance)

    # -- 2. a primal active set on the level with hard rows -----------------------------------
    def primal_active_set(self, level: RowBlock, rows: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                          m_kept: int, x: np.ndarray, basis: np.ndarray,
                          candidate: np.ndarray) -> np.ndarray | None:
        """The level's least squares with ``lower <= rows p <= upper`` as hard rows (the first
        ``m_kept`` kept from above), from ``x``; ``None`` when ``x`` is infeasible for the rows
        ``basis`` can move, an own row pushes back, or the working sets cycle."""
        tolerance = self.feasibility_tolerance
        mask = np.ones(len(lower), dtype=bool)  # the rows that z can move
        mask[:m_kept] = movable(rows[:m_kept], basis, self.rank_tolerance)
        rows, lower, upper = rows[mask], lower[mask], upper[mask]
        m_kept = int(np.count_nonzero(mask[:m_kept]))
        values = rows @ x
        if (values < lower - tolerance).any() or (values > upper + tolerance).any():
            return None
        bounds = np.zeros(len(lower))  # the bound of each row in the working set
        working: list[int] = []
        point = x
        for _ in range(self.iterations):
            optimum = self._working_optimum(level, rows, bounds, working, point, basis, candidate)
            blocked = self._blocking_point(rows, lower, upper, bounds, working, point, optimum)
            if blocked is not None:
                point = blocked
                continue
            point = optimum
            if not working:
                return point
            multipliers, signed, small = self._multipliers(level, rows, lower, upper, bounds, working, point, basis)
            if signed.min() >= -small:
                if (np.abs(multipliers[np.array(working) >= m_kept]) > small).any():
                    return None  # an own row pushes back: the optimum may need slack there
                return point
            working.pop(int(np.argmin(signed)))
        return None

    def _working_optimum(self, level: RowBlock, rows: np.ndarray, bounds: np.ndarray, working: list[int],
                         point: np.ndarray, basis: np.ndarray, candidate: np.ndarray) -> np.ndarray:
        """The least squares with the working rows at their bounds (elimination), or without
        any working row ``candidate`` (any minimiser of the unconstrained least squares will do)."""
        if not working:
            return candidate
        active = np.array(working)
        shift, reduced = pinned_step(rows[active], bounds[active] - rows[active] @ point, basis, self.rank_tolerance)
        optimum = point + shift
        matrix, target = level.equality_matrix, level.equality_vector
        return optimum + reduced @ min_norm(matrix @ reduced, target - matrix @ optimum, self.rank_tolerance)

    def _blocking_point(self, rows: np.ndarray, lower: np.ndarray, upper: np.ndarray, bounds: np.ndarray,
                        working: list[int], point: np.ndarray, optimum: np.ndarray) -> np.ndarray | None:
        """Where the first row outside the working set blocks the step ``point -> optimum`` (that
        row joins the working set at the bound it meets), or ``None`` if none does."""
        tolerance = self.feasibility_tolerance
        before, after = rows @ point, rows @ optimum
        outside = (after < lower - tolerance) | (after > upper + tolerance)
        outside[working] = False
        if not outside.any():
            return None
        index = np.flatnonzero(outside)
        bound = np.where(after[index] > upper[index], upper[index], lower[index])
        change = after[index] - before[index]
        with np.errstate(divide="ignore", invalid="ignore"):
            fraction = np.where(change != 0.0, (bound - before[index]) / change, 0.0)
        j = int(np.argmin(np.clip(fraction, 0.0, 1.0)))
        working.append(int(index[j]))
        bounds[index[j]] = bound[j]
        return point + min(max(fraction[j], 0.0), 1.0) * (optimum - point)

    def _multipliers(self, level: RowBlock, rows: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                     bounds: np.ndarray, working: list[int], point: np.ndarray,
                     basis: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """The working rows' multipliers at ``point``, the same signed so that a right one is
        >= 0 (inf for a row whose bounds are equal: either sign is right), and the tolerance
        below which a multiplier counts as zero."""
        active = np.array(working)
        matrix, target = level.equality_matrix, level.equality_vector
        gradient = basis.T @ (matrix.T @ (matrix @ point - target))
        normals = basis.T @ rows[active].T
        if len(active) == 1:
            multipliers = -(normals[:, 0] @ gradient) / (normals[:, 0] @ normals[:, 0]) * np.ones(1)
        else:
            multipliers = min_norm(normals, -gradient, self.rank_tolerance)
        sign = np.where(bounds[active] == upper[active], 1.0, -1.0)  # >= 0 at an upper bound
        signed = np.where(lower[active] == upper[active], np.inf, sign * multipliers)
        return multipliers, signed, 1e-9 * max(1.0, float(np.abs(multipliers).max()))
