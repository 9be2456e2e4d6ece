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
from dataclasses import dataclass, field
from typing import Any
from xml.etree import ElementTree

import mujoco
import numpy as np
import pinocchio

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
    first = 2 if _has_free_flyer(pin_model) else 1
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


def _has_free_flyer(pin_model: Any) -> bool:
    return pin_model.njoints > 1 and pin_model.joints[1].shortname() == "JointModelFreeFlyer"


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
               package_dirs: tuple[str, ...] = ()) -> tuple[mujoco.MjSpec, RobotInfo]:
    """The ``MjSpec`` (no floor, no light) and :class:`RobotInfo` of an example-robot-data robot name
    or a URDF path (``package_dirs``: where its ``package://`` meshes may be, see :func:`urdf_spec`)."""
    from dgraph.entities.robot.loading import check_source, is_urdf_path, load_model, load_robot

    if source in ROBOTS:
        return ROBOTS[source](dt, collisions)
    check_source(source)
    if is_urdf_path(source):
        path = os.path.realpath(source)
        return urdf_spec(path, load_model(path), os.path.splitext(os.path.basename(path))[0], dt, collisions,
                         package_dirs)
    robot = load_robot(source)
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
    floating = _has_free_flyer(pin_model)
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
    q = np.asarray(pinocchio.neutral(pin_model) if q0 is None else q0, dtype=float).copy()
    if q.shape != (pin_model.nq,):
        raise ValueError(f"{name}: q0 needs {pin_model.nq} values, got {q.shape}")
    joints = slice(7 if floating else 0, None)
    q[joints] = np.clip(q[joints], pin_model.lowerPositionLimit[joints], pin_model.upperPositionLimit[joints])
    info = RobotInfo(name, pin_model, root.name, floating_base=floating, q0=q)
    return spec, info


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
