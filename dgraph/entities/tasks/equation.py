"""TaskEquation: one weighted least-squares row block ``w * || A a - b ||^2`` of a QP."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.entities.features.feature import FeatureValue
from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class TaskEquation:
    """``matrix`` ``A`` (m x nv), ``vector`` ``b`` (m), ``weight`` ``w`` (m, >= 0).

    The solver minimises ``sum_i w_i (A a - b)_i^2`` over the accelerations ``a``. A
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
