"""Least squares by elimination in a null-space basis: the linear algebra of the lexicographic cascade.

Every step of the cascade moves ``x`` by ``Z z`` in the free directions ``Z`` (orthonormal
columns) the levels above left; these functions find the step and the directions that stay free.
``rank_tolerance`` is the relative threshold below which a direction counts as zero.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import lapack


def least_squares(matrix: np.ndarray, target: np.ndarray, basis: np.ndarray,
                  rank_tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """The minimum-norm step ``Z z`` with ``z = argmin ||A Z z - target||``, and the basis of the
    directions that stay free below (orthonormal columns spanning ``Z null(A Z)``).

    A column-pivoted QR of ``(A Z)^T = Q R Pi^T`` (LAPACK ``dgeqp3``; an SVD costs 5 to 10 times
    more at these sizes) splits ``Z Q`` into the row space of ``A Z`` (the first ``rank``
    columns, diagonal entries of ``R`` above ``rank_tolerance * max(1, |R_11|)``) and its null
    space; the step is ``Z Q_1 y`` with ``y = argmin ||R_1^T y - Pi^T target||`` (full column
    rank: a triangular solve when the rows are independent, else ``dgels``).
    """
    n = basis.shape[0]
    if not len(target) or not basis.shape[1]:
        return np.zeros(n), basis
    projected = matrix @ basis
    qr, pivots, tau, _, _ = lapack.dgeqp3(projected.T)
    diagonal = np.abs(qr.diagonal())
    rank = int(np.count_nonzero(diagonal > rank_tolerance * max(1.0, diagonal[0] if len(diagonal) else 0.0)))
    rotated, _, _ = lapack.dormqr("R", "N", qr[:, :len(tau)], tau, basis, lwork=64 * n)
    if rank == 0:
        return np.zeros(n), rotated
    permuted = target[pivots - 1]
    if rank == len(target):  # independent rows (the usual case): R_1^T is square, triangular
        y, _ = lapack.dtrtrs(qr[:rank, :rank], permuted, trans=1)
    else:
        y = lapack.dgels(np.triu(qr[:rank]).T, permuted)[1][:rank]
    return rotated[:, :rank] @ y, rotated[:, rank:]


def min_norm(matrix: np.ndarray, target: np.ndarray, rank_tolerance: float) -> np.ndarray:
    """``argmin ||M y - t||`` of least norm (LAPACK ``dgelsy``: one complete orthogonal
    factorisation; for the steps that need no null-space basis)."""
    m, n = matrix.shape
    if not m or not n:
        return np.zeros(n)
    rhs = np.zeros((max(m, n), 1))
    rhs[:m, 0] = target
    small = min(m, n)
    _, y, _, _, _ = lapack.dgelsy(matrix, rhs, np.zeros(n, dtype=np.int32), rank_tolerance,
                                  max(small + 3 * n + 1, 2 * small + 1) + 64 * n)
    return y[:n, 0]


def pinned_step(matrix: np.ndarray, gap: np.ndarray, basis: np.ndarray,
                rank_tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """As :func:`least_squares` (the step meeting ``matrix step = gap`` in ``basis`` and the
    basis left), with one row by a Householder reflection of ``Z^T c``."""
    if len(gap) != 1:
        return least_squares(matrix, gap, basis, rank_tolerance)
    direction = basis.T @ matrix[0]
    norm = math.sqrt(float(direction @ direction))
    if norm <= rank_tolerance * max(1.0, float(np.abs(direction).max(initial=0.0))):
        return np.zeros(len(matrix[0])), basis
    step = basis @ (direction * (gap[0] / norm**2))
    direction[0] += math.copysign(norm, direction[0])  # H = I - 2 u u^T maps Z^T c onto e_0
    direction /= math.sqrt(float(direction @ direction))
    return step, (basis - 2.0 * np.outer(basis @ direction, direction))[:, 1:]


def movable(matrix: np.ndarray, basis: np.ndarray, rank_tolerance: float) -> np.ndarray:
    """Which rows ``basis`` can still move (``C Z != 0``; the others are fixed above and hold at
    ``x`` up to the tolerances of the levels between)."""
    return np.abs(matrix @ basis).max(axis=1, initial=0.0) > rank_tolerance * max(
        1.0, float(np.abs(matrix).max(initial=0.0)))
