"""Leg-odometry helpers for base estimators: robot model, frames, relative kinematics.

Plain Python (no entity): the estimator entities build on these. Notation used by the
estimators' docstrings: ``W`` world, ``B`` base (the free-flyer joint), ``I`` IMU frame,
``F`` a foot frame (sole), ``S`` a force/torque sensor frame. ``R_XY`` is the rotation of
frame ``Y`` in frame ``X`` and ``r_XY`` the position of the origin of ``Y`` in ``X``.

:class:`RelativeKinematics` evaluates the robot *relative to its base*: with the free-flyer
at the identity and at rest, one first-order ``forwardKinematics`` from the joint encoders
``(q_j, qd_j)`` gives, for every frame ``X`` of interest, ``R_BX``, ``r_BX`` and its velocity
relative to the base expressed in ``B``: ``d/dt r_BX = J_X^lin(q_j) qd_j`` and
``w_BX = J_X^ang(q_j) qd_j`` (no Jacobian is formed).
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from dgraph.errors import ParamError


def frame_id(model: Any, name: str, entity: str, param: str, label: str | None = None) -> int:
    """The id of frame ``name``; a :class:`ParamError` naming the entity, parameter and close names."""
    label = label or entity
    if not model.existFrame(name):
        close = difflib.get_close_matches(name, [f.name for f in model.frames], n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise ParamError(f"{label}: parameter {param!r}: the model {model.name!r} has no frame "
                         f"{name!r}{hint}", entity=entity)
    return model.getFrameId(name)


def default_imu_frame(model: Any) -> str:
    """``imu_link`` if the model has it, else the frame of the free-flyer (``base_link``)."""
    if model.existFrame("imu_link"):
        return "imu_link"
    for frame in model.frames:
        if frame.parentJoint == 1 and frame.placement.isIdentity():
            return frame.name
    return model.frames[1].name


def standing_configuration(model: Any, foot_frames: Sequence[str]) -> np.ndarray:
    """Half-sitting (or neutral) configuration with the base height putting the lowest sole at z = 0."""
    import pinocchio as pin

    try:
        q = np.array(model.referenceConfigurations["half_sitting"], dtype=float)
    except (KeyError, IndexError, RuntimeError):
        q = pin.neutral(model)
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    lowest = min(pin.updateFramePlacement(model, data, model.getFrameId(f)).translation[2] for f in foot_frames)
    q[2] -= lowest
    return q


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a quaternion ``[x, y, z, w]`` (normalised here)."""
    x, y, z, w = (q / math.sqrt(float(q @ q))).tolist()  # Python floats: cheaper than numpy scalars
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def matrix_to_quat(r: np.ndarray) -> np.ndarray:
    """Quaternion ``[x, y, z, w]`` (``w >= 0``) of a rotation matrix (Shepperd's method)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = r.tolist()
    trace = r00 + r11 + r22
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [(r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s, 0.25 * s]
    elif r00 > r11 and r00 > r22:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        q = [0.25 * s, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s]
    elif r11 > r22:
        s = 2.0 * math.sqrt(1.0 + r11 - r00 - r22)
        q = [(r01 + r10) / s, 0.25 * s, (r12 + r21) / s, (r02 - r20) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + r22 - r00 - r11)
        q = [(r02 + r20) / s, (r12 + r21) / s, 0.25 * s, (r10 - r01) / s]
    out = np.array(q)
    out /= math.sqrt(float(out @ out))
    return -out if out[3] < 0 else out


def contact_hysteresis(force: float, previous: bool, on: float, off: float) -> bool:
    """Schmitt trigger: contact if ``force > on``, or if already in contact and ``force > off``."""
    return force > on or (previous and force > off)


def complementary_alpha(cutoff: float, dt: float) -> float:
    """Weight of the integrated accelerometer: ``alpha = tau / (tau + dt)``, ``tau = 1 / (2 pi f_c)``.

    ``f_c = inf`` gives ``alpha = 0`` (kinematics only).
    """
    tau = 1.0 / (2.0 * math.pi * cutoff)
    return tau / (tau + dt)


class FrameMotion:
    """Placement and velocity of a frame relative to the base, in the base frame."""

    __slots__ = ("angular", "linear", "rotation", "translation")

    def __init__(self, rotation: np.ndarray, translation: np.ndarray, linear: np.ndarray, angular: np.ndarray):
        self.rotation = rotation          # R_BX
        self.translation = translation    # r_BX
        self.linear = linear              # d/dt r_BX (base frame)
        self.angular = angular            # w_BX, angular velocity of X relative to B, in B


class RelativeKinematics:
    """Frames of a free-flyer model relative to its base, from the joint encoders.

    One ``pinocchio.forwardKinematics(model, data, q, v)`` with ``q = [0, 0, 0, 0, 0, 0, 1, q_j]``
    and ``v = [0_6, qd_j]`` (base at the identity and at rest) on a private ``Data``, then
    ``updateFramePlacement`` and ``getFrameVelocity(..., LOCAL_WORLD_ALIGNED)`` per frame.
    """

    def __init__(self, model: Any, frames: Sequence[int]):
        import pinocchio as pin

        self._pin = pin
        self.model = model
        self.data = model.createData()
        self.frames = list(frames)
        self._q = pin.neutral(model)
        self._q[:7] = [0, 0, 0, 0, 0, 0, 1]
        self._v = np.zeros(model.nv)
        self._lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def forward(self, q_joints: np.ndarray, v_joints: np.ndarray) -> None:
        """Only the forward kinematics: read the frames with ``pinocchio.updateFramePlacement``
        and ``getFrameVelocity(..., LOCAL_WORLD_ALIGNED)`` on ``model`` and ``data``."""
        self._q[7:] = q_joints
        self._v[6:] = v_joints
        self._pin.forwardKinematics(self.model, self.data, self._q, self._v)

    def update(self, q_joints: np.ndarray, v_joints: np.ndarray) -> dict[int, FrameMotion]:
        """Motion of every frame (by id) relative to the base, for joint positions and velocities."""
        pin, model, data = self._pin, self.model, self.data
        self.forward(q_joints, v_joints)
        out = {}
        for fid in self.frames:
            placement = pin.updateFramePlacement(model, data, fid)
            motion = pin.getFrameVelocity(model, data, fid, self._lwa)
            out[fid] = FrameMotion(placement.rotation, placement.translation, motion.linear, motion.angular)
        return out
