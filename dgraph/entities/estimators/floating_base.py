"""FloatingBaseEstimator: base pose and velocity from the IMU, joint encoders and foot F/T sensors."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.estimators.leg_odometry import (
    RelativeKinematics,
    complementary_alpha,
    default_imu_frame,
    frame_id,
    standing_configuration,
)
from dgraph.entities.estimators.sensor_guard import Channel, SensorGuard
from dgraph.entities.robot.loading import has_free_flyer, load_model
from dgraph.entities.robot.rotations import matrix_to_quat, quat_to_rows
from dgraph.signals.spec import non_finite
from dgraph.signals.value_types import value_type

SENSOR_INPUTS = ("imu_orientation", "imu_angular_velocity", "imu_linear_acceleration", "encoder_position",
                 "encoder_velocity", "ft_left_ankle", "ft_right_ankle")
"""The sensor inputs, in the order the guard checks them and :meth:`FloatingBaseEstimator.readings` returns them."""

_HEAD = 9
"""The floats before ``q`` in the estimate's array: ``x(t + 1)``, ``p~(t + 1)`` (the prediction state), ``v_WB``."""


@value_type
class Estimate:
    """Everything computed at one tick (the ``estimate`` output); read-only for readers."""

    __slots__ = ("anchored", "anchors", "base_velocity_world", "contacts", "next_prediction", "q", "readings",
                 "sensor_faults", "v")

    def __init__(self, q: np.ndarray, v: np.ndarray, contacts: list[bool], anchored: list[bool],
                 anchors: list[np.ndarray | None], base_velocity_world: np.ndarray, next_prediction: np.ndarray,
                 readings: list[np.ndarray], sensor_faults: int = 0):
        self.q, self.v, self.contacts, self.anchored, self.anchors = q, v, contacts, anchored, anchors
        self.base_velocity_world, self.next_prediction = base_velocity_world, next_prediction
        self.readings, self.sensor_faults = readings, sensor_faults


