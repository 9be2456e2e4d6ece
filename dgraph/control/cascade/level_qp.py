"""LevelQP: one level of the cascade as a ProxQP problem in ``(z, s)``, polished on its active set.

When no closed form solves a level (an own row needs slack, the active set cycles), the level
is, with ``x = x_{k-1} + Z z`` and no equality row:

```
min  ||A_k Z z - (b_k - A_k x_{k-1})||^2 + ||s||^2
s.t. min(l_j, C_j x_j) - C_j x_{k-1} <= C_j Z z <= max(u_j, C_j x_j) - C_j x_{k-1}      j < k (kept rows)
     l_k - C_k x_{k-1} <= C_k Z z - s <= u_k - C_k x_{k-1}
```

One ProxQP dense object is kept per structure (the keys of the levels down to this one, the
free dimension and the number of rows), warm-started with the latest earlier tick's answer of
the same structure mapped into the current basis (``z = Z^T (x_prev_tick - x_{k-1})``) and its
multipliers. ProxQP's answer is then refined on its active set (:meth:`LevelQP._polish`).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass

import numpy as np

from dgraph.control.cascade.elimination import least_squares, movable
from dgraph.control.cascade.kept_rows import KeptRows
from dgraph.control.proxqp import INFINITY, dense_qp, proxqp_status
from dgraph.control.rows import RowBlock
from dgraph.control.status import SOLVED, Status


@dataclass(slots=True)
class _Workspace:
    """A ProxQP object and its matrices for one level structure."""

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


def _level_cost(projected: np.ndarray, target: np.ndarray, own: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                z: np.ndarray) -> float:
    """``||A Z z - target||^2 + ||s||^2`` with ``s`` the violation of the level's own rows."""
    residual = projected @ z - target
    values = own @ z
    violation = values - np.clip(values, lower, upper)
    return float(residual @ residual + violation @ violation)


