"""The MuJoCo device entity: a robot of :mod:`dgraph_sim.robots` (TALOS, an arm, any example-robot-data
robot or URDF file) simulated by MuJoCo.

One tick ``t -> t + 1`` (``prepare_state(t)``): read ``control(t)`` (and the wrench inputs),
compute the joint torques, save the MuJoCo integration state (``mj_getState``, without the applied
forces, which a step does not change), finish the step with ``mj_step2`` (actuation,
acceleration, contacts, acceleration-stage sensors, integration), then ``mj_step1`` at the new
state (kinematics, position/velocity sensors), check for divergence and stage every state
(``fallen`` only when it changes, so its ``time`` is the tick of the change).
``commit_state(t + 1)`` publishes them and cannot fail. Calling ``mj_step2`` then ``mj_step1``
is the same sequence of computations as ``mj_step`` (split at a different place), so positions,
velocities, gyro and orientation at ``t + 1`` are those of the new state without an extra
``mj_forward``.

If a tick fails after MuJoCo stepped (another entity raised before the commit, or this device
detected a fall or a divergence), the next ``prepare_state`` restores the saved state first, so a
resumed run is identical to an uninterrupted one.

All states use Pinocchio's conventions (see :mod:`dgraph_sim.conventions`). Acceleration-stage
quantities (``imu_linear_acceleration``, the force/torque sensors, ``joint_torque``,
``contact_force_total``) stamped ``t + 1`` are those of the step ``t -> t + 1`` (computed at ``t``
with ``control(t)``, as a sensor sampled at the end of the period would see them); at tick 0 they
come from ``mj_forward`` with zero torque.
"""

from __future__ import annotations

import copy
import math
import os
from collections.abc import Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Literal

import mujoco
import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.actuators.chain import ChainFileError
from dgraph.entities.robot.loading import check_source
from dgraph_sim.camera import RobotCamera
from dgraph_sim.disturbances import Removals
from dgraph_sim.model import SimModel, load
from dgraph_sim.robots import MJCF_TOLERANCE, MjcfError, RobotInfo
from dgraph_sim.scenes import SceneError
from dgraph_sim.video import VideoError, VideoWriter, check_video, log_video
from dgraph_sim.viewer import PassiveViewer, ViewerError, check_display

_STATE = int(mujoco.mjtState.mjSTATE_INTEGRATION) & ~int(mujoco.mjtState.mjSTATE_QFRC_APPLIED
                                                          | mujoco.mjtState.mjSTATE_XFRC_APPLIED)
"""What ``mj_getState`` saves before a step: the integration state without the applied forces,
which neither MuJoCo's step nor this device changes (``qfrc_applied`` is never written,
``xfrc_applied`` only in the rows of the wrench bodies, rewritten at every tick before the step),
so restoring without them is exact; they are two thirds of the integration state on TALOS."""
_BAD_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                 mujoco.mjtWarning.mjWARN_BADQACC)
_BAD_WARNING_SLICE = slice(int(_BAD_WARNINGS[0]), int(_BAD_WARNINGS[-1]) + 1)
"""The bad qpos/qvel/qacc warnings are consecutive in ``mjtWarning``: one slice of ``warning.number``."""
assert [int(w) for w in _BAD_WARNINGS] == list(range(_BAD_WARNING_SLICE.start, _BAD_WARNING_SLICE.stop))


def _na(entity: MujocoDevice) -> tuple[int]:
    return (entity.na,)


CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}
"""The friction cones of MuJoCo's contact solver, by name."""


def _contact_option_problem(key: str, value: object) -> str | None:
    """What is wrong with the contact-solver option ``key: value``, or None."""
    if key == "cone":
        return None if value in CONES else f"one of {', '.join(CONES)}, got {value!r}"
    if key == "impratio":
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0
        return None if ok else f"a number > 0, got {value!r}"
    if key == "noslip_iterations":
        ok = isinstance(value, int) and not isinstance(value, bool) and value >= 0
        return None if ok else f"an integer >= 0, got {value!r}"
    return "unknown option (known: cone, impratio, noslip_iterations)"


def _port_name(body: str, prefix: str = "wrench_") -> str:
    """``<prefix><body>`` (``wrench_<body>``) with every character that is not a letter, digit or
    ``_`` replaced by ``_``."""
    return prefix + "".join(c if c.isalnum() or c == "_" else "_" for c in body)


