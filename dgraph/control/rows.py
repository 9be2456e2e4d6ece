"""RowBlock: equalities and inequalities over a solver's variables, the rows a priority level is made of.

A task, a contact or a limit hands a block to a strict-priority solver; the solver stacks the
blocks of one priority into one level (:func:`stacked`) and solves the levels lexicographically
(:mod:`~dgraph.control.cascade`). Bounds on variables are inequalities whose matrix selects
them (:func:`selection`).
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Sequence
from dataclasses import dataclass

import numpy as np

from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class RowBlock:
    """Equalities ``A x = b`` and inequalities ``l <= C x <= u`` over ``n`` variables ``x``.

    ``equality_matrix`` (m_e x n), ``equality_vector`` (m_e), ``inequality_matrix`` (m_i x n),
    ``lower`` and ``upper`` (m_i; ``-inf`` / ``inf`` where unbounded). ``active`` false: the
    block contributes nothing this tick (a solver leaves it out). ``key`` names the block's
    structure (which tasks, how many rows) for a solver that keeps a workspace per structure
    (the cascade warm-starts a level from the latest answer of the same keys); ``None``: unnamed.
    """

    equality_matrix: np.ndarray
    equality_vector: np.ndarray
    inequality_matrix: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    active: bool = True
    key: Hashable = None

    @classmethod
    def equalities(cls, matrix: np.ndarray, vector: np.ndarray, active: bool = True, key: Hashable = None) -> RowBlock:
        """Rows ``A x = b`` only."""
        return cls(matrix, vector, np.zeros((0, matrix.shape[1])), np.zeros(0), np.zeros(0), active, key)

    @classmethod
    def inequalities(cls, matrix: np.ndarray, lower: np.ndarray, upper: np.ndarray, active: bool = True,
                     key: Hashable = None) -> RowBlock:
        """Rows ``l <= C x <= u`` only."""
        return cls(np.zeros((0, matrix.shape[1])), np.zeros(0), matrix, lower, upper, active, key)

    @classmethod
    def empty(cls, n: int, key: Hashable = None) -> RowBlock:
        """No row over ``n`` variables (a level whose tasks are all inactive)."""
        return cls(np.zeros((0, n)), np.zeros(0), np.zeros((0, n)), np.zeros(0), np.zeros(0), key=key)

    def shape_problem(self, columns: int) -> str | None:
        """What is inconsistent in the arrays' shapes (``None`` if nothing)."""
        m_e, m_i = len(self.equality_vector), len(self.lower)
        if self.equality_matrix.shape != (m_e, columns) or self.inequality_matrix.shape != (len(self.upper), columns):
            return (f"matrices of shapes {self.equality_matrix.shape} and {self.inequality_matrix.shape} for "
                    f"{m_e} equality and {m_i} inequality rows over {columns} variables")
        if self.upper.shape != (m_i,):
            return f"{m_i} lower bounds but {self.upper.shape} upper bounds"
        return None

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


def stacked(blocks: Sequence[RowBlock], key: Hashable = None) -> RowBlock:
    """One block holding the rows of ``blocks`` (equalities stacked, inequalities stacked), named ``key``."""
    if len(blocks) == 1:
        b = blocks[0]
        return RowBlock(b.equality_matrix, b.equality_vector, b.inequality_matrix, b.lower, b.upper, key=key)
    return RowBlock(np.vstack([b.equality_matrix for b in blocks]), np.concatenate([b.equality_vector for b in blocks]),
                    np.vstack([b.inequality_matrix for b in blocks]), np.concatenate([b.lower for b in blocks]),
                    np.concatenate([b.upper for b in blocks]), key=key)


def selection(columns: Sequence[int], n: int) -> np.ndarray:
    """The rows of the ``n x n`` identity that pick ``columns``: with it, the bounds
    ``l <= x[columns] <= u`` are the inequalities of :meth:`RowBlock.inequalities`."""
    matrix = np.zeros((len(columns), n))
    matrix[np.arange(len(columns)), columns] = 1.0
    return matrix