@dg.register
class FloatingBaseEstimator(dg.Entity):
    r"""Floating-base estimator (in the spirit of Flayols et al., 2017): IMU + leg odometry.

    Uses only the IMU, the joint encoders and the foot force/torque sensors (for contact
    detection), never the true base. Notation (``leg_odometry``): ``W`` world, ``B`` base,
    ``I`` IMU, ``F`` foot (sole) frame, ``S`` ankle F/T sensor frame; ``R_XY``, ``r_XY``
    rotation and position of ``Y`` in ``X``; ``r_BX``, ``R_BX`` and the velocities relative to
    the base ``rd_BX = J_X^lin(q_j) qd_j = R_BX v_X``, ``w_BX = J_X^ang(q_j) qd_j = R_BX w_X`` (in
    ``B``; ``v_X``, ``w_X`` the frame's velocity in ``X``: (K) of ``RelativeKinematics``) come from
    one forward kinematics of the encoders ``(q_j, qd_j)`` with the base at the identity.

    At tick ``t``, from the inputs at ``t`` and the states at ``t`` (nothing else):

    1. Orientation: ``R_WB = R_WI R_BI^T`` (``R_WI`` from the IMU quaternion; the IMU is on the
       torso, so ``R_BI`` depends on the torso joints).
    2. Angular velocity (gyro ``w_g`` in ``I``): ``w_g = R_BI^T (w_B + w_BI)``, so
       ``w_B = R_BI w_g - w_BI = R_BI (w_g - w_I)`` (base frame, Pinocchio's ``v[3:6]``).
    3. Contacts: normal force ``f_k = e_z . (R_WB R_BS_k f_S_k)`` (sensor force along the world
       vertical); ``c_k = f_k > f_on or (a_k and f_k > f_off)`` (hysteresis), ``a_k`` the state
       "foot k was in contact at t-1 and has an anchor ``p_k``".
    4. Position: weights ``w_k = f_k / sum f`` over the feet in contact. Over the feet that
       stay in contact (``c_k and a_k``): ``p_WB = sum w_k (p_k - R_WB r_BF_k)`` (normalised
       weights); with none, ``p_WB`` is the prediction state ``p~``. A foot touching down
       (``c_k and not a_k``) is anchored at ``p_k = p_WB + R_WB r_BF_k``, consistent with
       ``p_WB``; a foot off the ground is ignored.
    5. Kinematic velocity (feet in contact do not move): the velocity of a point ``X`` fixed on
       the robot is ``v_WB + R_WB u_X`` with ``u_X = w_B x r_BX + R_BX v_X`` (in ``B``); a foot in
       contact gives ``0 = v_WB + R_WB u_F_k`` and the IMU point moves at
       ``v_I = v_WB + R_WB u_I``, so ``v_I,kin = R_WB (u_I - sum w_k u_F_k)`` (weights of (4)
       over the feet in contact).
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
       Base velocity: ``v_WB = v_I - R_WB u_I``.
    7. Outputs (Pinocchio conventions): ``q = [p_WB, quat_xyzw(R_WB), q_j]``,
       ``v = [R_WB^T v_WB, w_B, qd_j]`` with ``R_WB^T v_WB = R_WB^T v_I - u_I``.

    The 3-vector algebra is done in Python floats (a numpy call costs more than the dozen
    multiplications of a rotation); the frames come from one pass of
    :class:`~dgraph.entities.estimators.leg_odometry.RelativeKinematics`, and ``q``, ``v``, the
    next filter states and ``v_WB`` are written into one array (the outputs are slices of it).

    Tick transition (``prepare_state`` at ``t`` stages, ``commit_state`` publishes at ``t + 1``;
    flags and anchors only when they change):
    ``a_k(t + 1) = c_k(t)``, ``p_k(t + 1) = p_k`` (the anchor used at ``t``; kept when off),
    ``x(t + 1)`` as above, ``i(t + 1)`` true, ``p~(t + 1) = p_WB(t) + dt v_WB(t)``
    (dead reckoning when no foot is on the ground). Initial state: no anchor, ``i`` false,
    ``x = 0`` (used only if no foot touches at tick 0: the robot then starts at rest),
    ``p~ = q0[:3]``; the feet in contact at tick 0 are anchored from ``q0[:3]`` and the IMU
    orientation.

    Sensor readings are checked where they enter, before (1): every input goes through a
    :class:`~dgraph.entities.estimators.sensor_guard.SensorGuard` (``check_sensors``), which
    replaces a NaN, infinite, out-of-range or jumping element (and a frozen joint position) by
    its prediction and reports a fault naming ``estimator.<input>[i]`` (a frozen reading without
    a rate is reported and kept: there is nothing better): one bad sample costs one degraded tick,
    never the loop, and the filter states stay finite. Ranges: joint limits widened by
    ``joint_limit_margin``, joint speeds up to 1.5 times the model's limit plus 1 rad/s, the gyro
    up to ``gyro_range``, the accelerometer up to ``accelerometer_range``, the F/T sensors up to
    ``force_range`` and ``torque_range``; jumps per tick: ``encoder_step`` (from the position
    predicted with the encoder velocity), ``encoder_velocity_step``, ``gyro_step``, 0.05 per
    quaternion component; none for the F/T sensors (their readings jump at contact changes: up
    to 365 N per tick in the push scenario) and the accelerometer (an impact is a real spike of
    hundreds of m/s2, and the filter needs it to stop the fall velocity; a persistent offset
    within range is therefore integrated into the base velocity, as without the guard: there is
    no bias estimate); frozen after ``frozen_ticks`` identical readings, stale when a device
    state read has not been updated for ``stale_ticks`` ticks. Should a filter state still come
    out non-finite, the previous one is kept (and reported). The defaults are well above the
    largest change per tick in the shipped scenarios (encoder velocity 0.13 rad/s, gyro 0.005
    rad/s).

    Parameters: ``model``, ``foot_frames``, ``ft_frames``, ``imu_frame``, ``contact_force_on``,
    ``contact_force_off``, ``cutoff_frequency``, ``q0``, ``dt``, and the sensor checks above.
    Inputs: ``imu_orientation``, ``imu_angular_velocity``, ``imu_linear_acceleration``,
    ``encoder_position``, ``encoder_velocity``, ``ft_left_ankle``, ``ft_right_ankle``.
    Outputs: ``q``, ``v``, ``contact_left``, ``contact_right``, ``base_velocity_world``,
    ``sensor_faults`` (elements replaced at the tick), ``checked_ft_left_ankle`` and
    ``checked_ft_right_ankle`` (the wrenches as trusted, for other readers of the sensors),
    ``estimate`` (everything, as an object).
    States: ``anchor_left``, ``anchor_right``, ``anchored_left``, ``anchored_right``,
    ``prediction`` (``[x, p~]``, staged together every tick), ``velocity_initialised``.
    """

    has_state = True

    model = dg.Param("talos", kind="name_or_path", doc="example-robot-data robot name, URDF path or pinocchio.Model")
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
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    check_sensors = dg.Param(True, kind="bool", doc="check every sensor reading and replace a bad one (SensorGuard)")
    frozen_ticks = dg.Param(50, kind="int", minimum=0, doc="identical readings in a row that make a sensor "
                                                             "frozen (0: no test)")
    stale_ticks = dg.Param(20, kind="int", minimum=0, doc="ticks without an update of a sensor's source state "
                                                           "that make it stale (0: no test)")
    joint_limit_margin = dg.Param(0.1, kind="float", minimum=0.0, doc="rad beyond a joint limit still trusted")
    encoder_step = dg.Param(0.01, kind="float", minimum=0.0,
                            doc="largest change (rad) per tick of an encoder from its predicted position")
    encoder_velocity_step = dg.Param(5.0, kind="float", minimum=0.0,
                                     doc="largest change (rad/s) per tick of an encoder velocity")
    gyro_range = dg.Param(35.0, kind="float", minimum=0.0, doc="gyro measuring range (rad/s)")
    gyro_step = dg.Param(2.0, kind="float", minimum=0.0, doc="largest change (rad/s) per tick of the gyro")
    accelerometer_range = dg.Param(160.0, kind="float", minimum=0.0, doc="accelerometer range (m/s2)")
    force_range = dg.Param(10000.0, kind="float", minimum=0.0, doc="F/T force range (N)")
    torque_range = dg.Param(1000.0, kind="float", minimum=0.0, doc="F/T torque range (N m)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos",
            foot_frames: Sequence[str] = ("left_sole_link", "right_sole_link"),
            ft_frames: Sequence[str] = ("leg_left_6_joint", "leg_right_6_joint"), imu_frame: str | None = None,
            contact_force_on: float = 100.0, contact_force_off: float = 50.0, cutoff_frequency: float = 1.0,
            q0: ArrayLike | None = None, dt: float | None = None, check_sensors: bool = True, frozen_ticks: int = 50,
            stale_ticks: int = 20, joint_limit_margin: float = 0.1, encoder_step: float = 0.01,
            encoder_velocity_step: float = 5.0, gyro_range: float = 35.0, gyro_step: float = 2.0,
            accelerometer_range: float = 160.0, force_range: float = 10000.0, torque_range: float = 1000.0,
        ) -> None: ...

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
    prediction = dg.State(shape=(6,), doc="[x, p~]: the complementary filter's predicted IMU velocity in the world, "
                                          "and the dead-reckoned base position (used with no contact)")
    velocity_initialised = dg.State(shape=(), dtype="bool",
                                    doc="prediction holds a velocity prediction (after the first tick)")

    def configure(self) -> None:
        """Load the model, resolve the frames, size the encoder inputs."""
        entity = f"{self.name} ({self.type_name})"
        self.pin_model = model = load_model(self.model, self.name)
        if not has_free_flyer(model):
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
        for param in ("foot_frames", "ft_frames"):
            for name in getattr(self, param):
                frame_id(model, name, self.name, param, entity)
        frame_id(model, self.imu_frame_name, self.name, "imu_frame", entity)
        if self.q0 is not None and self.q0.shape != (self.nq,):
            raise dg.ParamError(f"{entity}: q0 has shape {self.q0.shape}, expected ({self.nq},)", entity=self.name)
        names = [*self.foot_frames, self.imu_frame_name, *self.ft_frames]
        self._kinematics = RelativeKinematics(model, names)  # left, right, IMU, sensors left, right
        self._gravity = np.array(model.gravity.linear, dtype=float).tolist()

    def setup(self) -> None:
        """Index the per-foot states (left, right); the sensor guard."""
        self._anchor = (self.anchor_left, self.anchor_right)
        self._anchored = (self.anchored_left, self.anchored_right)
        self._pending: list[dg.State] = []
        self._sensor_inputs = [getattr(self, name) for name in SENSOR_INPUTS]
        self._guard: SensorGuard | None = None  # made at the first reading (dt is the graph's)

    def _channels(self) -> list[Channel]:
        """The guarded inputs, in the order of :data:`SENSOR_INPUTS`, with their ranges and steps."""
        model, margin = self.pin_model, self.joint_limit_margin
        speed = 1.5 * np.asarray(model.velocityLimit[6:], dtype=float) + 1.0
        gyro, accelerometer = self.gyro_range, self.accelerometer_range
        wrench = np.array([self.force_range] * 3 + [self.torque_range] * 3)
        return [Channel("imu_orientation", -1.0 - 0.01, 1.0 + 0.01, 0.05, quaternion=True),
                Channel("imu_angular_velocity", -gyro, gyro, self.gyro_step),
                Channel("imu_linear_acceleration", -accelerometer, accelerometer),
                Channel("encoder_position", np.asarray(model.lowerPositionLimit[7:], dtype=float) - margin,
                        np.asarray(model.upperPositionLimit[7:], dtype=float) + margin, self.encoder_step,
                        rate="encoder_velocity"),
                Channel("encoder_velocity", -speed, speed, self.encoder_velocity_step),
                Channel("ft_left_ankle", -wrench, wrench),
                Channel("ft_right_ankle", -wrench, wrench)]

    def readings(self, t: int) -> list[np.ndarray]:
        """The sensor inputs at ``t`` as trusted (checked and repaired by the guard), in the order
        of :data:`SENSOR_INPUTS`."""
        guard = self._guard
        if guard is None:
            if not self.check_sensors:
                return [inp(t) for inp in self._sensor_inputs]
            guard = self._guard = SensorGuard(self, self._channels(), self.dt, self.frozen_ticks, self.stale_ticks)
        return guard.read(t)

    def reset(self) -> None:
        """No anchor, IMU at rest, base at ``q0[:3]``."""
        q0 = self.q0 if self.q0 is not None else standing_configuration(self.pin_model, self.foot_frames)
        self._guard = None  # no trusted reading yet
        for k in range(2):
            self._anchor[k].set(np.zeros(3), 0)
            self._anchored[k].set(False, 0)
        self.velocity_initialised.set(False, 0)
        self.prediction.set(np.array([0.0, 0.0, 0.0, *q0[:3]]), 0)
        self._pending = []

    # -- the estimate -----------------------------------------------------------------------
    @dg.output(dtype=Estimate, depends=(
        "imu_orientation", "imu_angular_velocity", "imu_linear_acceleration", "encoder_position",
        "encoder_velocity", "ft_left_ankle", "ft_right_ankle", "anchor_left", "anchor_right",
        "anchored_left", "anchored_right", "prediction", "velocity_initialised"))
    def estimate(self, t: int) -> Any:
        """Everything estimated at ``t`` (an ``Estimate``: q, v, contacts, anchors, next states)."""
        readings = self.readings(t)
        orientation, gyro, acceleration, q_j, qd_j, ft_left, ft_right = readings
        frames, motions = self._kinematics.forward(q_j, qd_j)  # R_BX, r_BX; v_X, w_X (K), for left, right, I, S_k
        r_wi = quat_to_rows(orientation.tolist())
        r_wb, w_b, u_i = _orientation(r_wi, frames[2], motions[2], gyro.tolist())  # (1), (2)
        forces = _normal_forces(r_wb, frames, ft_left.tolist(), ft_right.tolist())  # (3)
        anchored = [self.anchored_left(t), self.anchored_right(t)]
        on, off = self.contact_force_on, self.contact_force_off
        contacts = [forces[0] > on or (anchored[0] and forces[0] > off),
                    forces[1] > on or (anchored[1] and forces[1] > off)]
        p_wb, anchors = self._position(t, r_wb, frames, forces, contacts, anchored)                    # (4)
        dt = self.dt
        if contacts[0] or contacts[1]:
            v_i = self._fused_velocity(t, dt, r_wb, w_b, u_i, frames, motions, forces, contacts)          # (5), (6)
        else:
            v_i = self.prediction(t)[:3].tolist()
        values = self._values(dt, q_j, qd_j, acceleration, r_wi, r_wb, w_b, u_i, p_wb, v_i)             # (6), (7)
        v_start = _HEAD + self.nq
        return Estimate(values[_HEAD:v_start], values[v_start:], contacts, anchored, anchors, values[6:_HEAD],
                        values[:6], readings, self._guard.faulty if self._guard is not None else 0)

    def _position(self, t: int, r_wb: tuple[float, ...], frames: list[list[float]], forces: list[float],
                  contacts: list[bool], anchored: list[bool]) -> tuple[list[float], list[np.ndarray | None]]:
        """(4): ``p_WB`` (floats) from ``R_WB r_BF_k`` (``r_BF_k`` in the rows of the feet's frames), and
        every foot's anchor (the state while it stays, a new one at touch-down, None when off)."""
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = r_wb
        x0, x1, x2 = frames[0][9:]
        y0, y1, y2 = frames[1][9:]
        r_wf = ([r00 * x0 + r01 * x1 + r02 * x2, r10 * x0 + r11 * x1 + r12 * x2, r20 * x0 + r21 * x1 + r22 * x2],
                [r00 * y0 + r01 * y1 + r02 * y2, r10 * y0 + r11 * y1 + r12 * y2, r20 * y0 + r21 * y1 + r22 * y2])
        stay_left, stay_right = contacts[0] and anchored[0], contacts[1] and anchored[1]
        anchors = [self.anchor_left(t) if stay_left else None, self.anchor_right(t) if stay_right else None]
        if stay_left and stay_right:
            w_left = forces[0] / (forces[0] + forces[1])
            w_right = forces[1] / (forces[0] + forces[1])
            (a0, a1, a2), (b0, b1, b2) = anchors[0].tolist(), anchors[1].tolist()
            (l0, l1, l2), (r0, r1, r2) = r_wf
            p_wb = [w_left * (a0 - l0) + w_right * (b0 - r0), w_left * (a1 - l1) + w_right * (b1 - r1),
                    w_left * (a2 - l2) + w_right * (b2 - r2)]
        elif stay_left or stay_right:
            k = 0 if stay_left else 1
            (a0, a1, a2), (l0, l1, l2) = anchors[k].tolist(), r_wf[k]
            p_wb = [a0 - l0, a1 - l1, a2 - l2]
        else:
            p_wb = self.prediction(t)[3:].tolist()
        if contacts != anchored:  # a touch-down (or a lift-off)
            for k in (0, 1):
                if contacts[k] and anchors[k] is None:
                    anchors[k] = np.array([p + r for p, r in zip(p_wb, r_wf[k], strict=True)])
        return p_wb, anchors

    def _fused_velocity(self, t: int, dt: float, r_wb: tuple[float, ...], w_b: list[float], u_i: list[float],
                        frames: list[list[float]], motions: list[list[float]], forces: list[float],
                        contacts: list[bool]) -> list[float]:
        """(5) and (6): the IMU velocity ``v_I`` (floats), with at least one foot in contact, the feet's
        ``u_F_k = w_B x r_BF_k + R_BF_k v_F_k`` from their frames' rows (as ``u_I``)."""
        f_left = forces[0] if contacts[0] else 0.0
        f_right = forces[1] if contacts[1] else 0.0
        w_left, w_right = f_left / (f_left + f_right), f_right / (f_left + f_right)
        o0, o1, o2 = w_b
        a00, a10, a20, a01, a11, a21, a02, a12, a22, p0, p1, p2 = frames[0]
        b00, b10, b20, b01, b11, b21, b02, b12, b22, q0, q1, q2 = frames[1]
        (m0, m1, m2, _, _, _), (n0, n1, n2, _, _, _) = motions[0], motions[1]
        d0 = u_i[0] - (w_left * (o1 * p2 - o2 * p1 + a00 * m0 + a01 * m1 + a02 * m2)
                       + w_right * (o1 * q2 - o2 * q1 + b00 * n0 + b01 * n1 + b02 * n2))  # u_I - sum w_k u_F_k
        d1 = u_i[1] - (w_left * (o2 * p0 - o0 * p2 + a10 * m0 + a11 * m1 + a12 * m2)
                       + w_right * (o2 * q0 - o0 * q2 + b10 * n0 + b11 * n1 + b12 * n2))
        d2 = u_i[2] - (w_left * (o0 * p1 - o1 * p0 + a20 * m0 + a21 * m1 + a22 * m2)
                       + w_right * (o0 * q1 - o1 * q0 + b20 * n0 + b21 * n1 + b22 * n2))
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = r_wb
        k0, k1, k2 = r00 * d0 + r01 * d1 + r02 * d2, r10 * d0 + r11 * d1 + r12 * d2, r20 * d0 + r21 * d1 + r22 * d2
        if not self.velocity_initialised(t):
            return [k0, k1, k2]
        alpha = complementary_alpha(self.cutoff_frequency, dt)
        x0, x1, x2, _, _, _ = self.prediction(t).tolist()
        return [alpha * x0 + (1.0 - alpha) * k0, alpha * x1 + (1.0 - alpha) * k1, alpha * x2 + (1.0 - alpha) * k2]

    def _values(self, dt: float, q_j: np.ndarray, qd_j: np.ndarray, acceleration: np.ndarray,
                r_wi: list[list[float]], r_wb: tuple[float, ...], w_b: list[float], u_i: list[float],
                p_wb: list[float], v_i: list[float]) -> np.ndarray:
        """One array ``[x(t + 1), p~(t + 1), v_WB, q, v]``: the next states of (6) and the tick
        transition, with ``v_WB = v_I - R_WB u_I``, and (7) with ``R_WB^T v_WB = R_WB^T v_I - u_I``.
        Four writes: the floats up to the base of ``q`` (one run), the joints of ``q``, the base of
        ``v``, its joints."""
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = r_wb
        (e00, e01, e02), (e10, e11, e12), (e20, e21, e22) = r_wi
        (u0, u1, u2), (v0, v1, v2), (p0, p1, p2), (g0, g1, g2) = u_i, v_i, p_wb, self._gravity
        a0, a1, a2 = acceleration.tolist()
        b0, b1, b2 = v0 - (r00 * u0 + r01 * u1 + r02 * u2), v1 - (r10 * u0 + r11 * u1 + r12 * u2), \
            v2 - (r20 * u0 + r21 * u1 + r22 * u2)
        v_start = _HEAD + self.nq
        values = np.empty(v_start + self.nv)
        values[:_HEAD + 7] = [
            v0 + dt * (e00 * a0 + e01 * a1 + e02 * a2 + g0), v1 + dt * (e10 * a0 + e11 * a1 + e12 * a2 + g1),
            v2 + dt * (e20 * a0 + e21 * a1 + e22 * a2 + g2), p0 + dt * b0, p1 + dt * b1, p2 + dt * b2, b0, b1, b2,
            p0, p1, p2, *matrix_to_quat(((r00, r01, r02), (r10, r11, r12), (r20, r21, r22)))]
        values[_HEAD + 7:v_start] = q_j
        values[v_start:v_start + 6] = [r00 * v0 + r10 * v1 + r20 * v2 - u0, r01 * v0 + r11 * v1 + r21 * v2 - u1,
                                       r02 * v0 + r12 * v1 + r22 * v2 - u2, *w_b]
        values[v_start + 6:] = qd_j
        return values

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

    @dg.output(shape=(6,), depends=("estimate",))
    def checked_ft_left_ankle(self, t: int) -> Any:
        """The left ankle wrench as the guard trusts it (what the estimate used): for the other
        readers of the sensor, such as a ZMP estimator."""
        return self.estimate(t).readings[5]

    @dg.output(shape=(6,), depends=("estimate",))
    def checked_ft_right_ankle(self, t: int) -> Any:
        """The right ankle wrench as the guard trusts it."""
        return self.estimate(t).readings[6]

    @dg.output(shape=(), dtype="int", depends=("estimate",))
    def sensor_faults(self, t: int) -> int:
        """How many sensor elements the guard replaced (or found frozen) at ``t``: 0 on a clean tick."""
        return self.estimate(t).sensor_faults

    # -- tick transition ----------------------------------------------------------------------
    def prepare_state(self, t: int) -> None:
        """Stage the filter states, and the contact flags and anchors that change, from the values at ``t``.

        A flag or an anchor is staged (and committed) only when its value changes (touch-down,
        lift-off): its ``time`` is then the tick of the change, and a steady stance costs one
        state per tick (``prediction``), not six.
        """
        est = self.estimate(t)
        pending = [self.prediction]
        if not non_finite(est.next_prediction):
            self.prediction.stage(est.next_prediction, copy=False)  # a slice of the estimate's own array
        else:  # only with check_sensors off, or a sensor value the guard let through
            self.prediction.stage(self.prediction.value)
            self.report_fault(t, "prediction", "not finite", "kept the previous one")
        if est.contacts != est.anchored:
            for k in (0, 1):
                if est.contacts[k] != est.anchored[k]:
                    self._anchored[k].stage(est.contacts[k])
                    pending.append(self._anchored[k])
                    if est.contacts[k]:
                        self._anchor[k].stage(est.anchors[k], copy=False)
                        pending.append(self._anchor[k])
        if not self.velocity_initialised(t):  # after the first tick the prediction is meaningful,
            self.velocity_initialised.stage(True)  # in flight too (the robot starts at v0)
            pending.append(self.velocity_initialised)
        self._pending = pending

    def commit_state(self, t_next: int) -> None:
        """Publish the staged states at ``t + 1``; the guard's trusted readings become its prediction base."""
        dg.commit_all(self._pending, t_next)
        self._pending = []
        if self._guard is not None:
            self._guard.commit()


