"""MuJoCo robot models built at run time from URDFs: any example-robot-data robot, or a user's file.

:func:`robot_spec` builds the ``MjSpec`` and the :class:`RobotInfo` of a robot source (an
example-robot-data name or a URDF path, :mod:`dgraph.entities.robot.loading`): TALOS with
:func:`talos_spec`, every other robot with :func:`urdf_spec`. :class:`RobotInfo` says what the
device must know beyond the spec, so the device assumes nothing of TALOS: a floating base or a
fixed one, the IMU and force/torque sensors if any, the feet, the default configuration, the
position-mode gains and the fall detection height.

Any robot (:func:`urdf_spec`): the URDF that Pinocchio loads, read by MuJoCo with the choices
below (torque motors, armature, no URDF damping or friction, collision geoms); a free joint on
the root link if the Pinocchio model has a free-flyer root, else the root link welded to the
world (a fixed-base arm). Mesh paths are made absolute (``package://PKG/...`` looked for in
``package_dirs``, then under the URDF's folder and its ancestors); a visual mesh MuJoCo cannot
read (Collada ``.dae``, as example-robot-data's Panda and UR arms have) is left out, and the
collision geoms of a body left without a visual one are drawn instead (group 2). No sensors, no
feet, no fall detection; the default configuration is the SRDF's reference posture if
example-robot-data has one (Panda: ``default``), else Pinocchio's neutral configuration clipped
into the joint limits; no default position-mode gains (a position-mode device must be given
``kp`` and ``kd``).

A robot described for MuJoCo by an MJCF file (``robot_spec(..., mjcf=path)``, :func:`mjcf_spec`):
Pinocchio keeps the URDF or the example-robot-data model, MuJoCo reads the MJCF as written
(contacts, meshes, armature, damping, options), joints are matched by name, the MJCF's gear-1
motors are used (or motors are added if it has no actuator), and :func:`compare_dynamics`
refuses an MJCF whose masses, mass matrix or gravity torques differ from Pinocchio's beyond a
relative tolerance.

TALOS: :func:`talos_spec` builds an ``MjSpec`` of the **same** URDF that
``example_robot_data.load("talos")`` loads (``talos_reduced.urdf``: 32 actuated joints, STL
meshes), so that the MuJoCo model and the Pinocchio model have the same kinematics and the same
mass matrix (to 1e-13, see ``tests/sim/test_conventions.py``). Nothing is downloaded.

Choices, and why:

* **Free joint** ``root_joint`` on ``base_link`` (MuJoCo welds a URDF root to the world).
* **Torque motors**, one per actuated joint, in Pinocchio's actuated order, gear 1, with the URDF
  effort limit as ``ctrlrange`` (clipped by MuJoCo) and as the joint's ``actfrcrange``.
* **Armature** copied from the Pinocchio model (the SRDF rotor parameters give
  ``rotorInertia * gear² = 0.1``, grippers 0); without it M(q) differs by 0.1 on the diagonal.
* **URDF damping and friction are zeroed** in MuJoCo. MuJoCo would import them as viscous damping
  and ``frictionloss``; Pinocchio's RNEA/ABA ignore ``model.damping``/``model.friction``, so a
  controller built on Pinocchio would see an unmodelled drag. With both at zero the two
  simulators describe the same rigid-body system (joint position limits are kept in MuJoCo).
* **Collisions**: MuJoCo only excludes parent/child pairs and the TALOS collision meshes overlap
  their grand-parents at half-sitting, so the robot never collides with itself. Each sole is a
  box ``0.21 x 0.138`` (the TSID contact rectangle: 0.10 m ahead of the ankle, 0.11 m behind,
  ±0.069 m sideways) whose bottom face is the ``*_sole_link`` plane (the foot collision mesh is
  off); a box on a plane gives four corner contacts, the contact model of the controllers. By
  default (``collisions="all"``) the other collision meshes also touch the scene (a fallen robot
  lies on the floor, a hand can push a block), never each other; ``"feet"`` keeps the soles only.
  Collision geoms are in group 3 (hidden by the renderer's defaults); visual meshes are group 1
  and never collide.
* **Sensors** on sites placed at the frames of the real sensors: ``imu`` at ``imu_link`` (on
  ``torso_2_link`` in this URDF), force/torque sensors at the ankles (``leg_*_6_joint`` frames,
  the body frame of ``leg_*_6_link``) and at the wrists (``wrist_*_ft_link``, the URDF's wrist
  F/T frames, 0.051 m below ``arm_*_7_joint``).
"""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import dataclass, field, replace
from typing import Any
from xml.etree import ElementTree

import mujoco
import numpy as np
import pinocchio

from dgraph.entities.robot.loading import has_free_flyer

TALOS_URDF = "talos_data/robots/talos_reduced.urdf"
SOLE_HALF_SIZE = (0.105, 0.069, 0.005)
"""Half sizes of the sole collision box (x, y, z)."""
SOLE_CENTER_X = -0.005
"""x of the sole box centre in the ankle frame (0.10 m ahead, 0.11 m behind)."""
SOLE_DEPTH = 0.107
"""Distance from the ankle joint down to the sole plane (``leg_*_sole_fix_joint``)."""
COLLISION_GROUP = 3
"""Geom group of collision geoms (hidden by default when rendering)."""


