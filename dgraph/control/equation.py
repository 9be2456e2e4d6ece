"""TaskEquation: one weighted least-squares row block ``w * || A a - b ||^2`` over the accelerations."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.control.feature import FeatureValue
from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class TaskEquation:
    """``matrix`` ``A`` (m x nv), ``vector`` ``b`` (m), ``weight`` ``w`` (m, >= 0).

    A weighted solver minimises ``sum_i w_i (A a - b)_i^2`` over the accelerations ``a``; a
    strict-priority one takes the rows ``sqrt(w) (A a - b)`` as one level. A
    :class:`~dgraph.entities.tasks.Task` also hands over its ``feature`` and gains ``kp``,
    ``kd`` (vectors), which an energy tank reads to compute the task's stored energy.
    """

    matrix: np.ndarray
    vector: np.ndarray
    weight: np.ndarray
    feature: FeatureValue | None = None
    kp: np.ndarray | None = None
    kd: np.ndarray | None = None

    def residual(self, acceleration: np.ndarray) -> np.ndarray:
        """``A a - b``."""
        return self.matrix @ acceleration - self.vector

    def cost(self, acceleration: np.ndarray) -> float:
        """``sum_i w_i (A a - b)_i^2``."""
        r = self.residual(acceleration)
        return float(self.weight @ (r * r))

    def problem(self, nv: int) -> str | None:
        """What makes the equation unusable over ``nv`` accelerations: ``A`` not m x nv, ``b``
        or ``w`` not of length m, or a negative weight (``None`` if nothing)."""
        matrix, vector, weight = self.matrix, self.vector, self.weight
        rows = matrix.shape[0] if matrix.ndim == 2 else -1
        if matrix.ndim != 2 or matrix.shape[1] != nv:
            return f"task matrix has shape {matrix.shape}, the robot has nv = {nv}"
        if vector.shape != (rows,) or weight.shape != (rows,):
            return f"{rows} rows but a vector of shape {vector.shape} and weights of shape {weight.shape}"
        if (weight < 0).any():
            return "negative weights (the cost would not be convex)"
        return None
