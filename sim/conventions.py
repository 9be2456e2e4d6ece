"""The one place that maps Pinocchio conventions to MuJoCo conventions and back.

A robot with a free-flyer base and one-dof joints is described twice:

================  ==========================================  =========================================
                  Pinocchio (``q``, ``v``, ``tau``)           MuJoCo (``qpos``, ``qvel``, ``ctrl``)
================  ==========================================  =========================================
joint order       model order (TALOS: legs, torso, arms,      file order of the URDF (TALOS: torso,
                  head)                                       head, arms, legs); mapped by joint name
base orientation  ``q[3:7]`` quaternion ``(x, y, z, w)``      ``qpos[3:7]`` quaternion ``(w, x, y, z)``
base linear vel.  ``v[0:3]`` in the **base** frame            ``qvel[0:3]`` in the **world** frame
base angular vel. ``v[3:6]`` in the base frame                ``qvel[3:6]`` in the base frame
actuators         ``tau`` = ``v[6:]`` order (actuated joints)  ``ctrl`` in actuator order
================  ==========================================  =========================================

So ``qvel = T(q) v`` with ``T = blkdiag(R_base, I3, P)`` (``P`` a permutation), kinetic energy
gives ``M_pin = Tᵀ M_mj T`` and power gives generalised forces ``f_pin = Tᵀ f_mj``.
Every map precomputes its index arrays, so a call costs a few microseconds.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

_FREE_QPOS_OF_Q = np.array([0, 1, 2, 4, 5, 6, 3])
"""Offsets in the free joint's ``qpos`` of ``q[0:7]``: ``q[3:6]`` (x, y, z) sit at 4..6, ``q[6]`` (w) at 3."""


_ONE_DOF = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


def quat_xyzw_from_wxyz(quat: np.ndarray) -> np.ndarray:
    """MuJoCo ``(w, x, y, z)`` quaternion(s) to Pinocchio ``(x, y, z, w)`` (last axis)."""
    return np.asarray(quat)[..., [1, 2, 3, 0]]


def quat_wxyz_from_xyzw(quat: np.ndarray) -> np.ndarray:
    """Pinocchio ``(x, y, z, w)`` quaternion(s) to MuJoCo ``(w, x, y, z)`` (last axis)."""
    return np.asarray(quat)[..., [3, 0, 1, 2]]


