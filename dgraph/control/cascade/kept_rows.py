"""KeptRows: the inequalities of the levels already solved, kept at their optimal slack for the levels below."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dgraph.control.rows import RowBlock


@dataclass(slots=True)
class KeptRows:
    """The relaxed inequalities of the levels already solved: a row that holds at its level's
    optimum ``x_j`` is kept as ``min(l_j, C_j x_j) <= C_j x <= max(u_j, C_j x_j)`` (its bounds,
    widened by the tolerance the levels solved since may have used, so that ``x`` stays
    feasible); a violated one is pinned by the cascade (see :meth:`add`)."""

    matrices: list[np.ndarray] = field(default_factory=list)
    lower: list[np.ndarray] = field(default_factory=list)
    upper: list[np.ndarray] = field(default_factory=list)
    cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # stacked(), until the next add

    def add(self, level: RowBlock, x: np.ndarray, tolerance: float) -> np.ndarray | None:
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


def own_rows_hold(level: RowBlock, x: np.ndarray, tolerance: float) -> bool:
    """Whether ``x`` satisfies ``level``'s own inequalities within ``tolerance``."""
    if not len(level.lower):
        return True
    values = level.inequality_matrix @ x
    return not ((values < level.lower - tolerance).any() or (values > level.upper + tolerance).any())