def _orientation(r_wi: list[list[float]], imu: list[float], motion: list[float],
                 gyro: list[float]) -> tuple[tuple[float, ...], list[float], list[float]]:
    """(1) ``R_WB = R_WI R_BI^T`` (rows, flattened), (2) ``w_B = R_BI w_g - w_BI = R_BI (w_g - w_I)``
    (``w_BI = R_BI w_I``, (K)) and ``u_I = w_B x r_BI + R_BI v_I`` of (5), from ``R_WI`` (rows), the
    IMU frame's ``[R_BI by columns, r_BI]`` and ``[v_I, w_I]``, and the gyro ``w_g``. Python floats,
    as the rest of the estimate (a numpy call costs more than the dozen multiplications of a rotation)."""
    (e00, e01, e02), (e10, e11, e12), (e20, e21, e22) = r_wi
    b00, b10, b20, b01, b11, b21, b02, b12, b22, i0, i1, i2 = imu
    n0, n1, n2, m0, m1, m2 = motion
    g0, g1, g2 = gyro[0] - m0, gyro[1] - m1, gyro[2] - m2
    o0, o1, o2 = b00 * g0 + b01 * g1 + b02 * g2, b10 * g0 + b11 * g1 + b12 * g2, b20 * g0 + b21 * g1 + b22 * g2
    return ((e00 * b00 + e01 * b01 + e02 * b02, e00 * b10 + e01 * b11 + e02 * b12, e00 * b20 + e01 * b21 + e02 * b22,
             e10 * b00 + e11 * b01 + e12 * b02, e10 * b10 + e11 * b11 + e12 * b12, e10 * b20 + e11 * b21 + e12 * b22,
             e20 * b00 + e21 * b01 + e22 * b02, e20 * b10 + e21 * b11 + e22 * b12, e20 * b20 + e21 * b21 + e22 * b22),
            [o0, o1, o2],
            [o1 * i2 - o2 * i1 + b00 * n0 + b01 * n1 + b02 * n2, o2 * i0 - o0 * i2 + b10 * n0 + b11 * n1 + b12 * n2,
             o0 * i1 - o1 * i0 + b20 * n0 + b21 * n1 + b22 * n2])


def _normal_forces(r_wb: tuple[float, ...], frames: list[list[float]], left: list[float],
                   right: list[float]) -> list[float]:
    """(3) ``f_k = e_z . (R_WB R_BS_k f_S_k)`` from the sensor frames' ``[R_BS by columns, r_BS]``
    (``frames[3]``, ``frames[4]``) and the wrenches."""
    _, _, _, _, _, _, z0, z1, z2 = r_wb
    s00, s10, s20, s01, s11, s21, s02, s12, s22, _, _, _ = frames[3]
    t00, t10, t20, t01, t11, t21, t02, t12, t22, _, _, _ = frames[4]
    return [(z0 * s00 + z1 * s10 + z2 * s20) * left[0] + (z0 * s01 + z1 * s11 + z2 * s21) * left[1]
            + (z0 * s02 + z1 * s12 + z2 * s22) * left[2],
            (z0 * t00 + z1 * t10 + z2 * t20) * right[0] + (z0 * t01 + z1 * t11 + z2 * t21) * right[1]
            + (z0 * t02 + z1 * t12 + z2 * t22) * right[2]]


__all__ = ["Estimate", "FloatingBaseEstimator"]
