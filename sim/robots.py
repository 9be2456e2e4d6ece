"""MuJoCo robot models built at run time from example-robot-data URDFs.

Only TALOS for now: :func:`talos_spec` builds an ``MjSpec`` of the **same** URDF that
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

import mujoco
import numpy as np

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
    feet: tuple[str, ...]
    imu: SensorSite
    force_torque: dict[str, SensorSite] = field(default_factory=dict)
    q0: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Default configuration (Pinocchio convention): half-sitting, soles on the ground z = 0."""
    kp: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Default joint stiffness of a position-mode PD (actuated order), N m/rad."""
    kd: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Default joint damping of a position-mode PD (actuated order), N m s/rad."""


def pinocchio_model(name: str = "talos") -> Any:
    """The Pinocchio model of an example-robot-data robot (the robot family's cached one; do not modify)."""
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

    by_name = {j.name: j for j in spec.joints}
    for jid in range(2, pin_model.njoints):
        name = pin_model.names[jid]
        joint = by_name[name]
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
    info = RobotInfo("talos", pin_model, "base_link", feet, imu, force_torque, _standing_q0(pin_model), kp, kd)
    return spec, info


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
"""Robot spec builders by name: ``builder(dt, collisions) -> (MjSpec, RobotInfo)``."""
