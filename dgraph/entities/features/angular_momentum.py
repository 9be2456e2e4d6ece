"""AngularMomentum: the centroidal angular momentum against a reference."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.control.feature import FeatureValue
from dgraph.entities.features.feature import Feature
from dgraph.entities.robot.robot_state import RobotState


@dg.register
class AngularMomentum(Feature):
    """Centroidal angular momentum ``k = A_G,k v`` against ``k*`` (thesis Eq. 2.32).

    The thesis regulates ``k_dot = k_dot* + K_P (k* - k)`` (proportional only): this feature
    is already a rate, so ``error = k - k*``, ``error_velocity = 0`` (use ``kd = 0`` on its
    task), ``jacobian = A_G,k`` (the angular rows of the centroidal momentum matrix),
    ``drift = A_G,k_dot v`` and ``reference_acceleration = k_dot*``.

    Inputs: ``robot``, ``reference`` (3, default 0: the benchmark regulates k to 0),
    ``reference_rate`` (3, default 0).
    """
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str) -> None: ...

    reference = dg.Input(shape=(3,), default=np.zeros(3), doc="k*")
    reference_rate = dg.Input(shape=(3,), default=np.zeros(3), doc="k_dot*")

    def configure(self) -> None:
        """Three rows, no mask."""
        self.rows = None
        self.size = 3
        self._zeros = np.zeros(3)
        self._zeros.flags.writeable = False  # shared by every tick's value

    def evaluate(self, state: RobotState, t: int) -> FeatureValue:
        """Momentum error, Jacobian and drift."""
        momentum_matrix = state.centroidal_momentum_matrix[3:]
        return FeatureValue(momentum_matrix @ state.v - self.reference(t), self._zeros, momentum_matrix,
                            state.centroidal_drift[3:], self.reference_rate(t), is_rate=True)
