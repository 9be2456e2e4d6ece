"""PriorityRows: what one task contributes to one level of a strict-priority stack."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class PriorityRows:
    """Equalities ``A x = b`` and inequalities ``l <= C x <= u`` over the solver's variables.

    ``equality_matrix`` (m_e x n), ``equality_vector`` (m_e), ``inequality_matrix`` (m_i x n),
    ``lower`` and ``upper`` (m_i; ``-inf`` / ``inf`` where unbounded). ``active`` false: the
    task contributes nothing this tick (its level may become empty).
    """

    equality_matrix: np.ndarray
    equality_vector: np.ndarray
    inequality_matrix: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    active: bool = True

    @classmethod
    def equalities(cls, matrix: np.ndarray, vector: np.ndarray, active: bool = True) -> PriorityRows:
        """Rows ``A x = b`` only."""
        return cls(matrix, vector, np.zeros((0, matrix.shape[1])), np.zeros(0), np.zeros(0), active)

    @classmethod
    def inequalities(cls, matrix: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                     active: bool = True) -> PriorityRows:
        """Rows ``l <= C x <= u`` only."""
        return cls(np.zeros((0, matrix.shape[1])), np.zeros(0), matrix, lower, upper, active)

    @property
    def columns(self) -> int:
        """Number of variables the rows are written over."""
        return self.equality_matrix.shape[1]

    def shape_problem(self, columns: int) -> str | None:
        """What is inconsistent in the arrays' shapes (``None`` if nothing)."""
        m_e, m_i = len(self.equality_vector), len(self.lower)
        if self.equality_matrix.shape != (m_e, columns) or self.inequality_matrix.shape != (len(self.upper), columns):
            return (f"matrices of shapes {self.equality_matrix.shape} and {self.inequality_matrix.shape} for "
                    f"{m_e} equality and {m_i} inequality rows over {columns} variables")
        if self.upper.shape != (m_i,):
            return f"{m_i} lower bounds but {self.upper.shape} upper bounds"
        return None