class LevelQP:
    """The levels the closed forms could not solve, by ProxQP (module docstring). ``eps_abs``,
    ``max_iterations``: ProxQP's; ``rank_tolerance``, ``feasibility_tolerance``: the cascade's."""

    def __init__(self, eps_abs: float, max_iterations: int, rank_tolerance: float, feasibility_tolerance: float):
        self.eps_abs, self.max_iterations = eps_abs, max_iterations
        self.rank_tolerance, self.feasibility_tolerance = rank_tolerance, feasibility_tolerance
        self._workspaces: dict[Hashable, _Workspace] = {}

    def forget(self) -> None:
        """Drop every warm start (after a failure: the next tick starts cold)."""
        for ws in self._workspaces.values():
            ws.initialised, ws.latest, ws.guess = False, None, None

    def _workspace(self, key: Hashable, n_qp: int, n_in: int, free: int) -> _Workspace:
        ws = self._workspaces.get(key)
        if ws is None:
            # relative tolerance on the data (pulls of 1e3 m/s happen); then polished
            qp = dense_qp(n_qp, 0, n_in, eps_abs=self.eps_abs, max_iterations=self.max_iterations, eps_rel=1e-9)
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

    def solve(self, key: Hashable, level: RowBlock, x: np.ndarray, basis: np.ndarray, kept: KeptRows,
              tick: int | None) -> tuple[Status, int, np.ndarray]:
        """The level from ``x`` in the free directions ``basis``: ``(status, iterations, x)``
        (``x`` unchanged after a failure). ``key`` names the structure of the levels down to
        this one (its workspace and warm start)."""
        free, m_own = basis.shape[1], len(level.lower)
        kept_rows = self._movable_kept(kept, x, basis)
        m_kept = len(kept_rows[1])
        ws = self._workspace((*key, m_kept, m_own), free + m_own, m_kept + m_own, free)
        projected = level.equality_matrix @ basis
        self._write(ws, level, x, basis, projected, kept_rows)
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

    def _movable_kept(self, kept: KeptRows, x: np.ndarray,
                      basis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The kept rows ``(C, l, u)`` that ``z`` can move. A kept row that it cannot (``C Z = 0``:
        its directions are fixed above) holds at ``z = 0`` and stays out: rows of 1e-16 wreck
        ProxQP's equilibration (false infeasibility reports)."""
        matrix, lower, upper = kept.stacked(len(x))
        mask = movable(matrix, basis, self.rank_tolerance)
        return matrix[mask], lower[mask], upper[mask]

    @staticmethod
    def _write(ws: _Workspace, level: RowBlock, x: np.ndarray, basis: np.ndarray, projected: np.ndarray,
               kept_rows: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
        """The level's cost and rows in ``(z, s)`` (module docstring) into the workspace."""
        free, m_kept = basis.shape[1], len(kept_rows[1])
        ws.H[:free, :free] = 2.0 * projected.T @ projected
        ws.g[:free] = -2.0 * projected.T @ (level.equality_vector - level.equality_matrix @ x)
        for rows, matrix, lower, upper, widest in (
                (slice(0, m_kept), *kept_rows, 0.0),
                (slice(m_kept, None), level.inequality_matrix, level.lower, level.upper, -INFINITY)):
            ws.C[rows, :free] = matrix @ basis
            values = matrix @ x
            # kept rows hold at z = 0 (x satisfies them up to the tolerances of the levels between)
            ws.lower[rows] = np.clip(np.minimum(lower - values, -widest), -INFINITY, INFINITY)
            ws.upper[rows] = np.clip(np.maximum(upper - values, widest), -INFINITY, INFINITY)

    def _closest_feasible(self, ws: _Workspace) -> tuple[Status, int]:
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
        bound); the refined point is kept when it satisfies every row but the own rows it
        stops at, and its cost is no worse."""
        results = ws.qp.results
        z = results.x[:free]
        multipliers = results.z
        at_bound = np.where(multipliers > 0, ws.upper, ws.lower)
        active = np.abs(multipliers) > 1e-10 * max(1.0, float(np.abs(multipliers).max(initial=0.0)))
        kept_rows, own_rows = np.flatnonzero(active[:m_kept]), m_kept + np.flatnonzero(active[m_kept:])
        rows = ws.C[:, :free]
        base, null = least_squares(rows[kept_rows], at_bound[kept_rows], np.eye(free), self.rank_tolerance)
        objective = np.vstack([projected, rows[own_rows]])
        goal = np.concatenate([target, at_bound[own_rows]])
        refined = base + least_squares(objective, goal - objective @ base, null, self.rank_tolerance)[0]
        values = rows @ refined
        must_hold = np.ones(len(values), dtype=bool)  # every row but the own rows ProxQP stops at
        must_hold[own_rows] = False
        tolerance = self.feasibility_tolerance
        feasible = ((values[must_hold] >= ws.lower[must_hold] - tolerance).all()
                    and (values[must_hold] <= ws.upper[must_hold] + tolerance).all())
        own = (projected, target, rows[m_kept:], ws.lower[m_kept:], ws.upper[m_kept:])
        found = _level_cost(*own, z)
        if feasible and _level_cost(*own, refined) <= found + 1e-9 * (1e-6 + found):  # rounding aside, no worse
            return refined
        return z

    @staticmethod
    def _guess(ws: _Workspace, level: RowBlock, x: np.ndarray,
               basis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The warm start ``(z, s), y, multipliers`` mapped from the latest earlier answer."""
        if ws.guess is None:
            return None
        previous, multipliers = ws.guess
        z = basis.T @ (previous - x)
        values = level.inequality_matrix @ (x + basis @ z)
        slack = values - np.clip(values, level.lower, level.upper)
        return np.concatenate([z, slack]), np.zeros(0), multipliers

    @staticmethod
    def _run(ws: _Workspace, guess: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> tuple[Status, int]:
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
