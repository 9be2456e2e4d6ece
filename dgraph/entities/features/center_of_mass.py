"""CenterOfMass: the robot's centre of mass against a reference."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.control.feature import FeatureValue
from dgraph.entities.features.feature import Feature, parse_mask
from dgraph.entities.robot.robot_state import RobotState


@dg.register
class CenterOfMass(Feature):
    """Centre of mass ``c`` (world frame) against ``c*`` (thesis Eq. 4.9, linear part).

    ``error = c - c*``, ``error_velocity = J_com v - c_dot*``, ``jacobian = J_com``,
    ``drift = J_com_dot v``, ``reference_acceleration = c_ddot*``. ``mask`` (3 characters
    over x y z) splits the thesis's "CoM height" and "CoM lateral-sagittal" tasks.

    Inputs: ``robot``, ``reference_position`` (3), ``reference_velocity``,
    ``reference_acceleration`` (3, default 0).
    """

    mask = dg.Param("111", kind="str", doc="rows kept, over x y z")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, mask: str = "111") -> None: ...

    reference_position = dg.Input(shape=(3,), doc="c*")
    reference_velocity = dg.Input(shape=(3,), default=np.zeros(3), doc="c_dot*")
    reference_acceleration = dg.Input(shape=(3,), default=np.zeros(3), doc="c_ddot*")

    def configure(self) -> None:
        """Parse the mask."""
        self.rows = parse_mask(self, self.mask, 3)
        self.size = self.mask.count("1")

    def evaluate(self, state: RobotState, t: int) -> FeatureValue:
        """CoM error and its derivatives."""
        com = state.com
        return FeatureValue(com.position - self.reference_position(t), com.velocity - self.reference_velocity(t),
                            com.jacobian, com.drift, self.reference_acceleration(t))