@dataclass(frozen=True)
class SensorSite:
    """A sensor site: its MuJoCo site and body, and the Pinocchio frame it coincides with."""

    site: str
    body: str
    pin_frame: str


@dataclass(frozen=True)
class RobotInfo:
    """What the simulator needs to know about a robot beyond its ``MjSpec``."""

    name: str
    pin_model: Any
    base_body: str
    floating_base: bool = True
    """A free joint on ``base_body`` (Pinocchio: a free-flyer root); else the base is welded to the world."""
    feet: tuple[str, ...] = ()
    imu: SensorSite | None = None
    force_torque: dict[str, SensorSite] = field(default_factory=dict)
    """Force/torque sensors by name: the device publishes ``ft_<name>``."""
    q0: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Default configuration (Pinocchio convention); TALOS: half-sitting, soles on the ground z = 0."""
    kp: np.ndarray | None = None
    """Default joint stiffness of a position-mode PD (actuated order), N m/rad; None: none."""
    kd: np.ndarray | None = None
    """Default joint damping of a position-mode PD (actuated order), N m s/rad; None: none."""
    fall_height: float | None = None
    """Base height (m) under which the robot has fallen; None: no fall detection (a fixed base)."""


def pinocchio_model(name: str = "talos") -> Any:
    """The Pinocchio model of a robot source (the robot family's cached one; do not modify)."""
    from dgraph.entities.robot import load_model

    return load_model(name)


def _urdf_text(relative: str) -> tuple[str, str]:
    """The URDF text with MuJoCo-resolvable mesh paths, and the mesh directory."""
    import example_robot_data as erd

    robots = erd.getModelPath(relative)
    with open(os.path.join(robots, relative), encoding="utf-8") as f:
        text = f.read()
    return text.replace("package://example-robot-data/robots/", ""), robots


def talos_spec(dt: float = 0.001, collisions: str = "all") -> tuple[mujoco.MjSpec, RobotInfo]:
    """An ``MjSpec`` of TALOS (no floor, no light) and its :class:`RobotInfo`.

    ``collisions``: ``"all"`` (the sole boxes and every other collision mesh touch the scene,
    none touches the robot itself) or ``"feet"`` (only the sole boxes: a fallen robot goes
    through the floor).
    """
    if collisions not in ("feet", "all"):
        raise ValueError(f"collisions must be 'feet' or 'all', got {collisions!r}")
    pin_model = pinocchio_model("talos")
    text, mesh_dir = _urdf_text(TALOS_URDF)
    compiler = (f'<mujoco><compiler meshdir="{mesh_dir}" strippath="false" fusestatic="false" '
                'discardvisual="false" balanceinertia="false" autolimits="true"/></mujoco>')
    text = re.sub(r"(<robot[^>]*>)", lambda match: match.group(1) + compiler, text, count=1)
    spec = mujoco.MjSpec.from_string(text)
    spec.modelname = "talos"
    spec.option.timestep = dt
    spec.body("base_link").add_freejoint(name="root_joint")

    _add_motors(spec, pin_model)

    feet = ("leg_left_6_link", "leg_right_6_link")
    for geom in spec.geoms:
        if geom.contype == 0 and geom.conaffinity == 0:  # a visual mesh (group 1)
            continue
        geom.group = COLLISION_GROUP
        geom.conaffinity = 0  # robot geoms never collide with each other (contype & conaffinity)
        geom.contype = 1 if collisions == "all" and geom.parent.name not in feet else 0
    for foot in feet:
        spec.body(foot).add_geom(
            name=f"{foot}_sole", type=mujoco.mjtGeom.mjGEOM_BOX, size=list(SOLE_HALF_SIZE),
            pos=[SOLE_CENTER_X, 0.0, -SOLE_DEPTH + SOLE_HALF_SIZE[2]], contype=1, conaffinity=0,
            group=COLLISION_GROUP, rgba=[0.2, 0.2, 0.2, 1.0])

    imu = SensorSite("imu", "imu_link", "imu_link")
    force_torque = {
        "left_ankle": SensorSite("ft_left_ankle", "leg_left_6_link", "leg_left_6_joint"),
        "right_ankle": SensorSite("ft_right_ankle", "leg_right_6_link", "leg_right_6_joint"),
        "left_wrist": SensorSite("ft_left_wrist", "wrist_left_ft_link", "wrist_left_ft_link"),
        "right_wrist": SensorSite("ft_right_wrist", "wrist_right_ft_link", "wrist_right_ft_link"),
    }
    _add_sensor_sites(spec, imu, force_torque)
    # kp 3000, kd 60 hold TALOS standing; the grippers (no rotor inertia, 1.2e-3 kg m²) need far
    # lower gains: an explicit PD is stable at 1 ms only while kd dt / inertia < 2
    kp, kd = np.full(pin_model.nv - 6, 3000.0), np.full(pin_model.nv - 6, 60.0)
    grippers = [pin_model.joints[pin_model.getJointId(f"gripper_{s}_joint")].idx_v - 6 for s in ("left", "right")]
    kp[grippers], kd[grippers] = 100.0, 1.0
    info = RobotInfo("talos", pin_model, "base_link", floating_base=True, feet=feet, imu=imu,
                     force_torque=force_torque, q0=_standing_q0(pin_model), kp=kp, kd=kd, fall_height=0.6)
    return spec, info


def _add_motors(spec: mujoco.MjSpec, pin_model: Any) -> None:
    """A torque motor on every actuated (one-dof, non-root) joint of ``pin_model``, in its order:
    gear 1, the URDF effort limit as ``ctrlrange`` and ``actfrcrange``, the armature of the
    Pinocchio model, no damping nor friction loss (see the module docstring)."""
    by_name = {j.name: j for j in spec.joints}
    first = 2 if has_free_flyer(pin_model) else 1
    for jid in range(first, pin_model.njoints):
        name = pin_model.names[jid]
        joint = by_name.get(name)
        if joint is None or pin_model.joints[jid].nv != 1 or pin_model.joints[jid].nq != 1:
            raise ValueError(f"joint {name!r} of {spec.modelname}: only one-dof joints (revolute, prismatic) "
                             "with a MuJoCo twin of the same name are supported")
        idx_v = pin_model.joints[jid].idx_v
        joint.damping = [0.0, 0.0, 0.0]
        joint.frictionloss = 0.0
        joint.armature = float(pin_model.armature[idx_v])
        effort = float(pin_model.effortLimit[idx_v])
        joint.actfrcrange = [-effort, effort]
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
        motor = spec.add_actuator(name=name, target=name)
        motor.trntype = mujoco.mjtTrn.mjTRN_JOINT
        motor.set_to_motor()
        motor.ctrlrange = [-effort, effort]
        motor.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE


def _add_sensor_sites(spec: mujoco.MjSpec, imu: SensorSite, force_torque: dict[str, SensorSite]) -> None:
    """Sites at the sensor frames (body origins) and the MuJoCo sensors reading them."""
    site_type = mujoco.mjtObj.mjOBJ_SITE
    spec.body(imu.body).add_site(name=imu.site, size=[0.01, 0.01, 0.01], group=4)
    for kind, suffix in ((mujoco.mjtSensor.mjSENS_FRAMEQUAT, "quat"), (mujoco.mjtSensor.mjSENS_GYRO, "gyro"),
                         (mujoco.mjtSensor.mjSENS_ACCELEROMETER, "accelerometer")):
        spec.add_sensor(name=f"{imu.site}_{suffix}", type=kind, objtype=site_type, objname=imu.site)
    for site in force_torque.values():
        spec.body(site.body).add_site(name=site.site, size=[0.01, 0.01, 0.01], group=4)
        spec.add_sensor(name=f"{site.site}_force", type=mujoco.mjtSensor.mjSENS_FORCE, objtype=site_type,
                        objname=site.site)
        spec.add_sensor(name=f"{site.site}_torque", type=mujoco.mjtSensor.mjSENS_TORQUE, objtype=site_type,
                        objname=site.site)


def _standing_q0(pin_model: Any) -> np.ndarray:
    """SRDF ``half_sitting`` with the base height that puts the lower sole on z = 0."""
    import pinocchio as pin

    q = np.array(pin_model.referenceConfigurations["half_sitting"], dtype=float)
    q[2] = 0.0
    data = pin_model.createData()
    pin.framesForwardKinematics(pin_model, data, q)
    soles = [data.oMf[pin_model.getFrameId(f)].translation[2] for f in ("left_sole_link", "right_sole_link")]
    q[2] = -min(soles)
    return q


ROBOTS = {"talos": talos_spec}
"""Robots with a builder of their own (sensors, feet, soles): ``builder(dt, collisions) -> (MjSpec,
RobotInfo)``. Every other robot source is built by :func:`urdf_spec`."""

MESH_FORMATS = (".stl", ".obj", ".msh")
"""Mesh files MuJoCo reads."""
DRAWN_COLLISION_GROUP = 2
"""Geom group of the collision geoms of a body whose visual meshes MuJoCo cannot read (drawn by default)."""


def robot_spec(source: str, dt: float = 0.001, collisions: str = "all",
               package_dirs: tuple[str, ...] = (), mjcf: str | None = None) -> tuple[mujoco.MjSpec, RobotInfo]:
    """The ``MjSpec`` (no floor, no light) and :class:`RobotInfo` of an example-robot-data robot name
    or a URDF path (``package_dirs``: where its ``package://`` meshes may be, see :func:`urdf_spec`).

    ``mjcf``: the path of an MJCF file describing the same robot for MuJoCo (:func:`mjcf_spec`);
    the source then gives only the Pinocchio model and the :class:`RobotInfo` (its URDF is not
    read by MuJoCo, so its meshes need not be found)."""
    from dgraph.entities.robot.loading import check_source, describe_robot, is_urdf_path, load_model

    if mjcf is not None:
        if collisions != "all":
            raise ValueError(f"collisions {collisions!r} applies to robots built from a URDF; the contacts of an "
                             "MJCF are used as it writes them")
        if source in ROBOTS:
            info = ROBOTS[source](dt, collisions)[1]
        else:
            check_source(source)
            if is_urdf_path(source):
                path = os.path.realpath(source)
                model, name, q0 = load_model(path), os.path.splitext(os.path.basename(path))[0], None
            else:
                robot = describe_robot(source)
                model, name, q0 = robot.model, source, np.asarray(robot.q0, dtype=float)
            info = RobotInfo(name, model, "", floating_base=has_free_flyer(model), q0=_default_q0(model, name, q0))
        return mjcf_spec(mjcf, info, dt)
    if source in ROBOTS:
        return ROBOTS[source](dt, collisions)
    check_source(source)
    if is_urdf_path(source):
        path = os.path.realpath(source)
        return urdf_spec(path, load_model(path), os.path.splitext(os.path.basename(path))[0], dt, collisions,
                         package_dirs)
    robot = describe_robot(source)
    return urdf_spec(os.path.realpath(robot.urdf), robot.model, source, dt, collisions, package_dirs,
                     np.asarray(robot.q0, dtype=float))


def urdf_spec(urdf: str, pin_model: Any, name: str, dt: float = 0.001, collisions: str = "all",
              package_dirs: tuple[str, ...] = (), q0: np.ndarray | None = None) -> tuple[mujoco.MjSpec, RobotInfo]:
    """An ``MjSpec`` of the URDF file ``urdf`` (no floor, no light) and its :class:`RobotInfo`, for
    ``pin_model``, the Pinocchio model of that file (a free-flyer root or a fixed base).

    ``collisions``: ``"all"`` (every collision geom touches the scene, none the robot itself) or
    ``"feet"`` (none: such a robot has no feet). ``q0``: the default configuration (Pinocchio
    convention; default: the neutral one), clipped into the joint limits.
    """
    if collisions not in ("feet", "all"):
        raise ValueError(f"collisions must be 'feet' or 'all', got {collisions!r}")
    text, drawn = _resolved_urdf(urdf, package_dirs)
    spec = mujoco.MjSpec.from_string(text)
    spec.modelname = name
    spec.option.timestep = dt
    root = spec.worldbody.first_body()
    floating = has_free_flyer(pin_model)
    if floating:
        root.add_freejoint(name=pin_model.names[1])
    for equality in list(spec.equalities):  # URDF <mimic>: Pinocchio's model has independent joints
        spec.delete(equality)
    _add_motors(spec, pin_model)
    for geom in spec.geoms:
        if geom.contype == 0 and geom.conaffinity == 0:  # a visual mesh (group 1)
            continue
        geom.group = DRAWN_COLLISION_GROUP if geom.parent.name in drawn else COLLISION_GROUP
        geom.conaffinity = 0  # robot geoms never collide with each other
        geom.contype = 1 if collisions == "all" else 0
    info = RobotInfo(name, pin_model, root.name, floating_base=floating, q0=_default_q0(pin_model, name, q0))
    return spec, info


def _default_q0(pin_model: Any, name: str, q0: np.ndarray | None) -> np.ndarray:
    """``q0`` (default: the neutral configuration) with the joints clipped into their limits."""
    q = np.asarray(pinocchio.neutral(pin_model) if q0 is None else q0, dtype=float).copy()
    if q.shape != (pin_model.nq,):
        raise ValueError(f"{name}: q0 needs {pin_model.nq} values, got {q.shape}")
    joints = slice(7 if has_free_flyer(pin_model) else 0, None)
    q[joints] = np.clip(q[joints], pin_model.lowerPositionLimit[joints], pin_model.upperPositionLimit[joints])
    return q


def _resolved_urdf(urdf: str, package_dirs: tuple[str, ...]) -> tuple[str, set[str]]:
    """The text of ``urdf`` for MuJoCo: mesh paths absolute, visual meshes MuJoCo cannot read left out,
    the compiler options of this module; and the links left without a visual geometry by that."""
    from dgraph.entities.robot.loading import package_dirs_of

    tree = ElementTree.parse(urdf)
    robot = tree.getroot()
    folder = os.path.dirname(urdf)
    search = package_dirs_of(urdf, tuple(package_dirs))
    drawn = set()
    for link in robot.iter("link"):
        visuals = link.findall("visual")
        for element in [*visuals, *link.findall("collision")]:
            mesh = element.find("geometry/mesh")
            if mesh is None:
                continue
            path = _mesh_path(mesh.get("filename", ""), folder, search, urdf)
            if element.tag == "visual" and os.path.splitext(path)[1].lower() not in MESH_FORMATS:
                link.remove(element)
                visuals.remove(element)
                continue
            mesh.set("filename", path)
        if not visuals:
            drawn.add(link.get("name"))
    ElementTree.SubElement(ElementTree.SubElement(robot, "mujoco"), "compiler", {
        "strippath": "false", "fusestatic": "false", "discardvisual": "false", "balanceinertia": "false",
        "autolimits": "true"})
    return ElementTree.tostring(robot, encoding="unicode"), drawn


def _mesh_path(filename: str, folder: str, search: list[str], urdf: str) -> str:
    """The absolute path of a URDF mesh ``filename`` (relative to the URDF's ``folder``, ``file://``,
    or ``package://PKG/rest`` found as ``DIR/PKG/rest`` for the first ``DIR`` of ``search``)."""
    if filename.startswith("package://"):
        relative = filename[len("package://"):]
        for directory in search:
            candidate = os.path.join(directory, relative)
            if os.path.isfile(candidate):
                return candidate
        raise ValueError(f"{urdf}: mesh {filename!r} is in none of the package folders {search[:3]}...: give "
                         "the folder holding the package as package_dirs")
    path = filename[len("file://"):] if filename.startswith("file://") else filename
    path = path if os.path.isabs(path) else os.path.join(folder, path)
    if not os.path.isfile(path):
        raise ValueError(f"{urdf}: no mesh file {path!r}")
    return path


# -- a robot described for MuJoCo by an MJCF file ------------------------------------------------

MJCF_TOLERANCE = 0.01
"""Default relative tolerance of :func:`compare_dynamics` (1 %)."""


class MjcfError(ValueError):
    """An MJCF file that does not describe the robot of the Pinocchio model; ``joint`` names the
    joint at fault when there is one."""

    def __init__(self, message: str, joint: str | None = None):
        super().__init__(message)
        self.joint = joint


class MjcfWarning(UserWarning):
    """An MJCF that MuJoCo simulates differently from what the Pinocchio model assumes, within what
    the device accepts (actuator ranges other than the URDF effort limits, joint damping, friction
    loss or springs, which Pinocchio's dynamics do not have)."""


_MJ_KINDS = {mujoco.mjtJoint.mjJNT_HINGE: "hinge", mujoco.mjtJoint.mjJNT_SLIDE: "slide",
             mujoco.mjtJoint.mjJNT_BALL: "ball", mujoco.mjtJoint.mjJNT_FREE: "free"}


def _pin_kind(joint: Any) -> str:
    """``hinge`` (revolute), ``slide`` (prismatic), or Pinocchio's name of any other joint."""
    short = joint.shortname()
    if joint.nq == 1 and joint.nv == 1:
        if short.startswith(("JointModelRevolute", "JointModelR")):
            return "hinge"
        if short.startswith(("JointModelPrismatic", "JointModelP")):
            return "slide"
    return short


def mjcf_spec(path: str, info: RobotInfo, dt: float = 0.001) -> tuple[mujoco.MjSpec, RobotInfo]:
    """The ``MjSpec`` of the MJCF file ``path`` and ``info`` (the robot's, from its URDF or name)
    with ``base_body`` the MJCF's root body; raises :class:`MjcfError` naming the joint at fault.

    The MJCF describes the robot only: its ``worldbody`` holds one body, the robot's root, and no
    geom (the floor and the rest come from the device's scene); lights and cameras may stay. It is
    used as written (meshes, inertias, contacts, joint armature, damping and friction, options but
    the time step), after these checks against ``info.pin_model``:

    * joints match **by name**: every actuated joint of the Pinocchio model is a MuJoCo joint of
      the same name and type (revolute: hinge, prismatic: slide), and the MJCF has no other
      joint; a free joint on the root body iff the Pinocchio model has a free-flyer root (its name
      may differ), none elsewhere;
    * actuators: either none, and the device adds one torque motor per actuated joint as for a
      URDF (gear 1, the URDF effort limit as ``ctrlrange``), or exactly one **motor** (gear 1,
      no bias, no activation dynamics) per actuated joint; a position or velocity servo, a
      general actuator, a tendon or site transmission, a gear other than 1 are refused, because
      the device computes joint torques itself (its position mode is a PD on them). A motor
      without ``ctrlrange`` gets the URDF effort limit; one with a range other than it is kept and
      warned about (:class:`MjcfWarning`): MuJoCo clips there, the controller plans to the URDF's;
    * no equality constraint (a coupling Pinocchio's model does not have) and no gravity
      compensation on a body.

    That the two files describe the same masses and inertias is checked on the compiled model by
    :func:`compare_dynamics` (:func:`dgraph_sim.model.load`). TALOS (a robot of :data:`ROBOTS`)
    keeps its IMU and force/torque sensors: their sites go on the MJCF bodies of the same names.
    """
    pin_model = info.pin_model
    try:
        spec = mujoco.MjSpec.from_file(path)
    except Exception as exc:  # mujoco raises ValueError for XML, file and schema errors
        raise MjcfError(f"cannot read {path}: {exc}") from None
    spec.option.timestep = dt
    roots = list(spec.worldbody.bodies)
    if len(roots) != 1:
        raise MjcfError(f"{path}: the worldbody must hold one body, the robot's root (the scene comes from the "
                        f"device's scene), it holds {len(roots)}: {[b.name for b in roots]}")
    if len(spec.worldbody.geoms):
        raise MjcfError(f"{path}: the worldbody holds geoms {[g.name for g in spec.worldbody.geoms]}: the MJCF "
                        "describes the robot only (the floor and the rest come from the device's scene)")
    root = roots[0]
    floating = has_free_flyer(pin_model)
    first = 2 if floating else 1
    pin_joints = {pin_model.names[j]: pin_model.joints[j] for j in range(first, pin_model.njoints)}
    free = [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_FREE]
    if floating and (len(free) != 1 or free[0].parent.name != root.name):
        raise MjcfError(f"{path}: joint {pin_model.names[1]!r}: the Pinocchio model has a free-flyer root but the "
                        f"MJCF has {'no free joint' if not free else 'free joints'} "
                        f"{[(j.name, j.parent.name) for j in free] if free else ''} instead of one on its root "
                        f"body {root.name!r}", joint=pin_model.names[1])
    if not floating and free:
        raise MjcfError(f"{path}: joint {free[0].name!r}: the Pinocchio model has a fixed base but the MJCF a free "
                        f"joint on body {free[0].parent.name!r}", joint=free[0].name)
    mj_joints = {j.name: j for j in spec.joints if j.type != mujoco.mjtJoint.mjJNT_FREE}
    n_unnamed = sum(1 for j in spec.joints if j.type != mujoco.mjtJoint.mjJNT_FREE and not j.name)
    if n_unnamed:
        body = next(j.parent.name for j in spec.joints if j.type != mujoco.mjtJoint.mjJNT_FREE and not j.name)
        raise MjcfError(f"{path}: {n_unnamed} unnamed joint(s) (the first on body {body!r}): joints are matched to "
                        "the Pinocchio model's by name", joint="")
    missing = [n for n in pin_joints if n not in mj_joints]
    extra = [n for n in mj_joints if n not in pin_joints]
    if missing or extra:
        counts = f"{len(pin_joints)} actuated joints in the Pinocchio model, {len(mj_joints)} in the MJCF"
        parts = ([f"joint(s) {missing} of the Pinocchio model are not in the MJCF"] if missing else []) + \
                ([f"joint(s) {extra} of the MJCF are not in the Pinocchio model"] if extra else [])
        raise MjcfError(f"{path}: {'; '.join(parts)} ({counts}; joints are matched by name)",
                        joint=(missing or extra)[0])
    for name, joint in pin_joints.items():
        want, have = _pin_kind(joint), _MJ_KINDS.get(mj_joints[name].type, str(mj_joints[name].type))
        if want != have:
            raise MjcfError(f"{path}: joint {name!r} is a {have} joint in the MJCF but a {want} joint in the Pinocchio "
                            "model", joint=name)
    if len(spec.equalities):
        eq = spec.equalities[0]
        raise MjcfError(f"{path}: equality constraint {eq.name or '(unnamed)'!r} ({eq.name1} {eq.name2}) couples "
                        "what the Pinocchio model leaves independent: remove it", joint=eq.name1 or None)
    heavy = [b.name for b in spec.bodies if b.gravcomp != 0.0]
    if heavy:
        raise MjcfError(f"{path}: bodies {heavy} have gravity compensation (gravcomp), which the Pinocchio model "
                        "does not have")
    _check_actuators(spec, pin_model, path)
    _warn_passive(spec, path)
    if info.imu is not None or info.force_torque:
        needed = ([info.imu.body] if info.imu is not None else []) + [s.body for s in info.force_torque.values()]
        absent = [b for b in needed if spec.body(b) is None]
        if absent:
            raise MjcfError(f"{path}: {info.name}'s sensors are on bodies {absent}, which the MJCF does not have")
        _add_sensor_sites(spec, info.imu, info.force_torque)
    spec.modelname = spec.modelname or info.name
    return spec, replace(info, base_body=root.name)


def _check_actuators(spec: mujoco.MjSpec, pin_model: Any, path: str) -> None:
    """The MJCF's actuators are one gear-1 motor per actuated joint (a missing ``ctrlrange`` set to
    the URDF effort limit), or there are none and motors are added (see :func:`mjcf_spec`)."""
    first = 2 if has_free_flyer(pin_model) else 1
    effort = {pin_model.names[j]: float(pin_model.effortLimit[pin_model.joints[j].idx_v])
              for j in range(first, pin_model.njoints)}
    actuators = list(spec.actuators)
    if not actuators:
        for name, limit in effort.items():
            motor = spec.add_actuator(name=name, target=name)
            motor.trntype = mujoco.mjtTrn.mjTRN_JOINT
            motor.set_to_motor()
            motor.ctrlrange = [-limit, limit]
            motor.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        return
    advice = ("the device computes joint torques itself (its position mode is a PD on them): give one motor "
              "(gear 1) per actuated joint, or no actuator and the device adds them")
    driven: dict[str, str] = {}
    for act in actuators:
        label = act.name or f"#{actuators.index(act)}"
        if act.trntype != mujoco.mjtTrn.mjTRN_JOINT or act.target not in effort:
            raise MjcfError(f"{path}: actuator {label!r} drives {act.target!r} ({act.trntype.name}), not an actuated "
                            f"joint of the Pinocchio model: {advice}", joint=act.target or None)
        joint = act.target
        if joint in driven:
            raise MjcfError(f"{path}: joint {joint!r} is driven by two actuators, {driven[joint]!r} and {label!r}: "
                            f"{advice}", joint=joint)
        driven[joint] = label
        motor = (act.gaintype == mujoco.mjtGain.mjGAIN_FIXED and act.gainprm[0] == 1.0
                 and act.biastype == mujoco.mjtBias.mjBIAS_NONE and act.dyntype == mujoco.mjtDyn.mjDYN_NONE)
        if not motor:
            kind = "a servo (biased)" if act.biastype != mujoco.mjtBias.mjBIAS_NONE else "not a torque motor"
            raise MjcfError(f"{path}: actuator {label!r} on joint {joint!r} is {kind} (gain {act.gaintype.name} "
                            f"{act.gainprm[0]:g}, bias {act.biastype.name}, dynamics {act.dyntype.name}): {advice}",
                            joint=joint)
        gear = np.asarray(act.gear, dtype=float)
        if gear[0] != 1.0 or gear[1:].any():
            raise MjcfError(f"{path}: actuator {label!r} on joint {joint!r} has gear {gear.tolist()}: {advice}",
                            joint=joint)
        low, high = (float(x) for x in act.ctrlrange)
        if act.ctrllimited == mujoco.mjtLimited.mjLIMITED_FALSE or low == high == 0.0:
            act.ctrlrange = [-effort[joint], effort[joint]]
        elif not (high > 0.0 and low == -high):
            raise MjcfError(f"{path}: actuator {label!r} on joint {joint!r} has ctrlrange [{low:g}, {high:g}]: the "
                            "device clips torques to a symmetric range [-limit, limit]", joint=joint)
        elif high != effort[joint]:
            warnings.warn(f"{path}: actuator {label!r} on joint {joint!r} has ctrlrange ±{high:g}, the URDF effort "
                          f"limit is ±{effort[joint]:g}: MuJoCo clips at ±{high:g}, the controller (Pinocchio) "
                          f"plans up to ±{effort[joint]:g}", MjcfWarning, stacklevel=4)
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    missing = [j for j in effort if j not in driven]
    if missing:
        raise MjcfError(f"{path}: joint(s) {missing} have no actuator ({len(actuators)} actuators for {len(effort)} "
                        f"actuated joints): {advice}", joint=missing[0])


def _warn_passive(spec: mujoco.MjSpec, path: str) -> None:
    """Warn once about joint damping, friction loss and springs: MuJoCo applies them, Pinocchio's
    dynamics (so the controller's model) do not have them."""
    passive = [j.name for j in spec.joints
               if np.any(np.asarray(j.damping)) or j.frictionloss or np.any(np.asarray(j.stiffness))]
    if passive:
        warnings.warn(f"{path}: joints {passive} have damping, friction loss or a spring, which MuJoCo applies and "
                      "the controller's Pinocchio model does not have", MjcfWarning, stacklevel=4)


def _check_configurations(pin_model: Any, q0: np.ndarray, count: int = 3) -> list[np.ndarray]:
    """``q0`` and ``count`` configurations with the joints drawn (seeded) within their limits
    (where a limit is infinite, within ±1 of ``q0``), the base of ``q0``."""
    rng = np.random.default_rng(0)
    n_base = 7 if has_free_flyer(pin_model) else 0
    low = np.asarray(pin_model.lowerPositionLimit[n_base:], dtype=float)
    high = np.asarray(pin_model.upperPositionLimit[n_base:], dtype=float)
    low = np.where(np.isfinite(low), low, q0[n_base:] - 1.0)
    high = np.where(np.isfinite(high), high, q0[n_base:] + 1.0)
    configurations = [np.asarray(q0, dtype=float)]
    for _ in range(count):
        q = configurations[0].copy()
        q[n_base:] = rng.uniform(low, high)
        configurations.append(q)
    return configurations


def compare_dynamics(mj_model: mujoco.MjModel, joint_map: Any, pin_model: Any, q0: np.ndarray,
                     tolerance: float = MJCF_TOLERANCE, path: str = "the MJCF") -> dict[str, float]:
    """Check that ``mj_model`` (built from an MJCF) and ``pin_model`` (from the URDF) are the same
    rigid-body system where the controller relies on it; raises :class:`MjcfError` beyond
    ``tolerance``, else returns the three relative differences measured:

    * ``link_mass``: the mass each joint moves (its link and the links welded to it, Pinocchio's
      joint inertia), ``|m_mj - m_pin| / max(m_mj, m_pin)``;
    * ``mass_matrix``: ``|M_mj - M_pin|_ij / sqrt(M_pin,ii M_pin,jj)`` (``M_mj`` in Pinocchio's
      coordinates, ``Tᵀ M T``, armature included on both sides);
    * ``gravity``: ``|g_mj - g_pin|_i / max |g_pin|`` (the largest gravity torque or force);

    the last two at ``q0`` and three configurations drawn (seeded) within the joint limits.
    """
    import pinocchio as pin

    floating = joint_map.floating_base
    names = ([f"{pin_model.names[1]}[{i}]" for i in range(6)] if floating else []) + list(joint_map.joint_names)
    # the mass each joint moves: a MuJoCo body belongs to its nearest ancestor (or itself) with a joint
    pin_ids = {pin_model.names[j]: j for j in range(1, pin_model.njoints)}
    mj_mass = dict.fromkeys(pin_ids, 0.0)
    for body in range(1, mj_model.nbody):
        owner = body
        while owner > 0 and not mj_model.body_jntnum[owner]:
            owner = int(mj_model.body_parentid[owner])
        if owner == 0:
            continue  # welded to the world (a fixed base's root link)
        jnt = int(mj_model.body_jntadr[owner])
        name = pin_model.names[1] if floating and jnt == joint_map.free_joint else mujoco.mj_id2name(
            mj_model, mujoco.mjtObj.mjOBJ_JOINT, jnt)
        if name in mj_mass:  # scene bodies (free blocks) are not the robot's
            mj_mass[name] += float(mj_model.body_mass[body])
    worst: dict[str, tuple[float, str, str]] = {}  # kind: (relative error, what, joint)
    for name, jid in pin_ids.items():
        m_pin, m_mj = float(pin_model.inertias[jid].mass), mj_mass[name]
        error = abs(m_mj - m_pin) / max(m_mj, m_pin, 1e-12)
        if error > worst.get("link_mass", (-1.0,))[0]:
            worst["link_mass"] = (error, f"the link moved by joint {name!r} weighs {m_mj:.6g} kg in the MJCF, "
                                         f"{m_pin:.6g} kg in the URDF", name)
    data, d = pin_model.createData(), mujoco.MjData(mj_model)
    configurations = _check_configurations(pin_model, q0)
    gravities = [pin.computeGeneralizedGravity(pin_model, data, q).copy() for q in configurations]
    scale = max(float(np.abs(np.array(gravities)).max()), 1e-12)
    M = np.zeros((mj_model.nv, mj_model.nv))
    for k, (q, g_pin) in enumerate(zip(configurations, gravities, strict=True)):
        where = "the reference configuration" if k == 0 else f"configuration {k} (seeded, within the limits)"
        mujoco.mj_resetData(mj_model, d)
        joint_map.qpos_from_q(q, d.qpos)
        mujoco.mj_forward(mj_model, d)
        mujoco.mj_fullM(mj_model, d, M)
        T = joint_map.velocity_transform(q)
        M_pin = pin.crba(pin_model, data, q)
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        diag = np.sqrt(np.maximum(np.diag(M_pin), 1e-12))
        error = np.abs(T.T @ M @ T - M_pin) / np.outer(diag, diag)
        i, j = np.unravel_index(int(np.argmax(error)), error.shape)
        if error[i, j] > worst.get("mass_matrix", (-1.0,))[0]:
            worst["mass_matrix"] = (float(error[i, j]), f"mass matrix entry ({names[i]}, {names[j]}) at {where}: "
                                    f"{(T.T @ M @ T)[i, j]:.6g} in the MJCF, {M_pin[i, j]:.6g} in the URDF", names[j])
        g_mj = joint_map.generalized_force_from_qfrc(q, d.qfrc_bias.copy())
        error = np.abs(g_mj - g_pin) / scale
        i = int(np.argmax(error))
        if error[i] > worst.get("gravity", (-1.0,))[0]:
            worst["gravity"] = (float(error[i]), f"gravity torque on joint {names[i]!r} at {where}: {g_mj[i]:.6g} "
                                f"in the MJCF, {g_pin[i]:.6g} in the URDF", names[i])
    bad = [(key, *value) for key, value in worst.items() if value[0] > tolerance]
    if bad:
        raise MjcfError(f"{path} and the URDF of the Pinocchio model disagree beyond the relative tolerance "
                        f"{tolerance:g} (mjcf_tolerance): " + "; ".join(f"{text} ({key} {error:.3g})"
                                                                         for key, error, text, _ in bad),
                        joint=bad[0][3])
    return {key: value[0] for key, value in worst.items()}


def apply_chains(m: mujoco.MjModel, chains: dict[str, Any], source: str = "actuator file") -> None:
    """Give the named joints of the compiled model ``m`` the dynamics of their actuator chains
    (:class:`dgraph.entities.actuators.ChainParameters`, :func:`dgraph.entities.actuators.chain.mujoco_joint`):
    ``armature`` = I_m (replacing the URDF's rotor inertia; the link's inertia stays the rigid
    body's), ``damping`` = F_vm + F_vj, ``frictionloss`` = F_sm + F_sj, and ``±R K_m i_max`` as
    the joint's ``actfrcrange`` and its motor's ``ctrlrange`` (MuJoCo clips there, the device
    too). Applied to the compiled model, after :func:`compare_dynamics` (the Pinocchio model
    keeps its own armature: the chain is the actuator model's to compensate). A joint missing
    from ``m`` or without a motor raises ``ValueError`` naming ``source``."""
    from dgraph.entities.actuators.chain import mujoco_joint

    joint_trn = int(mujoco.mjtTrn.mjTRN_JOINT)
    motors = {int(m.actuator_trnid[a, 0]): a for a in range(m.nu) if int(m.actuator_trntype[a]) == joint_trn}
    for name, chain in chains.items():
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid < 0 or jid not in motors or int(m.jnt_type[jid]) not in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                                                        int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise ValueError(f"{source}: joint {name!r} is not an actuated one-dof joint of the robot")
        dof, motor = int(m.jnt_dofadr[jid]), motors[jid]
        values = mujoco_joint(chain)
        m.dof_armature[dof] = values["armature"]
        m.dof_damping[dof] = values["damping"]
        m.dof_frictionloss[dof] = values["frictionloss"]
        limit = values["force_limit"]
        if np.isfinite(limit):
            m.jnt_actfrcrange[jid] = [-limit, limit]
            m.jnt_actfrclimited[jid] = 1
            m.actuator_ctrlrange[motor] = [-limit, limit]
            m.actuator_ctrllimited[motor] = 1
    mujoco.mj_setConst(m, mujoco.MjData(m))  # the constants derived from the inertia (dof_invweight0...)
