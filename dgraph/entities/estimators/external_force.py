"""ExternalForce: the force the environment exerts beyond a force/torque sensor, from its reading."""

from __future__ import annotations

import numpy as np

import dgraph as dg
from dgraph.entities.robot.robot_state import FrameReader, RobotState


def payload_mass(state: RobotState, frame: int) -> float:
    """Mass carried beyond a sensor frame: the subtree of the frame's parent joint."""
    model = state.model
    joint = model.frames[frame].parentJoint
    return float(sum(model.inertias[j].mass for j in range(joint, model.njoints) if joint in model.supports[j]))


@dg.register
class ExternalForce(FrameReader, dg.Entity):
    """External force on the robot beyond a wrist (or ankle) force/torque sensor, world axes.

    The sensor reads the wrench the child side (hand and what it holds) exerts on the parent side,
    in the sensor frame. Quasi-statically the hand's weight ``m g`` and the external force ``F``
    both go through the sensor, so ``F = R f_s - m g`` (``g`` the gravity vector, ``R`` the
    sensor frame's orientation). The hand's own accelerations are neglected. ``m`` is
    ``payload_mass``, by default the mass of the subtree of the sensor frame's parent joint in
    the plugged model; a reduced model merges the links between that joint and the sensor into
    it (TALOS: 0.31 kg of ``arm_left_7_link``), so give the URDF mass beyond the sensor when it
    matters (TALOS wrist: 1.384 kg). A held tool should be in that mass or massless.

    Parameters: ``frame`` (the sensor frame, e.g. ``wrist_left_ft_link``), ``payload_mass`` (kg).
    Inputs: ``robot`` (RobotModel state), ``wrench`` (6, the sensor reading: force then torque).
    Outputs: ``force`` (3, N, world), ``payload`` (kg, the compensated mass).
    """

    frame = dg.Param(kind="str", doc="the sensor frame")
    payload_mass = dg.Param(None, kind="float", minimum=0.0, optional=True,
                            doc="mass beyond the sensor (kg; default: subtree of the frame's parent joint)")
    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")
    wrench = dg.Input(shape=(6,), doc="sensor reading [force, torque], sensor frame")

    @dg.output(shape=(), depends=("robot",))
    def payload(self, t: int) -> float:
        """Mass beyond the sensor (kg)."""
        if self.payload_mass is not None:
            return self.payload_mass
        state = self.robot(t)
        return payload_mass(state, self.frame_index(state))

    @dg.output(shape=(3,), depends=("robot", "wrench", "payload"), labels=("x", "y", "z"))
    def force(self, t: int) -> np.ndarray:
        """``R f_s - m g`` (N, world)."""
        state = self.robot(t)
        rotation = state.frame_placement(self.frame_index(state)).rotation
        return rotation @ self.wrench(t)[:3] - self.payload(t) * state.model.gravity.linear
