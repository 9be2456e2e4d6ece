"""A compiled simulation model: robot + scene as an ``MjModel``, with its Pinocchio twin.

:func:`load` is cached per process on its arguments: devices share the ``MjModel`` (each has its
own ``MjData``) and must not modify it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import mujoco
import numpy as np

from dgraph.entities.robot.loading import file_stamp, is_urdf_path
from dgraph_sim.conventions import JointMap
from dgraph_sim.robots import (
    MJCF_TOLERANCE,
    MjcfError,
    RobotInfo,
    apply_chains,
    compare_dynamics,
    robot_spec,
)
from dgraph_sim.scenes import add_scene


@dataclass(frozen=True)
class SensorLayout:
    """Addresses in ``MjData.sensordata`` of the robot's sensors (the IMU's are None without an IMU)."""

    imu_quat: int | None
    imu_gyro: int | None
    imu_accelerometer: int | None
    force: dict[str, int]
    torque: dict[str, int]


@dataclass(frozen=True)
class SimModel:
    """An ``MjModel`` of a robot in a scene, the Pinocchio model it matches, and the maps between them."""

    mj_model: mujoco.MjModel
    pin_model: Any
    joint_map: JointMap
    robot: RobotInfo
    sensors: SensorLayout
    robot_bodies: slice
    """Ids of the robot's bodies (the base's subtree, contiguous: the robot is built before the scene)."""

    @property
    def q0(self) -> np.ndarray:
        """The robot's default configuration (a copy), Pinocchio convention."""
        return self.robot.q0.copy()


def _sensor_adr(m: mujoco.MjModel, name: str) -> int:
    return int(m.sensor_adr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, name)])


def load(robot: str = "talos", scene: str = "flat", dt: float = 0.001, collisions: str = "all",
         package_dirs: tuple[str, ...] = (), mjcf: str | None = None,
         mjcf_tolerance: float = MJCF_TOLERANCE, actuators: str | None = None) -> SimModel:
    """Build (once per process and arguments) the MuJoCo model of ``robot`` (an example-robot-data
    name or a URDF path, :func:`dgraph_sim.robots.robot_spec`) in ``scene``.

    ``mjcf``: an MJCF file describing the robot for MuJoCo (:func:`dgraph_sim.robots.mjcf_spec`;
    relative: to the working directory), checked against the Pinocchio model of ``robot`` by
    :func:`dgraph_sim.robots.compare_dynamics` with ``mjcf_tolerance``; a mismatch raises
    :class:`~dgraph_sim.robots.MjcfError`. The cache knows the MJCF file, and a URDF file given
    as ``robot``, by its real path, size and modification time, so an edited file is read again
    (``package_dirs``: by their absolute paths).

    ``actuators``: an actuator parameter file
    (:func:`dgraph.entities.actuators.chain.load_chain_file`) whose joints get their chain's
    armature, damping, friction loss and force range (:func:`dgraph_sim.robots.apply_chains`);
    a bad file or an unknown joint raises :class:`~dgraph.entities.actuators.chain.ChainFileError`.
    The cache knows it by its real path, size and modification time too."""
    urdf_stamp = None
    if is_urdf_path(robot) and os.path.isfile(robot):  # else robot_spec refuses it
        robot = os.path.realpath(robot)
        urdf_stamp = file_stamp(robot)
    stamp = None
    if mjcf is not None:
        mjcf = os.path.realpath(mjcf)
        try:
            status = os.stat(mjcf)
        except OSError as exc:
            raise MjcfError(f"cannot read {mjcf}: {exc.strerror}") from None
        stamp = (status.st_size, status.st_mtime_ns)
    actuators_stamp = None
    if actuators is not None:
        actuators = os.path.realpath(actuators)
        actuators_stamp = file_stamp(actuators) if os.path.isfile(actuators) else None
    package_dirs = tuple(os.path.abspath(folder) for folder in package_dirs)
    return _load(robot, scene, dt, collisions, package_dirs, mjcf, stamp, float(mjcf_tolerance), urdf_stamp,
                 actuators, actuators_stamp)


@lru_cache(maxsize=16)
def _load(robot: str, scene: str, dt: float, collisions: str, package_dirs: tuple[str, ...], mjcf: str | None,
          stamp: tuple[int, int] | None, mjcf_tolerance: float, urdf_stamp: tuple[int, int] | None,
          actuators: str | None = None, actuators_stamp: tuple[int, int] | None = None) -> SimModel:
    """:func:`load`, cached (``stamp``, ``urdf_stamp`` and ``actuators_stamp``: the size and
    modification time of the MJCF, of a URDF ``robot`` and of the actuator file, keys only)."""
    if not (dt > 0.0 and np.isfinite(dt)):
        raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
    spec, info = robot_spec(robot, dt, collisions, tuple(package_dirs), mjcf)
    add_scene(spec, scene, tracked_body=info.base_body)
    # NaN must reach our divergence check instead of MuJoCo silently resetting the state
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
    try:
        m = spec.compile()
    except ValueError as exc:
        if mjcf is None:
            raise
        raise MjcfError(f"{mjcf}: MuJoCo cannot compile it in scene {scene!r}: {exc}") from None
    imu = info.imu
    sensors = SensorLayout(
        imu_quat=None if imu is None else _sensor_adr(m, f"{imu.site}_quat"),
        imu_gyro=None if imu is None else _sensor_adr(m, f"{imu.site}_gyro"),
        imu_accelerometer=None if imu is None else _sensor_adr(m, f"{imu.site}_accelerometer"),
        force={k: _sensor_adr(m, f"{s.site}_force") for k, s in info.force_torque.items()},
        torque={k: _sensor_adr(m, f"{s.site}_torque") for k, s in info.force_torque.items()},
    )
    base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, info.base_body)
    if base < 0:
        raise ValueError(f"the base body {info.base_body!r} of {robot} is not in the MuJoCo model")
    ids = [b for b in range(m.nbody) if m.body_rootid[b] == base]
    if ids != list(range(ids[0], ids[-1] + 1)):
        raise ValueError(f"the bodies of {robot} are not contiguous in the MuJoCo model")
    bodies = slice(ids[0], ids[-1] + 1)
    try:
        joint_map = JointMap(info.pin_model, m)
    except ValueError as exc:
        if mjcf is None:
            raise
        raise MjcfError(f"{mjcf}: {exc}") from None
    if mjcf is not None:
        compare_dynamics(m, joint_map, info.pin_model, info.q0, mjcf_tolerance, mjcf)
    if actuators is not None:
        from dgraph.entities.actuators.chain import ChainFileError, load_chain_file

        try:
            apply_chains(m, load_chain_file(actuators), actuators)
        except ValueError as exc:
            raise ChainFileError(str(exc)) from None
    return SimModel(m, info.pin_model, joint_map, info, sensors, bodies)
