"""TaskRows: the weighted task part of the inverse-dynamics cost, stacked into one matrix and formed with one product.

Each task owns a fixed block of rows of one stacked matrix ``[A_1; A_2; ...]`` (the way TSID lays
out its formulation), so a tick copies every task's rows into its block and forms
``H_aa = (sqrt(2 W) A)^T (sqrt(2 W) A)`` with one BLAS product instead of one per task.
"""

from __future__ import annotations

import numpy as np

from dgraph.control.equation import TaskEquation


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
