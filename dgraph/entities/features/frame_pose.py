"""FramePose: the placement of a robot frame against a reference, on SE(3)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.control.feature import FeatureValue
from dgraph.entities.features.feature import Feature, parse_mask
from dgraph.entities.robot.robot_state import WORLD, FrameKinematics, FrameReader, RobotState
from dgraph.entities.robot.rotations import log3_product


@dg.register
class FramePose(FrameReader, Feature):
    """Pose of ``frame`` against a reference, with world axes at the frame origin (thesis Eq. 4.6).

    ``x = (p, R)``, ``x* = (p*, R*)``;
    ``error = [p - p*, log3(R R*^T)]`` (the SE(3) difference as a world-axes twist),
    ``error_velocity = [p_dot - p_dot*, omega - omega*]``, ``jacobian`` ``J`` with
    ``[p_dot, omega] = J v``, ``drift = J_dot v`` (classical acceleration at ``a = 0``) and
    ``reference_acceleration = [p_ddot*, omega_dot*]``. ``mask`` (6 characters 0/1 over
    ``x y z rx ry rz``, world axes) keeps a subset: ``"000111"`` is an orientation feature
    (the thesis's waist task), ``"001000"`` a height.

    Parameters: ``frame``, ``mask`` (default all six).
    Inputs: ``robot``; ``reference_position`` (3, default 0), ``reference_orientation``
    (quaternion xyzw, default identity), ``reference_velocity`` and ``reference_acceleration``
    (6, world axes, default 0).
    """

    frame = dg.Param(kind="str", doc="frame name in the robot model")
    mask = dg.Param("111111", kind="str", doc="rows kept, over x y z rx ry rz (world axes)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, frame: str, mask: str = "111111") -> None: ...

    reference_position = dg.Input(shape=(3,), default=np.zeros(3), doc="p*")
    reference_orientation = dg.Input(shape=(4,), default=np.array([0.0, 0.0, 0.0, 1.0]), doc="R* as xyzw")
    reference_velocity = dg.Input(shape=(6,), default=np.zeros(6), doc="[p_dot*, omega*]")
    reference_acceleration = dg.Input(shape=(6,), default=np.zeros(6), doc="[p_ddot*, omega_dot*]")

    def configure(self) -> None:
        """Parse the mask: the half (position or orientation) it keeps rows of, or both, and the
        rows kept within it."""
        parse_mask(self, self.mask, 6)
        position, orientation = "1" in self.mask[:3], "1" in self.mask[3:]
        self._block = slice(0 if position else 3, 6 if orientation else 3)
        self.rows = parse_mask(self, self.mask[self._block], self._block.stop - self._block.start)
        self.size = self.mask.count("1")
        self._reference: tuple[np.ndarray, list[list[float]]] | None = None  # (quaternion, R*^T) last converted

    def constant_problem(self, name: str, value: object) -> str | None:
        """A constant reference orientation is a quaternion that can be normalised."""
        if name == "reference_orientation" and not np.linalg.norm(value) > 1e-9:
            return f"expected a unit quaternion [x, y, z, w], got {value}"
        return None

    def _reference_rotation(self, t: int) -> list[list[float]]:
        """``R*^T`` (rows of floats) from the reference quaternion (normalised), converted again
        only when the quaternion is not the same constant as last time."""
        quat = self.reference_orientation(t)
        cached = self._reference
        if cached is not None and cached[0] is quat and self.reference_orientation.source is None:
            return cached[1]
        norm = np.linalg.norm(quat)
        if not norm > 1e-9:
            raise dg.SpecError(f"{self.name}.reference_orientation is not a unit quaternion: {quat}",
                               entity=self.name, signal="reference_orientation")
        rows = pin.Quaternion(quat / norm).toRotationMatrix().T.tolist()
        self._reference = (quat, rows)
        return rows

    def _error(self, frame: FrameKinematics, t: int) -> np.ndarray:
        """``[p - p*, log3(R R*^T)]`` on the half (or both) the mask keeps rows of; the logarithm
        in Python floats (:func:`~dgraph.entities.robot.rotations.log3_product`)."""
        block = self._block
        if block.stop == 3:
            return frame.translation - self.reference_position(t)
        orientation = log3_product(frame.rotation.tolist(), self._reference_rotation(t))
        if block.start == 3:
            return np.array(orientation)
        return np.concatenate([frame.translation - self.reference_position(t), orientation])

    def evaluate(self, state: RobotState, t: int) -> FeatureValue:
        """Pose error and its derivatives on SE(3), world axes, on the half the mask keeps rows of
        (both halves: all six rows)."""
        frame = state.frame(self.frame_index(state), WORLD)
        block = self._block
        return FeatureValue(self._error(frame, t), (frame.velocity - self.reference_velocity(t))[block],
                            frame.jacobian[block], frame.drift[block], self.reference_acceleration(t)[block])
