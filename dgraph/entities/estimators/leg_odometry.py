"""Leg-odometry helpers for base estimators: robot model, frames, relative kinematics.

Plain Python (no entity): the estimator entities build on these. Notation used by the
estimators' docstrings: ``W`` world, ``B`` base (the free-flyer joint), ``I`` IMU frame,
``F`` a foot frame (sole), ``S`` a force/torque sensor frame. ``R_XY`` is the rotation of
frame ``Y`` in frame ``X`` and ``r_XY`` the position of the origin of ``Y`` in ``X``.

:class:`RelativeKinematics` evaluates the robot *relative to its base*: with the free-flyer
at the identity and at rest, one first-order ``forwardKinematics`` from the joint encoders
``(q_j, qd_j)`` gives, for every frame ``X`` of interest, ``R_BX``, ``r_BX`` and its velocity
in ``X``, ``(v_X, w_X)``, hence relative to the base in ``B``: ``d/dt r_BX = J_X^lin(q_j) qd_j
= R_BX v_X`` and ``w_BX = J_X^ang(q_j) qd_j = R_BX w_X`` (no Jacobian is formed). The
quaternion helpers work on Python floats, which the estimators use for their 3-vector algebra.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from dgraph.entities.selection import contiguous
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


def complementary_alpha(cutoff: float, dt: float) -> float:
    """Weight of the integrated accelerometer: ``alpha = tau / (tau + dt)``, ``tau = 1 / (2 pi f_c)``.

    ``f_c = inf`` gives ``alpha = 0`` (kinematics only).
    """
    tau = 1.0 / (2.0 * math.pi * cutoff)
    return tau / (tau + dt)


class RelativeKinematics:
    """A few frames of a free-flyer model relative to its base, from the joint encoders.

    Built for the frames named in ``frames``: every joint that moves none of them (outside the
    supports of their parent joints: on TALOS the arms, grippers and head when the frames are
    on the legs and the torso) is locked (``pinocchio.buildReducedModel``), which changes
    nothing for these frames and halves the work; then every frame ``X`` gets a joint of its
    own, appended after the others: a revolute joint held at zero (its motion is the identity,
    so its placement is the frame's, bit for bit) on the frame's parent joint at the frame's
    placement. :meth:`forward` runs one first-order ``pinocchio.forwardKinematics(model, data,
    q, v)`` on that model with ``q = [0, 0, 0, 0, 0, 0, 1, q_j, 0]`` and ``v = [0_6, qd_j, 0]``
    (base at the identity and at rest, ``q_j``, ``qd_j`` restricted to the joints kept), which
    computes every frame's placement ``(R_BX, r_BX)`` and velocity ``(v_X, w_X)`` (Pinocchio's
    LOCAL: expressed in ``X``) with the joints', in C++. In ``B``::

        d/dt r_BX = J_X^lin(q_j) qd_j = R_BX v_X,   w_BX = J_X^ang(q_j) qd_j = R_BX w_X.    (K)

    It returns them in Python floats, one row per frame in the order of ``frames``, as they lie
    in Pinocchio's memory: ``R_BX`` column by column and ``r_BX`` (12 floats), and ``v_X``,
    ``w_X`` (6 floats). The frames' joints being consecutive, their placements and velocities
    are consecutive elements of ``data.oMi`` and ``data.v`` (std::vectors): one read-only
    (frames, 12) and one (frames, 6) array view them (their layout is checked here), and one
    ``tolist`` each converts them; the views are valid as long as this object (which holds
    ``data``) lives.
    """

    def __init__(self, model: Any, frames: Sequence[str]):
        import pinocchio as pin

        kept = {j for name in frames for j in model.supports[model.frames[model.getFrameId(name)].parentJoint]}
        locked = [j for j in range(2, model.njoints) if j not in kept]
        self.model = reduced = pin.buildReducedModel(model, locked, pin.neutral(model)) if locked else pin.Model(model)
        first = reduced.njoints
        for name in frames:
            frame = reduced.frames[reduced.getFrameId(name)]
            reduced.addJoint(frame.parentJoint, pin.JointModelRX(), frame.placement, f"{name} (frame)")
        self.data = data = reduced.createData()
        joints = range(first, reduced.njoints)
        self._placements = _rows([(data.oMi[j].rotation, data.oMi[j].translation) for j in joints])
        self._motions = _rows([(data.v[j].linear, data.v[j].angular) for j in joints])
        kept_joints = sorted(kept - {0, 1})
        self._q_joints = contiguous(np.array([i for j in kept_joints for i in range(
            model.idx_qs[j] - 7, model.idx_qs[j] - 7 + model.nqs[j])], dtype=np.intp))  # a slice: a view
        self._v_joints = contiguous(np.array([i for j in kept_joints for i in range(
            model.idx_vs[j] - 6, model.idx_vs[j] - 6 + model.nvs[j])], dtype=np.intp))
        self._q = pin.neutral(reduced)  # the frames' joints stay at 0
        self._q[:7] = [0, 0, 0, 0, 0, 0, 1]
        self._v = np.zeros(reduced.nv)
        self._q_slice, self._v_slice = slice(7, reduced.idx_qs[first]), slice(6, reduced.idx_vs[first])
        self._pin = pin

    def forward(self, q_joints: np.ndarray, v_joints: np.ndarray) -> tuple[list[list[float]], list[list[float]]]:
        """The pass for joint positions ``q_joints`` (``q[7:]`` of the full model) and velocities
        ``v_joints`` (``v[6:]``): per frame, ``[R_BX by columns, r_BX]`` and ``[v_X, w_X]``."""
        self._q[self._q_slice] = q_joints[self._q_joints]
        self._v[self._v_slice] = v_joints[self._v_joints]
        self._pin.forwardKinematics(self.model, self.data, self._q, self._v)
        return self._placements.tolist(), self._motions.tolist()


def _rows(elements: list[tuple[np.ndarray, ...]]) -> np.ndarray:
    """A read-only view of consecutive elements of a Pinocchio std::vector, one row per element.

    ``elements[i]`` are the float64 arrays eigenpy gives for the members of element ``i`` (the
    rotation and translation of an SE3, the linear and angular parts of a Motion): they share
    the vector's memory. The row of an element is its memory, its members one after the other,
    a matrix column by column (Eigen's order); a RuntimeError if the members do not tile the
    elements that way, at one element's size apart.
    """
    width = sum(member.size for member in elements[0])
    origin = elements[0][0].__array_interface__["data"][0]
    for i, members in enumerate(elements):
        found = [address - origin for member in members for address in _addresses(member)]
        if found != [8 * (i * width + k) for k in range(width)]:
            raise RuntimeError(f"unexpected memory layout of a Pinocchio vector (element {i}: offsets {found})")
    return np.lib.stride_tricks.as_strided(elements[0][0], shape=(len(elements), width), strides=(8 * width, 8),
                                           writeable=False)


def _addresses(array: np.ndarray) -> list[int]:
    """The addresses of the entries of a float64 array, column by column (Eigen's order)."""
    if array.dtype != np.float64:
        raise RuntimeError(f"expected float64 Pinocchio memory, got {array.dtype}")
    start = array.__array_interface__["data"][0]
    order = sorted(np.ndindex(array.shape), key=lambda index: index[::-1])
    return [start + sum(i * s for i, s in zip(index, array.strides, strict=True)) for index in order]


