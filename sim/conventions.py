"""The one place that maps Pinocchio conventions to MuJoCo conventions and back.

A robot with one-dof joints, on a free-flyer base or a fixed one, is described twice:

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

A fixed-base robot (an arm; Pinocchio's model has no free-flyer root, MuJoCo's welds the root link
to the world) has no base rows: ``q``, ``v`` and ``tau`` are the joints', ``T = P``.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from dgraph.entities.robot.loading import has_free_flyer

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
    The Pinocchio model has a free-flyer root (named anything) or a fixed base, and one-dof
    joints otherwise; the MuJoCo model, for a free-flyer, a free joint on the same base body, and
    hinge/slide joints with the same names. MuJoCo may have more joints (free bodies of a scene):
    they are ignored, and the ``qpos``/``qvel`` given to the maps must be the full MuJoCo vectors.

    The *actuated order* is Pinocchio's order of ``q[7:]`` / ``v[6:]`` (a fixed base: ``q``,
    ``v``): joint torques, encoder readings and position targets are exchanged in that order.
    ``floating_base`` tells which; ``base_body`` is the MuJoCo body of the free joint, or the
    root link welded to the world.
    """

    def __init__(self, pin_model: Any, mj_model: mujoco.MjModel):
        self.nq, self.nv = int(pin_model.nq), int(pin_model.nv)
        self.floating_base = has_free_flyer(pin_model)
        n_base = 6 if self.floating_base else 0
        self.na = self.nv - n_base
        if self.floating_base:
            free = [j for j in range(mj_model.njnt) if int(mj_model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
            if not free:
                raise ValueError("JointMap needs a MuJoCo model with a free joint on the robot base")
            self.free_joint = free[0]
            self.base_body = int(mj_model.jnt_bodyid[self.free_joint])
            free_qadr = int(mj_model.jnt_qposadr[self.free_joint])
            free_vadr = int(mj_model.jnt_dofadr[self.free_joint])
        else:
            self.free_joint = -1
            free_qadr = free_vadr = -1
        self.joint_names: list[str] = []
        qadr, vadr = [], []
        for jid in range(2 if self.floating_base else 1, pin_model.njoints):
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
        base_q, base_v = (free_qadr + _FREE_QPOS_OF_Q, free_vadr + np.arange(6)) if self.floating_base else ((), ())
        #: qpos index of each entry of q: ``q = qpos[qpos_index]``, ``qpos[qpos_index] = q``
        self.qpos_index = np.concatenate([base_q, self.qpos_joints]).astype(np.intp)
        #: qvel index of each entry of v (before the base linear velocity is rotated)
        self.qvel_index = np.concatenate([base_v, self.qvel_joints]).astype(np.intp)
        if not self.floating_base:  # the root link, welded to the world: the top body above the first joint
            body = int(mj_model.jnt_bodyid[mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, self.joint_names[0])])
            self.base_body = int(mj_model.body_rootid[body])
            if int(mj_model.body_jntnum[self.base_body]) and int(mj_model.jnt_type[mj_model.body_jntadr[
                    self.base_body]]) == int(mujoco.mjtJoint.mjJNT_FREE):
                raise ValueError("the Pinocchio model has a fixed base but the MuJoCo model a free joint on "
                                 f"{mj_model.body(self.base_body).name!r}")
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
        """The base orientation quaternion ``(w, x, y, z)`` held in ``qpos`` (a floating base)."""
        if not self.floating_base:
            raise ValueError("a fixed-base robot has no base orientation in qpos")
        return qpos[self._qadr_free + 3:self._qadr_free + 7]

    def qvel_from_v(self, q: np.ndarray, v: np.ndarray, qvel: np.ndarray | None = None) -> np.ndarray:
        """MuJoCo ``qvel`` from Pinocchio ``(q, v)``: the base linear velocity goes to the world frame."""
        out = np.zeros(self.mj_nv) if qvel is None else qvel
        out[self.qvel_index] = v
        if not self.floating_base:
            return out
        quat = self._quat
        quat[0] = q[6]
        quat[1:] = q[3:6]
        mujoco.mju_rotVecQuat(self._vec, np.ascontiguousarray(v[:3]), quat)
        out[self._vadr_free:self._vadr_free + 3] = self._vec
        return out

    def v_from_qvel(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """Pinocchio ``v`` from MuJoCo ``(qpos, qvel)``: the base linear velocity goes to the base frame."""
        v = qvel[self.qvel_index]
        if not self.floating_base:
            return v
        quat = self._quat
        mujoco.mju_negQuat(quat, np.ascontiguousarray(self.base_quat_wxyz(qpos)))
        mujoco.mju_rotVecQuat(self._vec, np.ascontiguousarray(v[:3]), quat)
        v[:3] = self._vec
        return v

    def velocity_transform(self, q: np.ndarray) -> np.ndarray:
        """The matrix ``T(q)`` (``mj_nv x nv``) with ``qvel = T v``; ``M_pin = Tᵀ M_mj T``."""
        T = np.zeros((self.mj_nv, self.nv))
        n_base = self.nv - self.na
        T[self.qvel_joints, np.arange(n_base, self.nv)] = 1.0
        if not self.floating_base:
            return T
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, np.ascontiguousarray(quat_wxyz_from_xyzw(q[3:7])))
        T[self._vadr_free:self._vadr_free + 3, 0:3] = rot.reshape(3, 3)
        T[self._vadr_free + 3:self._vadr_free + 6, 3:6] = np.eye(3)
        return T

    def generalized_force_from_qfrc(self, q: np.ndarray, qfrc: np.ndarray) -> np.ndarray:
        """Pinocchio generalised force ``Tᵀ f_mj`` from a MuJoCo ``qfrc`` vector (same power)."""
        f = qfrc[self.qvel_index]
        if not self.floating_base:
            return f
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
