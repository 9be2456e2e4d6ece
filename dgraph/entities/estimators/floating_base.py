"""FloatingBaseEstimator: base pose and velocity from the IMU, joint encoders and foot F/T sensors."""

from __future__ import annotations

from typing import Any

import numpy as np

import dgraph as dg
from dgraph.entities.estimators.leg_odometry import (
    RelativeKinematics,
    complementary_alpha,
    contact_hysteresis,
    default_imu_frame,
    frame_id,
    matrix_to_quat,
    standing_configuration,
)
from dgraph.entities.robot.robot_state import load_model


class Estimate:
    """Everything computed at one tick (the ``estimate`` output); read-only for readers."""

    __slots__ = ("anchors", "base_velocity_world", "contacts", "next_position", "next_velocity", "q", "v")

    def __init__(self, q: np.ndarray, v: np.ndarray, contacts: list[bool], anchors: list[np.ndarray | None],
                 base_velocity_world: np.ndarray, next_velocity: np.ndarray, next_position: np.ndarray):
        self.q, self.v, self.contacts, self.anchors = q, v, contacts, anchors
        self.base_velocity_world = base_velocity_world
        self.next_velocity, self.next_position = next_velocity, next_position


@dg.register
class FloatingBaseEstimator(dg.Entity):
    r"""Floating-base estimator (in the spirit of Flayols et al., 2017): IMU + leg odometry.

    Uses only the IMU, the joint encoders and the foot force/torque sensors (for contact
    detection), never the true base. Notation (``leg_odometry``): ``W`` world, ``B`` base,
    ``I`` IMU, ``F`` foot (sole) frame, ``S`` ankle F/T sensor frame; ``R_XY``, ``r_XY``
    rotation and position of ``Y`` in ``X``; ``r_BX``, ``R_BX`` and the velocities relative to
    the base ``rd_BX = J_X^lin(q_j) qd_j``, ``w_BX = J_X^ang(q_j) qd_j`` (in ``B``) come from one
    forward kinematics of the encoders ``(q_j, qd_j)`` with the base at the identity.

    At tick ``t``, from the inputs at ``t`` and the states at ``t`` (nothing else):

    1. Orientation: ``R_WB = R_WI R_BI^T`` (``R_WI`` from the IMU quaternion; the IMU is on the
       torso, so ``R_BI`` depends on the torso joints).
    2. Angular velocity (gyro ``w_g`` in ``I``): ``w_g = R_BI^T (w_B + w_BI)``, so
       ``w_B = R_BI w_g - w_BI`` (base frame, Pinocchio's ``v[3:6]``); ``w_W = R_WB w_B``.
    3. Contacts: normal force ``f_k = e_z . (R_WB R_BS_k f_S_k)`` (sensor force along the world
       vertical); ``c_k = f_k > f_on or (a_k and f_k > f_off)`` (hysteresis), ``a_k`` the state
       "foot k was in contact at t-1 and has an anchor ``p_k``".
    4. Position: weights ``w_k = f_k / sum f`` over the feet in contact. Over the feet that
       stay in contact (``c_k and a_k``): ``p_WB = sum w_k (p_k - R_WB r_BF_k)`` (normalised
       weights); with none, ``p_WB`` is the prediction state ``p~``. A foot touching down
       (``c_k and not a_k``) is anchored at ``p_k = p_WB + R_WB r_BF_k``, consistent with
       ``p_WB``; a foot off the ground is ignored.
    5. Kinematic velocity (feet in contact do not move):
       ``0 = v_WB + w_W x (R_WB r_BF_k) + R_WB rd_BF_k``, so
       ``v_kin = -sum w_k (w_W x (R_WB r_BF_k) + R_WB rd_BF_k)``, carried to the IMU point:
       ``v_I,kin = v_kin + w_W x (R_WB r_BI) + R_WB rd_BI``.
    6. Complementary filter at the IMU point (where the accelerometer measures, so no lever
       arm is neglected), with ``a_W = R_WI a_acc + g`` (``a_acc`` the proper acceleration,
       ``g = (0, 0, -9.81)``), ``x`` the predicted IMU velocity state,
       ``alpha = tau / (tau + dt)``, ``tau = 1 / (2 pi cutoff_frequency)``::

           v_I(t)   = alpha x(t) + (1 - alpha) v_I,kin(t)     (x(t) alone with no contact)
           x(t + 1) = v_I(t) + dt a_W(t)

       i.e. ``V_I = tau s / (1 + tau s) (A_W / s) + 1 / (1 + tau s) V_I,kin``: the integrated
       accelerometer above the cutoff, leg kinematics below. ``cutoff_frequency = inf`` is
       kinematics only. At the first tick only (state ``i`` false) there is no prediction
       yet: ``v_I = v_I,kin`` (``alpha = 0``) if a foot touches, else ``x(0)`` (the robot
       starts at ``v0 = 0``); from then on the prediction is kept, in flight too, so a robot
       that lands keeps the velocity it fell with.
       Base velocity: ``v_WB = v_I - w_W x (R_WB r_BI) - R_WB rd_BI``.
    7. Outputs (Pinocchio conventions): ``q = [p_WB, quat_xyzw(R_WB), q_j]``,
       ``v = [R_WB^T v_WB, w_B, qd_j]``.

    Tick transition (``prepare_state`` at ``t`` stages, ``commit_state`` publishes at ``t + 1``;
    flags and anchors only when they change):
    ``a_k(t + 1) = c_k(t)``, ``p_k(t + 1) = p_k`` (the anchor used at ``t``; kept when off),
    ``x(t + 1)`` as above, ``i(t + 1) = i(t) or any c_k(t)``, ``p~(t + 1) = p_WB(t) + dt v_WB(t)``
    (dead reckoning when no foot is on the ground). Initial state: no anchor, ``i`` false,
    ``x = 0`` (used only if no foot touches at tick 0: the robot then starts at rest),
    ``p~ = q0[:3]``; the feet in contact at tick 0 are anchored from ``q0[:3]`` and the IMU
    orientation.

    Parameters: ``model``, ``foot_frames``, ``ft_frames``, ``imu_frame``, ``contact_force_on``,
    ``contact_force_off``, ``cutoff_frequency``, ``q0``, ``dt``.
    Inputs: ``imu_orientation``, ``imu_angular_velocity``, ``imu_linear_acceleration``,
    ``encoder_position``, ``encoder_velocity``, ``ft_left_ankle``, ``ft_right_ankle``.
    Outputs: ``q``, ``v``, ``contact_left``, ``contact_right``, ``base_velocity_world``,
    ``estimate`` (everything, as an object). States: ``anchor_left``, ``anchor_right``,
    ``anchored_left``, ``anchored_right``, ``velocity_prediction``, ``velocity_initialised``,
    ``position_prediction``.
    """

    has_state = True

    model = dg.Param("talos", kind="object", doc="example-robot-data robot name or pinocchio.Model")
    foot_frames = dg.Param(["left_sole_link", "right_sole_link"], kind="str_list",
                           doc="left and right foot frames whose origin is anchored while in contact")
    ft_frames = dg.Param(["leg_left_6_joint", "leg_right_6_joint"], kind="str_list",
                         doc="left and right ankle F/T sensor frames")
    imu_frame = dg.Param(None, kind="str", doc="IMU frame (default: imu_link if the model has it, else the base)")
    contact_force_on = dg.Param(100.0, kind="float", minimum=0.0, doc="normal force (N) above which a foot touches")
    contact_force_off = dg.Param(50.0, kind="float", minimum=0.0,
                                 doc="normal force (N) below which a foot in contact leaves (<= on)")
    cutoff_frequency = dg.Param(1.0, kind="float", minimum=1e-6,
                                doc="complementary filter cutoff (Hz): kinematics below, accelerometer above")
    q0 = dg.Param(None, kind="vector", doc="initial configuration; only the base position q0[:3] is used "
                                           "(default: half-sitting with the soles at z = 0)")
    dt = dg.Param(None, kind="float", doc="tick period in s (default: the graph's dt)")

    imu_orientation = dg.Input(shape=(4,), doc="quaternion [x, y, z, w] of the IMU frame in the world")
    imu_angular_velocity = dg.Input(shape=(3,), doc="gyro, IMU frame (rad/s)")
    imu_linear_acceleration = dg.Input(shape=(3,), doc="accelerometer: proper acceleration in the IMU frame (m/s2)")
    encoder_position = dg.Input(shape=("nj",), doc="joint positions, model order (q[7:])")
    encoder_velocity = dg.Input(shape=("nj_v",), doc="joint velocities, model order (v[6:])")
    ft_left_ankle = dg.Input(shape=(6,), doc="left ankle wrench [force, torque] in its sensor frame")
    ft_right_ankle = dg.Input(shape=(6,), doc="right ankle wrench [force, torque] in its sensor frame")

    anchor_left = dg.State(shape=(3,), doc="world position of the left foot frame while in contact")
    anchor_right = dg.State(shape=(3,), doc="world position of the right foot frame while in contact")
    anchored_left = dg.State(shape=(), dtype="bool", doc="left foot was in contact at t-1 (anchor valid)")
    anchored_right = dg.State(shape=(), dtype="bool", doc="right foot was in contact at t-1 (anchor valid)")
    velocity_prediction = dg.State(shape=(3,), doc="complementary filter: predicted IMU velocity in the world")
    velocity_initialised = dg.State(shape=(), dtype="bool",
                                    doc="velocity_prediction holds a prediction (a foot has touched)")
    position_prediction = dg.State(shape=(3,), doc="dead-reckoned base position (used with no contact)")

    def configure(self) -> None:
        """Load the model, resolve the frames, size the encoder inputs."""
        entity = f"{self.name} ({self.type_name})"
        self.pin_model = model = load_model(self.model, self.name)
        if model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer":
            raise dg.ParamError(f"{entity}: the model's first joint must be a free flyer", entity=self.name)
        self.nq, self.nv = model.nq, model.nv
        self.nj, self.nj_v = model.nq - 7, model.nv - 6
        for param in ("foot_frames", "ft_frames"):
            if len(getattr(self, param)) != 2:
                raise dg.ParamError(f"{entity}: parameter {param!r} needs two frames (left, right), got "
                                    f"{getattr(self, param)}", entity=self.name)
        if self.contact_force_off > self.contact_force_on:
            raise dg.ParamError(f"{entity}: contact_force_off ({self.contact_force_off}) must not exceed "
                                f"contact_force_on ({self.contact_force_on})", entity=self.name)
        self.imu_frame_name = self.imu_frame or default_imu_frame(model)
        self._foot = [frame_id(model, f, self.name, "foot_frames", entity) for f in self.foot_frames]
        self._ft = [frame_id(model, f, self.name, "ft_frames", entity) for f in self.ft_frames]
        self._imu = frame_id(model, self.imu_frame_name, self.name, "imu_frame", entity)
        if self.q0 is not None and self.q0.shape != (self.nq,):
            raise dg.ParamError(f"{entity}: q0 has shape {self.q0.shape}, expected ({self.nq},)", entity=self.name)
        self._kinematics = RelativeKinematics(model, dict.fromkeys([*self._foot, *self._ft, self._imu]))
        self._pin = self._kinematics._pin
        self._lwa = self._kinematics._lwa
        self._gravity = np.array(model.gravity.linear, dtype=float)

    def setup(self) -> None:
        """Index the per-foot ports (left, right)."""
        self._ft_in = (self.ft_left_ankle, self.ft_right_ankle)
        self._anchor = (self.anchor_left, self.anchor_right)
        self._anchored = (self.anchored_left, self.anchored_right)
        self._pending: list[dg.State] = []

    def reset(self) -> None:
        """No anchor, IMU at rest, base at ``q0[:3]``."""
        q0 = self.q0 if self.q0 is not None else standing_configuration(self.pin_model, self.foot_frames)
        for k in range(2):
            self._anchor[k].set(np.zeros(3), 0)
            self._anchored[k].set(False, 0)
        self.velocity_prediction.set(np.zeros(3), 0)
        self.velocity_initialised.set(False, 0)
        self.position_prediction.set(np.array(q0[:3], dtype=float), 0)
        self._pending = []

    # -- the estimate -----------------------------------------------------------------------
    @dg.output(dtype="object", depends=(
        "imu_orientation", "imu_angular_velocity", "imu_linear_acceleration", "encoder_position",
        "encoder_velocity", "ft_left_ankle", "ft_right_ankle", "anchor_left", "anchor_right",
        "anchored_left", "anchored_right", "velocity_prediction", "velocity_initialised", "position_prediction"))
    def estimate(self, t: int) -> Any:
        """Everything estimated at ``t`` (an ``Estimate``: q, v, contacts, anchors, next states)."""
        q_j, qd_j = self.encoder_position(t), self.encoder_velocity(t)
        pin, kin, lwa = self._pin, self._kinematics, self._lwa
        model, data = kin.model, kin.data
        kin.forward(q_j, qd_j)  # frames relative to the base, in B (see RelativeKinematics)
        imu = pin.updateFramePlacement(model, data, self._imu)
        imu_motion = pin.getFrameVelocity(model, data, self._imu, lwa)
        left, right = self._foot
        # rows: r_BF_left, r_BF_right, r_BI, then their velocities rd_BF_left, rd_BF_right, rd_BI
        frames = np.array([pin.updateFramePlacement(model, data, left).translation,
                           pin.updateFramePlacement(model, data, right).translation, imu.translation,
                           pin.getFrameVelocity(model, data, left, lwa).linear,
                           pin.getFrameVelocity(model, data, right, lwa).linear, imu_motion.linear])
        r_bi = imu.rotation

        quat = pin.Quaternion(self.imu_orientation(t))  # coefficients x, y, z, w
        r_wi = quat.normalized().toRotationMatrix()
        r_wb = r_wi.dot(r_bi.T)                                             # (1)
        w_b = r_bi.dot(self.imu_angular_velocity(t)) - imu_motion.angular  # (2)
        # w_W x (R_WB r) + R_WB rd = R_WB (w_B x r + rd): velocities relative to the base in B
        # (rows: r^T S(w_B)^T = (w_B x r)^T), then every row rotated to the world at once
        frames[3:] += frames[:3].dot(pin.skew(w_b).T)
        world = frames.dot(r_wb.T)  # R_WB r_BF_k, R_WB r_BI, the feet's terms of (5), the lever arm
        vertical = r_wb[2]                                                  # e_z in B (a row of R_WB)

        forces, contacts, anchored = [0.0, 0.0], [False, False], [False, False]
        for k in range(2):                                                  # (3)
            force = self._ft_in[k](t)[:3]
            f_n = float(vertical.dot(pin.updateFramePlacement(model, data, self._ft[k]).rotation.dot(force)))
            anchored[k] = bool(self._anchored[k](t))
            forces[k] = f_n
            contacts[k] = contact_hysteresis(f_n, anchored[k], self.contact_force_on, self.contact_force_off)

        staying = [k for k in range(2) if contacts[k] and anchored[k]]
        anchors = [self._anchor[k](t) if k in staying else None for k in range(2)]
        if len(staying) == 2:                                               # (4)
            total = forces[0] + forces[1]
            weights = np.array([forces[0] / total, forces[1] / total])
            p_wb = weights.dot(np.array(anchors) - world[:2])
        elif staying:
            k = staying[0]
            p_wb = anchors[k] - world[k]
        else:
            p_wb = np.array(self.position_prediction(t), dtype=float)
        for k in range(2):
            if contacts[k] and anchors[k] is None:
                anchors[k] = p_wb + world[k]

        lever = world[5]                                                    # v_I - v_WB
        x = self.velocity_prediction(t)
        if contacts[0] or contacts[1]:                                      # (5)
            total = (forces[0] if contacts[0] else 0.0) + (forces[1] if contacts[1] else 0.0)
            weights = np.array([forces[0] / total if contacts[0] else 0.0, forces[1] / total if contacts[1] else 0.0])
            v_i_kin = lever - weights.dot(world[3:5])
            alpha = complementary_alpha(self.cutoff_frequency, self.dt) if self.velocity_initialised(t) else 0.0
            v_i = alpha * x + (1.0 - alpha) * v_i_kin                       # (6)
        else:
            v_i = np.array(x, dtype=float)
        v_wb = v_i - lever
        a_w = r_wi.dot(self.imu_linear_acceleration(t)) + self._gravity

        q = np.concatenate([p_wb, matrix_to_quat(r_wb), q_j])               # (7)
        v = np.concatenate([v_wb.dot(r_wb), w_b, qd_j])
        dt = self.dt
        return Estimate(q, v, contacts, anchors, v_wb, v_i + dt * a_w, p_wb + dt * v_wb)

    @dg.output(shape=("nq",), depends=("estimate",))
    def q(self, t: int) -> Any:
        """Estimated configuration ``[base position, base quaternion xyzw, joints]``."""
        return self.estimate(t).q

    @dg.output(shape=("nv",), depends=("estimate",))
    def v(self, t: int) -> Any:
        """Estimated velocity ``[base linear (base frame), base angular (base frame), joints]``."""
        return self.estimate(t).v

    @dg.output(shape=(), dtype="bool", depends=("estimate",))
    def contact_left(self, t: int) -> Any:
        """The left foot is in contact (force hysteresis)."""
        return self.estimate(t).contacts[0]

    @dg.output(shape=(), dtype="bool", depends=("estimate",))
    def contact_right(self, t: int) -> Any:
        """The right foot is in contact (force hysteresis)."""
        return self.estimate(t).contacts[1]

    @dg.output(shape=(3,), depends=("estimate",))
    def base_velocity_world(self, t: int) -> Any:
        """Fused linear velocity of the base origin in the world frame."""
        return self.estimate(t).base_velocity_world

    # -- tick transition ----------------------------------------------------------------------
    def prepare_state(self, t: int) -> None:
        """Stage the filter states, and the contact flags and anchors that change, from the values at ``t``.

        A flag or an anchor is staged (and committed) only when its value changes (touch-down,
        lift-off): its ``time`` is then the tick of the change, and a steady stance costs two
        states per tick, not seven.
        """
        est = self.estimate(t)
        pending = [self.velocity_prediction, self.position_prediction]
        self.velocity_prediction.stage(est.next_velocity)
        self.position_prediction.stage(est.next_position)
        for k in range(2):
            if est.contacts[k] != self._anchored[k](t):
                self._anchored[k].stage(est.contacts[k])
                pending.append(self._anchored[k])
                if est.contacts[k]:
                    self._anchor[k].stage(est.anchors[k])
                    pending.append(self._anchor[k])
        if not self.velocity_initialised(t):  # after the first tick the prediction is meaningful,
            self.velocity_initialised.stage(True)  # in flight too (the robot starts at v0)
            pending.append(self.velocity_initialised)
        self._pending = pending

    def commit_state(self, t_next: int) -> None:
        """Publish the staged states at ``t + 1``."""
        for state in self._pending:
            state.commit(t_next)
        self._pending = []

__all__ = ["Estimate", "FloatingBaseEstimator"]