@dg.register
class MujocoDevice(dg.Device):
    """A robot simulated by MuJoCo (built from the URDF that Pinocchio loads), 1 tick = 1 step.

    ``model``: an example-robot-data robot name (``talos``, ``panda``, ``ur5``...) or the path of a
    URDF file (its ``package://`` meshes found through ``package_dirs``, see
    :mod:`dgraph_sim.robots`). What the robot has, its :class:`~dgraph_sim.robots.RobotInfo`
    says: a floating base (``q`` starts with the base position and quaternion) or a fixed one
    (``q`` is the joints'), an IMU, force/torque sensors, fall detection.

    Control modes: ``torque`` (``control`` = joint torques) or ``position`` (``control`` = joint
    position targets q*, ``tau = feedforward_torque + kp (q* - q) + kd (velocity_reference - v)``).
    Torques are clipped to the URDF effort limits; ``joint_torque`` reports what was applied.
    Vectors of actuated joints are in Pinocchio's order of ``q[7:]`` / ``v[6:]`` (a fixed base:
    ``q``, ``v``).

    A non-finite command never reaches MuJoCo and does not stop the run: when the torque computed
    from the inputs at ``t`` (``control``, and in position mode ``feedforward_torque`` and
    ``velocity_reference``) is not finite, the step applies the last valid command instead (torque
    mode: the last finite ``control``; position mode: the last valid ``(control,
    velocity_reference, feedforward_torque)``, its PD law computed on the state at ``t``) or, if
    no command was ever valid, zero torque (torque mode) or a hold of the joints where they were
    when the fault began (position mode: target ``q_j(t)``, no velocity reference, no
    feed-forward). The state ``control_fault`` (int, stamped ``t + 1`` like ``joint_torque``)
    counts the consecutive ticks whose command was replaced, 0 when the command was applied, and
    each replaced tick reports a fault naming ``device.control`` (:mod:`dgraph.faults`);
    like ``fallen`` it is staged only when it changes. Non-finite wrench inputs are disturbances,
    not commands: they still raise a ``DGraphError`` (the tick fails, every state stays at ``t``).

    Inputs: ``control`` (na), in position mode ``feedforward_torque`` and ``velocity_reference``
    (na, default zeros), ``wrench_<body>`` (6, world frame, at the body's CoM) for each of
    ``wrench_bodies``, ``remove_<body>`` (bool) for each of ``remove_on``. States: ``q``, ``v``,
    ``encoder_position``, ``encoder_velocity``,
    ``joint_torque``, ``contact_force_total``, ``sim_time``, ``control_fault``; a robot with an IMU
    (TALOS) adds ``imu_orientation``, ``imu_angular_velocity``, ``imu_linear_acceleration``; one
    with force/torque sensors ``ft_<sensor>`` for each (TALOS: ``ft_left_ankle``,
    ``ft_right_ankle``, ``ft_left_wrist``, ``ft_right_wrist``); a floating base with fall
    detection (TALOS, or ``fall_height`` given) ``fallen`` (``q[2] < fall_height``). A fixed-base
    arm has none of these.

    The sensor states (IMU, encoders, F/T) are raw readings (``finite=None``): a NaN or an
    infinity in one, as a real driver may hand over, is staged as it is and caught by its reader
    (the estimator's sensor guard) instead of failing the tick; ``q`` and ``v`` stay checked
    (with the divergence check, they are the simulation's own state).

    Force/torque sensors (6: force then torque, N and N m, in the sensor frame, torque about the
    sensor origin) report the wrench that the child side (foot or hand) exerts on the parent side
    (leg or arm): standing still, an ankle force along the sole normal is about +(weight carried
    by that foot minus the foot's own weight). Sensor frames are Pinocchio frames:
    ``leg_left_6_joint``, ``leg_right_6_joint``, ``wrist_left_ft_link``, ``wrist_right_ft_link``;
    the IMU is at ``imu_link`` (on ``torso_2_link``).

    ``mjcf``: the path of an MJCF file describing the same robot for MuJoCo (tuned contacts,
    actuators, meshes MuJoCo cannot read from the URDF) while Pinocchio keeps ``model``; in a
    graph file a relative path is taken from the file's folder, in Python (and ``--set``) from
    the working directory. Joints are matched by name, actuators are the MJCF's motors (gear 1)
    or, if it has none, motors with the URDF effort limits; the masses, mass matrix and gravity
    torques must agree with Pinocchio's within ``mjcf_tolerance`` (relative), else the device is
    refused naming ``mjcf`` and the joint (:func:`dgraph_sim.robots.mjcf_spec`,
    :func:`dgraph_sim.robots.compare_dynamics`).

    ``actuators``: an actuator parameter file (e.g. ``graphs/data/talos_actuators.yaml``,
    :func:`dgraph.entities.actuators.chain.load_chain_file`): each joint it names gets its
    chain's dynamics (:func:`dgraph_sim.robots.apply_chains`): armature ``I_m``, viscous damping
    ``F_vm + F_vj``, dry friction loss ``F_sm + F_sj`` and torques clipped at ``±R K_m i_max``
    (``joint_torque`` reports the clipped torque), so the simulated joint behaves like
    :class:`~dgraph.entities.actuators.ActuatorModel`'s chain. Pinocchio's model is not changed:
    a controller built on it does not know the chain, which the actuator model compensates.

    ``contact_solver``: MuJoCo contact options other than its defaults (pyramidal cone,
    ``impratio`` 1, no no-slip pass), for this device's model only: ``cone`` (``pyramidal`` or
    ``elliptic``), ``impratio`` (the ratio of frictional to normal constraint impedance: above 1,
    friction is "harder", MuJoCo's remedy for the slow creep of its soft contacts under a
    sustained tangential load, e.g. a foot on a 15-degree pad) and ``noslip_iterations``.

    ``viewer: true`` opens an interactive MuJoCo window (``mujoco.viewer.launch_passive``) at the
    first tick run, synced at ``viewer_fps`` and paced to the wall clock (:mod:`dgraph_sim.viewer`);
    :meth:`close` closes it. It needs a display (``DISPLAY`` or ``WAYLAND_DISPLAY``) that GLFW can
    open, else the device is refused with a ``ParamError``. The window does not change the
    simulation, and works with ``video_path`` (``MUJOCO_GL`` is for offscreen rendering only).
    """

    model = dg.Param("talos", kind="name_or_path", doc="example-robot-data robot name (talos, panda, ur5...) or "
                     "URDF path (in a graph file, relative to its folder)")
    package_dirs = dg.Param([], kind="path_list", doc="folders holding the packages of a URDF's package:// meshes "
                            "(besides the URDF's folder and its ancestors; in a graph file, relative to its folder)")
    mjcf = dg.Param(None, kind="path", doc="MJCF file describing the robot for MuJoCo (Pinocchio keeps model); "
                    "joints matched by name, masses checked (in a graph file, relative to its folder)")
    mjcf_tolerance = dg.Param(MJCF_TOLERANCE, kind="float", minimum=0.0, doc="relative tolerance of the check "
                              "that the MJCF and the Pinocchio model have the same masses and inertias")
    actuators = dg.Param(None, kind="path", doc="actuator parameter file (YAML): its joints get the chain's armature "
                         "I_m, damping F_v, friction loss F_s, force range R K_m i_max (in a graph file, relative "
                         "to its folder)")
    scene = dg.Param("flat", kind="str", doc="scene (dgraph_sim.scenes.SCENES), or several joined by '+', "
                     "applied in order on one floor (obstacles+push)")
    collisions = dg.Param("all", kind="str", choices=("feet", "all"),
                          doc="robot geoms touching the scene: every collision mesh (never each other), or soles only")
    control_mode = dg.Param("torque", kind="str", choices=("torque", "position"), doc="what control commands")
    kp = dg.Param(None, kind="vector", minimum=0.0, doc="position mode stiffness, N m/rad, scalar or one per joint "
                  "(default: the robot's, TALOS 3000, grippers 100)")
    kd = dg.Param(None, kind="vector", minimum=0.0, doc="position mode damping, N m s/rad, scalar or one per joint "
                  "(default: the robot's, TALOS 60, grippers 1)")
    q0 = dg.Param(None, kind="vector", doc="initial configuration, nq (default: the robot's, TALOS half-sitting "
                  "on the floor, else the SRDF reference posture or the neutral one)")
    v0 = dg.Param(None, kind="vector", doc="initial velocity, nv (default: zeros)")
    dt = dg.Param(None, kind="float", minimum=1e-6, maximum=1.0, doc="time step in s (default: the graph's dt)")
    contact_solver = dg.Param(None, kind="object", doc="MuJoCo contact options that differ from its defaults: "
                              "{cone: pyramidal|elliptic, impratio: > 0, noslip_iterations: >= 0}")
    wrench_bodies = dg.Param([], kind="str_list", doc="bodies getting a wrench_<body> input (world frame, at CoM)")
    remove_bodies = dg.Param([], kind="str_list", doc="scene mocap bodies removed during the run (unannounced)")
    remove_times = dg.Param([], kind="vector", doc="time (s) at which each of remove_bodies is removed")
    remove_on = dg.Param([], kind="str_list", doc="scene mocap bodies getting a remove_<body> input (bool): "
                         "removed, for the rest of the run, at the first tick it is true (an event of the run)")
    fall_height = dg.Param(None, kind="float", doc="base height (m) under which fallen is true (default: the "
                           "robot's, TALOS 0.6; a floating base only)")
    viewer = dg.Param(False, kind="bool", doc="show the simulation in an interactive MuJoCo window (needs a display)")
    viewer_fps = dg.Param(30.0, kind="float", minimum=1.0, maximum=1000.0, doc="viewer frame rate (simulated time)")
    stop_on_fall = dg.Param(False, kind="bool", doc="raise a DGraphError when the robot falls")
    video_path = dg.Param(None, kind="str", doc="record a video (.mp4 H.264, .gif, .webp or .png), written at "
                          "close; an .mp4 is also logged to the graph's Rerun recording")
    video_fps = dg.Param(25.0, kind="float", minimum=0.1, maximum=1000.0, doc="video frame rate")
    video_start = dg.Param(0.0, kind="float", minimum=0.0, doc="time (s) of the first video frame")
    video_size = dg.Param([320, 240], kind="int_list", doc="video width and height in pixels")
    video_camera = dg.Param("robot", kind="str", choices=("robot", "track", "front"),
                            doc="video camera: framing the whole robot (following it past a dead zone), "
                            "side view tracking its CoM, or fixed in front of the origin")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", package_dirs: Sequence[str] = (), mjcf: str | None = None,
            mjcf_tolerance: float = 0.01, actuators: str | None = None, scene: str = "flat",
            collisions: Literal["feet", "all"] = "all", control_mode: Literal["torque", "position"] = "torque",
            kp: ArrayLike | None = None, kd: ArrayLike | None = None, q0: ArrayLike | None = None,
            v0: ArrayLike | None = None, dt: float | None = None, contact_solver: Any = None,
            wrench_bodies: Sequence[str] = (), remove_bodies: Sequence[str] = (), remove_times: ArrayLike = (),
            remove_on: Sequence[str] = (), fall_height: float | None = None, viewer: bool = False,
            viewer_fps: float = 30.0, stop_on_fall: bool = False, video_path: str | None = None,
            video_fps: float = 25.0, video_start: float = 0.0, video_size: Sequence[int] = (320, 240),
            video_camera: Literal["robot", "track", "front"] = "robot",
        ) -> None: ...

    control = dg.Input(shape=_na, doc="joint torques (torque mode) or position targets (position mode)")
    # declared per instance (their zero default is sized by the robot): in position mode only,
    # feedforward_torque (na, added torque) and velocity_reference (na, joint velocity
    # reference); wrench_<body> (6) for each of wrench_bodies; remove_<body> (bool) for each of remove_on

    q = dg.State(shape=("nq",), doc="configuration (Pinocchio: base position, quaternion xyzw, joints)")
    v = dg.State(shape=("nv",), doc="velocity (Pinocchio: base linear and angular in the base frame, joints)")
    encoder_position = dg.State(finite=None, shape=_na, doc="actuated joint positions, rad")
    encoder_velocity = dg.State(finite=None, shape=_na, doc="actuated joint velocities, rad/s")
    joint_torque = dg.State(shape=_na, doc="applied joint torques after clipping, N m")
    contact_force_total = dg.State(shape=(3,), doc="sum of the contact forces the scene exerts on the robot, world")
    sim_time = dg.State(shape=(), doc="MuJoCo time, s")
    control_fault = dg.State(shape=(), dtype="int", doc="consecutive ticks whose non-finite command was replaced "
                             "by the last valid one (0: the command was applied)")

    # -- construction -----------------------------------------------------------------------
    def _set_contact_solver(self, options: mujoco.MjOption) -> None:
        """Apply ``contact_solver`` to the model's options; a ParamError naming a bad entry."""
        given = self.contact_solver or {}
        if not isinstance(given, dict):
            raise dg.ParamError(f"{self.name}: parameter 'contact_solver': expected a mapping, got {given!r}",
                                entity=self.name)
        for key, value in given.items():
            problem = _contact_option_problem(key, value)
            if problem:
                raise dg.ParamError(f"{self.name}: parameter 'contact_solver': {key}: {problem}", entity=self.name)
            if key == "cone":
                options.cone = CONES[value]
            else:
                setattr(options, key, value)

    def configure(self) -> None:
        """Load the model (cached per process), size the ports, declare the sensor states the robot
        has and the wrench inputs."""
        check_source(self.model, self.name)
        if self.mjcf is not None and self.collisions != "all":
            raise dg.ParamError(f"{self.name}: parameter 'collisions': {self.collisions!r} applies to a robot built "
                                "from its URDF; with mjcf the MJCF's contacts are used as written", entity=self.name)
        try:
            self.sim: SimModel = load(self.model, self.scene, 0.001, self.collisions, tuple(self.package_dirs),
                                      self.mjcf, self.mjcf_tolerance, self.actuators)
        except ChainFileError as exc:  # before ValueError, which it is
            raise dg.ParamError(f"{self.name}: parameter 'actuators': {exc}", entity=self.name) from None
        except SceneError as exc:  # an unknown scene, two scenes adding the same name (a ValueError too)
            raise dg.ParamError(f"{self.name}: parameter 'scene': {exc}", entity=self.name) from None
        except MjcfError as exc:  # the MJCF does not describe the robot of the Pinocchio model
            raise dg.ParamError(f"{self.name}: parameter 'mjcf': {exc}", entity=self.name) from None
        except ValueError as exc:  # a mesh not found, a joint MuJoCo cannot mirror
            raise dg.ParamError(f"{self.name}: parameter 'model': cannot build {self.model!r}: {exc}",
                                entity=self.name) from None
        robot = self.sim.robot
        self.mj_model = copy.copy(self.sim.mj_model)  # own copy: the time step follows dt
        self._set_contact_solver(self.mj_model.opt)
        # software (llvmpipe) rendering: multisampling costs 4-6x (0.6 s -> 0.1 s at 320x240)
        self.mj_model.vis.quality.offsamples = 0
        self.mj_model.vis.quality.shadowsize = 2048
        self.joint_map = self.sim.joint_map
        self.nq, self.nv, self.na = self.joint_map.nq, self.joint_map.nv, self.joint_map.na
        self._gains = {}
        for name in ("kp", "kd"):
            value = getattr(self, name)
            default = getattr(robot, name)
            if value is None and default is None:
                if self.control_mode == "position":
                    raise dg.ParamError(f"{self.name}: parameter {name!r}: position mode on {robot.name} needs kp and "
                                        "kd (the robot has no default gains)", entity=self.name)
                default = 0.0  # torque mode: no PD
            gain = np.asarray(default if value is None else value, dtype=float)
            if gain.shape not in ((), (self.na,)) or not np.isfinite(gain).all():
                raise dg.ParamError(f"{self.name}: parameter {name!r} must be a finite scalar or {self.na} values",
                                    entity=self.name)
            self._gains[name] = np.broadcast_to(gain, (self.na,)).copy()
        if len(self.video_size) != 2 or min(self.video_size) < 8 or max(self.video_size) > 4096:
            raise dg.ParamError(f"{self.name}: video_size must be [width, height] in 8..4096", entity=self.name)
        self._declare_sensors(robot)
        if self.control_mode == "position":  # they would be silently ignored in torque mode
            self.declare("feedforward_torque", dg.Input(shape=(self.na,), default=np.zeros(self.na),
                                                        doc="added joint torque in position mode, N m"))
            self.declare("velocity_reference", dg.Input(shape=(self.na,), default=np.zeros(self.na),
                                                        doc="joint velocity reference in position mode, rad/s"))
        self._wrenches: list[tuple[int, str]] = []
        for body in self.wrench_bodies:
            body_id = mujoco.mj_name2id(self.mj_model, mujoco.mjtObj.mjOBJ_BODY, body)
            if body_id < 0:
                known = ", ".join(self.mj_model.body(b).name for b in range(1, self.mj_model.nbody))
                raise dg.ParamError(f"{self.name}: wrench body {body!r} is not in the model; bodies: {known}",
                                    entity=self.name)
            port = _port_name(body)
            if any(port == p for _, p in self._wrenches):
                raise dg.ParamError(f"{self.name}: two wrench bodies map to the input {port!r}", entity=self.name)
            self.declare(port, dg.Input(shape=(6,), default=np.zeros(6),
                                        doc=f"world-frame [force, torque] applied at the CoM of {body}"))
            self._wrenches.append((body_id, port))
        self._remove_ports = [_port_name(body, "remove_") for body in self.remove_on]
        if len(set(self._remove_ports)) != len(self._remove_ports):
            raise dg.ParamError(f"{self.name}: two remove_on bodies map to the same input", entity=self.name)
        for body, port in zip(self.remove_on, self._remove_ports, strict=True):
            self.declare(port, dg.Input(shape=(), dtype="bool", default=False,
                                        doc=f"removes the scene body {body} when true (latched until reset)"))

    def _declare_sensors(self, robot: RobotInfo) -> None:
        """The states of the robot's sensors (IMU, force/torque) and of its fall detection, if it has them."""
        if robot.imu is not None:
            self.declare("imu_orientation", dg.State(finite=None, shape=(4,),
                                                     doc="IMU frame orientation in the world, quaternion xyzw"))
            self.declare("imu_angular_velocity", dg.State(finite=None, shape=(3,),
                                                          doc="IMU angular velocity in the IMU frame, rad/s"))
            self.declare("imu_linear_acceleration", dg.State(
                finite=None, shape=(3,), doc="IMU proper acceleration (a - g) in the IMU frame, m/s²"))
        for key, site in robot.force_torque.items():
            self.declare(f"ft_{key}", dg.State(finite=None, shape=(6,), doc=f"wrench at {site.pin_frame} (child side "
                                               "on parent side), sensor frame"))
        self._fall_height = robot.fall_height if self.fall_height is None else self.fall_height
        if self.fall_height is not None and not robot.floating_base:
            raise dg.ParamError(f"{self.name}: parameter 'fall_height': {robot.name} has a fixed base (no fall "
                                "detection)", entity=self.name)
        if self._fall_height is not None:
            self.declare("fallen", dg.State(shape=(), dtype="bool", doc="base height below fall_height"))
        elif self.stop_on_fall:
            raise dg.ParamError(f"{self.name}: parameter 'stop_on_fall': {robot.name} has no fall detection (a "
                                "fixed base, or no fall_height)", entity=self.name)

    def setup(self) -> None:
        """MuJoCo data, buffers, removals, the viewer and the video hook."""
        m = self.mj_model
        self.data = mujoco.MjData(m)
        try:
            self._removals = Removals(m, self.remove_bodies, np.atleast_1d(self.remove_times), self.remove_on) \
                if self.remove_bodies or np.size(self.remove_times) or self.remove_on else None
        except ValueError as exc:
            raise dg.ParamError(f"{self.name}: {exc}", entity=self.name) from None
        self._saved = np.zeros(mujoco.mj_stateSize(m, _STATE))
        self._pending = False
        self._warning_counts = [0, 0, 0]
        jm = self.joint_map
        self._ctrl_index, self._actuated_index = jm.ctrl_index, jm.actuated_index
        self._lower = -m.actuator_ctrlrange[self._actuated_index, 1]
        self._upper = m.actuator_ctrlrange[self._actuated_index, 1]
        self._setup_sensors()
        # the states that are q, v or views of them (the encoders: the joints' part)
        self._floating = jm.floating_base
        self._q_parts = [(self.q, None), (self.encoder_position, slice(self.nq - self.na, None))]
        self._v_parts = [(self.v, None), (self.encoder_velocity, slice(self.nv - self.na, None))]
        self._base_z = int(self.joint_map.qpos_index[2]) if self._floating else -1
        # views on the MjData buffers (fixed for its lifetime; mj_setState writes into them)
        d = self.data
        self._qpos, self._qvel, self._ctrl, self._xfrc = d.qpos, d.qvel, d.ctrl, d.xfrc_applied
        self._sensordata, self._actuator_force = d.sensordata, d.actuator_force
        self._bad_warning_counts = d.warning.number[_BAD_WARNING_SLICE]  # a view
        # R_WB^T (the base's xmat, transposed): MuJoCo sets a free body's orientation from its
        # qpos quaternion (normalised) in mj_kinematics, which mj_step1 and mj_forward run
        self._base_rt = d.xmat[jm.base_body].reshape(3, 3).T
        self._qpos_index, self._qvel_index = jm.qpos_index, jm.qvel_index
        base_linear = int(jm.qvel_index[0])  # the free joint's linear velocity (world frame): qvel[i:i + 3]
        self._qvel_base_linear = d.qvel[base_linear:base_linear + 3] if self._floating else None
        bodies = self.sim.robot_bodies  # a slice
        self._cfrc_robot = d.cfrc_ext[bodies, 3:]
        self._xfrc_robot = d.xfrc_applied[bodies, :3]
        self._ones = np.ones(bodies.stop - bodies.start)
        self._ctrl_identity = bool(np.array_equal(self._ctrl_index, np.arange(self.na)))
        self._torque_mode = self.control_mode == "torque"
        self._kp, self._kd = self._gains["kp"], self._gains["kd"]
        self._timestep = float(m.opt.timestep)
        self._fallen_staged = self._fault_staged = False
        self._held = self._held_next = None
        self._viewer: PassiveViewer | None = None
        self._renderers: dict[tuple[int, int], mujoco.Renderer] = {}
        self._camera = RobotCamera(m, self.sim.robot_bodies, jm.base_body)
        self._video: VideoWriter | None = None
        self._video_streams: list = []  # the graph's Rerun streams the .mp4 is logged to (shares held)
        self._next_frame = 0
        if self.video_path is not None:
            try:
                check_video(self.video_path, self.video_size)
            except VideoError as exc:
                raise dg.ParamError(f"{self.name}: video_path: {exc}", entity=self.name) from None
            self._renderer(*self.video_size, purpose="video_path")  # no OpenGL: refused now, not at the first frame
            self.after.add(self._record_frame)
        if self.viewer:  # the display is checked now; the window opens at the first tick run (_show)
            try:
                check_display()
            except ViewerError as exc:
                raise dg.ParamError(f"{self.name}: parameter 'viewer': {exc}", entity=self.name) from None
            self.before.add(self._show)

    def _setup_sensors(self) -> None:
        """One gather of ``sensordata`` per tick for the robot's sensors, and the states that are its parts.

        The gather: IMU quaternion (xyzw), gyro, accelerometer (if the robot has an IMU), then the
        F/T block (force then torque of each sensor, in the robot's order), negated: MuJoCo
        reports the wrench the parent exerts on the child subtree.
        """
        robot, sensors = self.sim.robot, self.sim.sensors
        imu = [self.imu_orientation, self.imu_angular_velocity, self.imu_linear_acceleration] \
            if robot.imu is not None else []
        self._ft_states = [getattr(self, f"ft_{k}") for k in robot.force_torque]
        self._tick_states = [self.q, self.v, *imu, self.encoder_position, self.encoder_velocity,
                             *self._ft_states, self.joint_torque, self.contact_force_total, self.sim_time]
        index = []
        if imu:
            index += [sensors.imu_quat + np.array([1, 2, 3, 0]), sensors.imu_gyro + np.arange(3),
                      sensors.imu_accelerometer + np.arange(3)]
        n_imu = 10 if imu else 0
        if self._ft_states:
            keys = list(robot.force_torque)
            start = sensors.force[keys[0]]
            expected = [start + 6 * i + o for i in range(len(keys)) for o in (0, 3)]
            if [a for k in keys for a in (sensors.force[k], sensors.torque[k])] != expected:
                raise dg.DGraphError(f"{self.name}: force/torque sensors are not laid out as expected",
                                     entity=self.name)
            index.append(start + np.arange(6 * len(keys)))
        self._sensor_index = np.concatenate(index).astype(np.intp) if index else np.zeros(0, dtype=np.intp)
        self._sensor_sign = np.ones(len(self._sensor_index))
        self._sensor_sign[n_imu:] = -1.0
        self._sensor_parts = [*([(imu[0], slice(0, 4)), (imu[1], slice(4, 7)), (imu[2], slice(7, 10))] if imu else []),
                              *[(state, slice(n_imu + 6 * i, n_imu + 6 + 6 * i))
                                for i, state in enumerate(self._ft_states)]]

    def reset(self) -> None:
        """Put MuJoCo at ``q0``, ``v0`` (``mj_forward``) and the states at tick 0."""
        jm = self.joint_map
        q0 = self.sim.q0 if self.q0 is None else np.asarray(self.q0, dtype=float)
        v0 = np.zeros(self.nv) if self.v0 is None else np.asarray(self.v0, dtype=float)
        if q0.shape != (self.nq,) or v0.shape != (self.nv,) or not (np.isfinite(q0).all() and np.isfinite(v0).all()):
            raise dg.ParamError(f"{self.name}: q0 needs {self.nq} and v0 {self.nv} finite values", entity=self.name)
        q0 = q0.copy()
        if self._floating:
            if not 0.5 < np.linalg.norm(q0[3:7]) < 2.0:
                raise dg.ParamError(f"{self.name}: q0[3:7] must be a quaternion (x, y, z, w)", entity=self.name)
            q0[3:7] /= np.linalg.norm(q0[3:7])
        m, d = self.mj_model, self.data
        mujoco.mj_resetData(m, d)
        jm.qpos_from_q(q0, d.qpos)
        jm.qvel_from_v(q0, v0, d.qvel)
        mujoco.mj_forward(m, d)
        # cfrc_ext (contact_force_total) is filled by MuJoCo only for an acceleration-stage sensor
        # that needs it (force, torque, accelerometer...: TALOS's F/T sensors and IMU); without one
        # (an arm from a URDF) the device calls mj_rnePostConstraint itself after each step
        self._rne_post_constraint = not d.flg_rnepost
        if self._rne_post_constraint:
            mujoco.mj_rnePostConstraint(m, d)
        self._pending = False
        self._sync_warnings()
        self._stage_all(self._contact_force(), everything=True)
        self.control_fault.stage(0)
        for sig in self._states():
            sig.commit(0)
        self._fallen_staged = False
        self._held = self._held_next = None

    def _states(self) -> list[dg.State]:
        return [s for s in self.ports.values() if isinstance(s, dg.State)]

    # -- the tick ---------------------------------------------------------------------------
    def _torque(self, t: int) -> tuple[np.ndarray | None, bool]:
        """Joint torques (actuated order, before clipping) for the step ``t -> t + 1``, and whether
        the command at ``t`` was replaced: its torque was not finite (or so large that its square
        overflows, beyond 1e154), so the last valid command is applied instead (see the class
        docstring).

        Torque mode, replaced: ``None``, MuJoCo's ``ctrl`` already holds that command. It holds the
        torque applied at the last committed tick (zero after a reset: ``mj_resetData``), which is
        a copy (a producer may reuse its buffer), is not changed by MuJoCo, and is saved with the
        state, so a failed tick's torque is undone with it. Position mode keeps a copy of its last
        valid command, committed with the state.
        """
        if self._torque_mode:
            tau = self.control(t)
            return (tau, False) if math.isfinite(np.dot(tau, tau)) else (None, True)
        command = (self.control(t), self.feedforward_torque(t), self.velocity_reference(t))
        tau = self._pd(command)
        if math.isfinite(np.dot(tau, tau)):  # kept as a copy: a producer may reuse its buffer
            self._held_next = tuple(np.array(part, dtype=float) for part in command)
            return tau, False
        self._held_next = self._held if self._held is not None else self._hold_default()
        return self._pd(self._held_next), True

    def _hold_default(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position mode, the command held when none was ever valid: the joints held where they
        are (target ``q_j(t)``, no velocity reference, no feed-forward)."""
        return self.encoder_position.value, np.zeros(self.na), np.zeros(self.na)

    def _pd(self, command: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
        """Position mode: ``feedforward + kp (q* - q_j) + kd (v_ref - qd_j)`` on the state at ``t``."""
        target, feedforward, velocity = command
        return (feedforward + self._kp * (target - self.encoder_position.value)
                + self._kd * (velocity - self.encoder_velocity.value))

    def prepare_state(self, t: int) -> None:
        """Apply the control at ``t``, step MuJoCo, check it, stage the state at ``t + 1``."""
        m, d = self.mj_model, self.data
        if self._pending:
            self._restore()
        dt = self.dt
        if dt != self._timestep:
            m.opt.timestep = self._timestep = dt
        tau, replaced = self._torque(t)
        if replaced:
            self.report_fault(t, "control", "not finite", "applied the last valid command (if none: zero torque, "
                              "or in position mode the joints held)")
        wrenches = self._read_wrenches(t) if self._wrenches else ()
        mujoco.mj_getState(m, d, self._saved, _STATE)
        self._pending = True
        if self._removals is not None:
            self._removals.apply(d, t * dt, [bool(self.signal(port)(t)) for port in self._remove_ports])
        if tau is not None:  # else (torque mode, command replaced) ctrl holds the last valid one
            if self._ctrl_identity:
                self._ctrl[:] = tau
            else:
                np.take(tau, self._ctrl_index, out=self._ctrl)
        for body, wrench in wrenches:
            self._xfrc[body] = wrench
        mujoco.mj_step2(m, d)
        if self._rne_post_constraint:  # cfrc_ext: the contact forces of this step (efc_force, contact frames)
            mujoco.mj_rnePostConstraint(m, d)
        contact_force = self._contact_force()  # contact forces of this step: read before mj_step1
        mujoco.mj_step1(m, d)
        self._check(t)
        fallen = self._stage_all(contact_force)
        previous_fault = self.control_fault.value
        fault = previous_fault + 1 if replaced else 0
        self._fault_staged = fault != previous_fault
        if self._fault_staged:
            self.control_fault.stage(fault)
        if self.stop_on_fall and fallen:
            raise dg.DGraphError(f"{self.name}: the robot fell during tick {t} (base height "
                                 f"{d.qpos[self._base_z]:.3f} m < fall_height {self._fall_height} m "
                                 f"at tick {t + 1})", entity=self.name, signal="fallen")

    def _read_wrenches(self, t: int) -> list[tuple[int, np.ndarray]]:
        """``(body id, wrench)`` of each wrench input at ``t``; a non-finite one raises (a disturbance,
        not a command: the tick fails)."""
        wrenches = [(body, self.signal(port)(t)) for body, port in self._wrenches]
        for (_, port), (_, wrench) in zip(self._wrenches, wrenches, strict=True):
            if not np.isfinite(wrench).all():
                raise dg.DGraphError(f"{self.name}: non-finite {port} at tick {t}", entity=self.name, signal=port)
        return wrenches

    def commit_state(self, t_next: int) -> None:
        """Publish the staged state at ``t + 1`` (the states of every tick in one go)."""
        dg.commit_all(self._tick_states, t_next)
        if self._fallen_staged:
            self.fallen.commit(t_next)
            self._fallen_staged = False
        if self._fault_staged:
            self.control_fault.commit(t_next)
            self._fault_staged = False
        self._held = self._held_next
        self._pending = False

    def _restore(self) -> None:
        """Back to the state saved before the last uncommitted step."""
        m, d = self.mj_model, self.data
        mujoco.mj_setState(m, d, self._saved, _STATE)
        mujoco.mj_step1(m, d)
        self._sync_warnings()
        self._pending = False

    def _sync_warnings(self) -> None:
        self._warning_counts = self._bad_warning_counts.tolist()

    def _check(self, t: int) -> None:
        """Raise if MuJoCo diverged: a bad qpos/qvel/qacc warning since the last step.

        The warnings cover a non-finite state: ``mj_step1``, the last thing to run on the new
        state, starts by checking qpos and qvel (``mj_checkPos``, ``mj_checkVel``: NaN, inf or
        beyond 1e10 count a warning and, unless disabled, reset the data). So the state is
        finite whenever no count changed; it is looked at only to name the problem.
        """
        counts = self._bad_warning_counts.tolist()
        if counts == self._warning_counts:
            return
        qpos, qvel = self._qpos, self._qvel
        # NaN or inf make the squared norms non-finite (so do values beyond 1e154: diverged too)
        finite = math.isfinite(np.dot(qpos, qpos) + np.dot(qvel, qvel))
        problems = [f"{mujoco.mjtWarning(int(w)).name[7:]} (index {self.data.warning[int(w)].lastinfo})"
                    for w, n, n0 in zip(_BAD_WARNINGS, counts, self._warning_counts, strict=True) if n != n0]
        if not finite:
            problems.append("non-finite qpos/qvel")
        self._warning_counts = counts
        raise dg.DivergenceError(f"{self.name}: MuJoCo simulation diverged at tick {t}: {', '.join(problems)}; "
                             "the state at this tick is kept (lower the gains, the time step or the applied "
                             "wrenches)", entity=self.name)

    def _stage_all(self, contact_force: np.ndarray, everything: bool = False) -> bool:
        """Stage every state from the MuJoCo data (Pinocchio conventions); returns ``fallen``.

        ``fallen`` is staged only when it changes (or with ``everything``): its ``time`` is the
        tick of the change, like the estimator's contact flags. A few gathers with precomputed
        index arrays; the encoder and F/T states are views of them.
        """
        q = self._qpos[self._qpos_index]                                 # JointMap.q_from_qpos
        v = self._qvel[self._qvel_index]                                 # JointMap.v_from_qvel: the base
        if self._floating:
            np.dot(self._base_rt, self._qvel_base_linear, out=v[:3])     # linear velocity R_WB^T v
        sensors = self._sensordata[self._sensor_index] * self._sensor_sign  # F/T negated
        torque = self._actuator_force[self._actuated_index]
        # every array is this tick's own (a gather, or a view of one) and never written again: no
        # copies, and one NaN check per gather
        dg.stage_views([(q, self._q_parts), (v, self._v_parts), (sensors, self._sensor_parts),
                        (torque, ((self.joint_torque, None),)), (contact_force, ((self.contact_force_total, None),))])
        self.sim_time.stage(self.data.time)
        if self._fall_height is None:
            return False
        fallen = q.item(2) < self._fall_height  # the base height, qpos[self._base_z]
        self._fallen_staged = everything or fallen != self.fallen.value
        if self._fallen_staged:
            self.fallen.stage(fallen)
        return fallen

    def _contact_force(self) -> np.ndarray:
        """Sum of the contact forces the scene exerts on the robot, world frame (valid after ``mj_step2``).

        ``cfrc_ext`` (computed by MuJoCo for the force/torque sensors, else by the device's own
        ``mj_rnePostConstraint``) holds, per body, the external force in the world frame: contacts
        plus ``xfrc_applied``; the applied part is removed.
        """
        total = self._ones @ self._cfrc_robot
        if self._wrenches:
            total -= self._ones @ self._xfrc_robot
        return total

    # -- rendering --------------------------------------------------------------------------
    def _renderer(self, width: int, height: int, purpose: str = "render") -> mujoco.Renderer:
        """The offscreen renderer of this size (made once); without OpenGL a ``DGraphError`` (a
        ``ParamError`` naming the parameter ``purpose`` when it is one) that says how to get it."""
        key = (width, height)
        renderer = self._renderers.get(key)
        if renderer is None:
            m = self.mj_model
            m.vis.global_.offwidth = max(m.vis.global_.offwidth, width)
            m.vis.global_.offheight = max(m.vis.global_.offheight, height)
            try:
                renderer = self._renderers[key] = mujoco.Renderer(m, height, width)
            except Exception as exc:  # MuJoCo's GL back-ends fail with FatalError, ImportError, AttributeError...
                error = dg.ParamError if purpose != "render" else dg.DGraphError
                raise error(f"{self.name}: {purpose}: offscreen rendering is not available "
                            f"(MUJOCO_GL={os.environ.get('MUJOCO_GL', '(unset)')}: {type(exc).__name__}: {exc}); "
                            "without a display set MUJOCO_GL=egl (or osmesa) before mujoco is imported",
                            entity=self.name) from None
        return renderer

    def render(self, width: int = 320, height: int = 240, camera: str = "robot") -> np.ndarray:
        """An RGB image (height x width x 3, uint8) of the current state, offscreen, from ``camera``:
        ``robot`` (a free camera framing the whole robot, :class:`~dgraph_sim.camera.RobotCamera`)
        or a camera of the model (``track``, ``front``)."""
        if self._pending:
            self._restore()
        renderer = self._renderer(width, height)
        view = self._camera.update(self.data, width, height) if camera == "robot" else camera
        renderer.update_scene(self.data, camera=view)
        return renderer.render().copy()

    @dg.command
    def snapshot(self, path: str = "snapshot.png", width: int = 640, height: int = 480) -> str:
        """Save a PNG image of the current state (the camera framing the robot); returns the path."""
        from PIL import Image

        Image.fromarray(self.render(width, height)).save(path)
        return path

    def _record_frame(self, t: int) -> None:
        """After hook: add a video frame every 1 / video_fps seconds (the nearest whole number of
        ticks; the video's frame rate is the one that makes) from ``video_start`` on. The first
        frame opens the writer and, for an .mp4, takes a share of the graph's Rerun streams
        (closed with the device)."""
        if t < self._next_frame:
            return
        interval = max(1, round(1.0 / (self.video_fps * self.dt)))
        if self._video is None:
            start = math.ceil(self.video_start / self.dt - 1e-9)  # the first tick at or after video_start
            if t < start:
                self._next_frame = start
                return
            fps = 1 / (interval * Fraction(self.dt).limit_denominator(1_000_000_000))
            try:
                self._video = VideoWriter(self.video_path, fps, tuple(self.video_size))
            except VideoError as exc:
                raise dg.DGraphError(f"{self.name}: video_path: {exc}", entity=self.name) from None
            if self._video.kind == ".mp4" and self.graph is not None:
                from dgraph.entities.recording.rerun_stream import join_streams

                self._video_streams = join_streams(self.graph)
        try:
            self._video.add(self.render(*self.video_size, camera=self.video_camera), t)
        except VideoError as exc:
            raise dg.DGraphError(f"{self.name}: video_path: {exc}", entity=self.name) from None
        self._next_frame = t + interval

    def _show(self, t: int) -> None:
        """Before hook (``viewer: true``): open the window at the first tick run (the graph's dt is
        known then, and loading, checking or drawing a graph opens none), then show the state at
        ``t``. A before hook: ``launch_passive`` runs ``mj_forward`` on the data, which at tick 0
        repeats :meth:`reset`'s ``mj_forward`` at the same state."""
        if self._viewer is None:
            try:
                self._viewer = PassiveViewer(self.mj_model, self.data, self.dt, self.viewer_fps)
            except ViewerError as exc:
                raise dg.DGraphError(f"{self.name}: parameter 'viewer': {exc}", entity=self.name) from None
        self._viewer.sync(t)

    def write_video(self) -> str | None:
        """Finish the video file ``video_path`` (its format by its extension: ``.mp4``, ``.gif``,
        ``.webp``, ``.png``; see :mod:`dgraph_sim.video`) and log an .mp4 to the graph's Rerun
        recording (entity ``video/<device name>``, each frame at its tick); returns the path, or
        ``None`` if no frame was taken. Idempotent."""
        if self._video is None:
            return None
        try:
            path = self._video.close()
            if path is not None:
                for stream in self._video_streams:
                    log_video(stream, f"video/{self.name}", path, self._video.ticks)
        except VideoError as exc:
            raise dg.DGraphError(f"{self.name}: video_path: {exc}", entity=self.name) from None
        finally:
            streams, self._video_streams = self._video_streams, []
            for stream in streams:
                stream.close()
        return None if path is None else str(path)

    def close(self) -> None:
        """Close the viewer (if any), write the video (if any) and free the renderers (freed even if the
        video fails)."""
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None
        try:
            self.write_video()
        finally:
            for renderer in self._renderers.values():
                renderer.close()
            self._renderers = {}