class JointMap:
    """Index maps between a Pinocchio model and a MuJoCo model of the same robot.

    Built from a ``pinocchio.Model`` and an ``mujoco.MjModel``; joints are matched by name.
    The Pinocchio model must have a free-flyer root (named anything) and one-dof joints
    otherwise; the MuJoCo model a free joint on the same base body and hinge/slide joints with
    the same names. MuJoCo may have more joints (free bodies of a scene): they are ignored, and
    the ``qpos``/``qvel`` given to the maps must be the full MuJoCo vectors.

    The *actuated order* is Pinocchio's order of ``q[7:]`` / ``v[6:]``: joint torques, encoder
    readings and position targets are exchanged in that order.
    """

    def __init__(self, pin_model: Any, mj_model: mujoco.MjModel):
        self.nq, self.nv = int(pin_model.nq), int(pin_model.nv)
        self.na = self.nv - 6
        if pin_model.njoints < 2 or pin_model.joints[1].shortname() != "JointModelFreeFlyer":
            raise ValueError("JointMap needs a Pinocchio model with a free-flyer root joint")
        free = [j for j in range(mj_model.njnt) if int(mj_model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
        if not free:
            raise ValueError("JointMap needs a MuJoCo model with a free joint on the robot base")
        self.free_joint = free[0]
        self.base_body = int(mj_model.jnt_bodyid[self.free_joint])
        free_qadr = int(mj_model.jnt_qposadr[self.free_joint])
        free_vadr = int(mj_model.jnt_dofadr[self.free_joint])
        self.joint_names: list[str] = []
        qadr, vadr = [], []
        for jid in range(2, pin_model.njoints):
            joint = pin_model.joints[jid]
            name = pin_model.names[jid]
            if joint.nq != 1 or joint.nv != 1:
                raise ValueError(f"JointMap supports one-dof joints only; {name} has nq={joint.nq}")
            mj_id = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if mj_id < 0:
                raise ValueError(f"joint {name!r} of the Pinocchio model is not in the MuJoCo model")
            if int(mj_model.jnt_type[mj_id]) not in _ONE_DOF:
                raise ValueError(f"MuJoCo joint {name!r} is not a one-dof joint")
            self.joint_names.append(name)
            qadr.append(int(mj_model.jnt_qposadr[mj_id]))
            vadr.append(int(mj_model.jnt_dofadr[mj_id]))
        self.mj_nq, self.mj_nv = int(mj_model.nq), int(mj_model.nv)
        #: qpos indices of the actuated joints, in actuated (Pinocchio) order
        self.qpos_joints = np.array(qadr, dtype=np.intp)
        #: qvel indices of the actuated joints, in actuated (Pinocchio) order
        self.qvel_joints = np.array(vadr, dtype=np.intp)
        #: qpos index of each entry of q: ``q = qpos[qpos_index]``, ``qpos[qpos_index] = q``
        self.qpos_index = np.concatenate([free_qadr + _FREE_QPOS_OF_Q, self.qpos_joints])
        #: qvel index of each entry of v (before the base linear velocity is rotated)
        self.qvel_index = np.concatenate([free_vadr + np.arange(6), self.qvel_joints])
        self._qadr_free = free_qadr
        self._vadr_free = free_vadr
        # actuators: ctrl[k] drives actuated joint ctrl_index[k]
        names = set(self.joint_names)
        ctrl_index = []
        for k in range(mj_model.nu):
            jid = int(mj_model.actuator_trnid[k, 0])
            jname = mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, jid)
            if int(mj_model.actuator_trntype[k]) != int(mujoco.mjtTrn.mjTRN_JOINT) or jname not in names:
                raise ValueError(f"actuator {k} does not drive one actuated joint of the Pinocchio model")
            ctrl_index.append(self.joint_names.index(jname))
        #: ``ctrl = tau[ctrl_index]`` (actuator order from actuated order)
        self.ctrl_index = np.array(ctrl_index, dtype=np.intp)
        #: ``tau = ctrl_like[actuated_index]`` (actuated order from actuator order)
        self.actuated_index = np.full(self.na, -1, dtype=np.intp)
        self.actuated_index[self.ctrl_index] = np.arange(len(ctrl_index))
        self._quat = np.zeros(4)
        self._vec = np.zeros(3)

    # -- configuration ------------------------------------------------------------------------
    def qpos_from_q(self, q: np.ndarray, qpos: np.ndarray | None = None) -> np.ndarray:
        """MuJoCo ``qpos`` from Pinocchio ``q``; writes into ``qpos`` (full MuJoCo vector) if given."""
        out = np.zeros(self.mj_nq) if qpos is None else qpos
        out[self.qpos_index] = q
        return out

    def q_from_qpos(self, qpos: np.ndarray) -> np.ndarray:
        """Pinocchio ``q`` from MuJoCo ``qpos`` (a new array)."""
        return qpos[self.qpos_index]

    # -- velocity -----------------------------------------------------------------------------
    def base_quat_wxyz(self, qpos: np.ndarray) -> np.ndarray:
        """The base orientation quaternion ``(w, x, y, z)`` held in ``qpos``."""
        return qpos[self._qadr_free + 3:self._qadr_free + 7]

    def qvel_from_v(self, q: np.ndarray, v: np.ndarray, qvel: np.ndarray | None = None) -> np.ndarray:
        """MuJoCo ``qvel`` from Pinocchio ``(q, v)``: the base linear velocity goes to the world frame."""
        out = np.zeros(self.mj_nv) if qvel is None else qvel
        out[self.qvel_index] = v
        quat = self._quat
        quat[0] = q[6]
        quat[1:] = q[3:6]
        mujoco.mju_rotVecQuat(self._vec, np.ascontiguousarray(v[:3]), quat)
        out[self._vadr_free:self._vadr_free + 3] = self._vec
        return out

    def v_from_qvel(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """Pinocchio ``v`` from MuJoCo ``(qpos, qvel)``: the base linear velocity goes to the base frame."""
        v = qvel[self.qvel_index]
        quat = self._quat
        mujoco.mju_negQuat(quat, np.ascontiguousarray(self.base_quat_wxyz(qpos)))
        mujoco.mju_rotVecQuat(self._vec, np.ascontiguousarray(v[:3]), quat)
        v[:3] = self._vec
        return v

    def velocity_transform(self, q: np.ndarray) -> np.ndarray:
        """The matrix ``T(q)`` (``mj_nv x nv``) with ``qvel = T v``; ``M_pin = Tᵀ M_mj T``."""
        T = np.zeros((self.mj_nv, self.nv))
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, np.ascontiguousarray(quat_wxyz_from_xyzw(q[3:7])))
        T[self._vadr_free:self._vadr_free + 3, 0:3] = rot.reshape(3, 3)
        T[self._vadr_free + 3:self._vadr_free + 6, 3:6] = np.eye(3)
        T[self.qvel_joints, np.arange(6, self.nv)] = 1.0
        return T

    def generalized_force_from_qfrc(self, q: np.ndarray, qfrc: np.ndarray) -> np.ndarray:
        """Pinocchio generalised force ``Tᵀ f_mj`` from a MuJoCo ``qfrc`` vector (same power)."""
        f = qfrc[self.qvel_index]
        quat = self._quat  # conjugate of the base orientation: world frame -> base frame
        quat[0] = q[6]
        quat[1:] = -q[3:6]
        mujoco.mju_rotVecQuat(self._vec, np.ascontiguousarray(f[:3]), quat)
        f[:3] = self._vec
        return f

    # -- actuation and encoders -----------------------------------------------------------------
    def ctrl_from_tau(self, tau: np.ndarray) -> np.ndarray:
        """MuJoCo ``ctrl`` (actuator order) from torques in actuated (Pinocchio) order."""
        return tau[self.ctrl_index]

    def tau_from_actuators(self, values: np.ndarray) -> np.ndarray:
        """Actuated (Pinocchio) order from a per-actuator vector (``actuator_force``, ``ctrl``)."""
        return values[self.actuated_index]

    def joint_positions(self, qpos: np.ndarray) -> np.ndarray:
        """Actuated joint positions (``q[7:]``) from MuJoCo ``qpos``."""
        return qpos[self.qpos_joints]

    def joint_velocities(self, qvel: np.ndarray) -> np.ndarray:
        """Actuated joint velocities (``v[6:]``) from MuJoCo ``qvel``."""
        return qvel[self.qvel_joints]
