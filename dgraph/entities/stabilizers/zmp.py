"""The zero-moment point measured by force/torque sensors, as functions and as an entity."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.entities.robot.robot_state import RobotState, frame_problems
from dgraph.entities.robot.rotations import cross

GRAVITY = 9.81


def world_wrench(position: np.ndarray, rotation: np.ndarray, wrench: np.ndarray) -> np.ndarray:
    """A sensor-frame ``[force, torque about the sensor origin]`` as ``[force, torque about the
    world origin]``, world axes: ``f_W = R f``, ``τ_O = p × f_W + R τ``."""
    world = (rotation @ wrench.reshape(2, 3).T).T.tolist()  # [R f, R τ]
    moment = cross(position.tolist(), world[0])
    return np.array([*world[0], moment[0] + world[1][0], moment[1] + world[1][1], moment[2] + world[1][2]])


def point_force(point: np.ndarray, force: np.ndarray) -> np.ndarray:
    """``[f, p × f]``: a force applied at ``point``, as a wrench about the world origin."""
    f = force.tolist()
    return np.array([*f, *cross(point.tolist(), f)])


def zero_moment_point(wrench: np.ndarray, height: float = 0.0) -> np.ndarray:
    """The point ``p`` of the plane ``z = height`` about which the total contact wrench (world
    axes, torque about the origin) has no horizontal moment (thesis §2.2.1):
    ``p_x = (h f_x − τ_y) / f_z``, ``p_y = (h f_y + τ_x) / f_z``."""
    f, tau = wrench[:3], wrench[3:]
    return np.array([(height * f[0] - tau[1]) / f[2], (height * f[1] + tau[0]) / f[2], height])


@dg.register
class ZmpEstimator(dg.Entity):
    """Measured ZMP from the ankle force/torque sensors (thesis §2.2.1; used by Eq. 2.30–2.31).

    Each sensor gives the wrench its foot exerts on its leg, in the sensor frame (MuJoCo's
    ankle sensors, ``MujocoDevice.ft_*_ankle``). With ``compensate_feet`` the wrench of the
    ground on the foot is that wrench plus the foot's weight at the foot's centre of mass
    (``w_ground = w_sensor + [m g ẑ, c × m g ẑ]``; static: the foot's acceleration is
    neglected). The wrenches are summed about the world origin (``world_wrench``: total force
    ``f``, torque ``τ``) and the ZMP is where their horizontal moment vanishes on the horizontal
    plane ``z = h`` of the tick, ``h = plane_height(t)`` (``zero_moment_point``, thesis §2.2.1):

        p_x = (h f_x − τ_y) / f_z,   p_y = (h f_y + τ_x) / f_z,   p_z = h.

    On flat ground ``h`` is the floor's height (the ``height`` parameter, the input's default);
    on stairs or platforms the plane follows the support (plug the planned ZMP's height). For
    pure forces ``f_i`` applied at points ``c_i`` (``τ = Σ c_i × f_i``) this is

        p_xy = Σ_i (f_iz c_i,xy − f_i,xy (c_iz − h)) / f_z:

    vertical forces give the same horizontal point on every plane; a horizontal force moves it
    along its line of action, by ``−f_i,xy (c_iz − h) / f_z``.
    Below ``min_normal_force`` of total vertical force (no contact) the ZMP is undefined and the
    output is the mean of the sensor frames' horizontal positions, on the plane.

    Parameters: ``sensors`` (names of the wrench inputs), ``frames`` (their Pinocchio frames,
    same order; TALOS: ``leg_left_6_joint``, ``leg_right_6_joint``), ``compensate_feet``,
    ``height`` (m, the default of ``plane_height``), ``min_normal_force`` (N).
    Inputs: ``robot`` (a RobotModel's state at the measured configuration), one wrench (6) per
    sensor, ``plane_height`` (scalar, m; default ``height``). Outputs: ``wrench`` (total ground
    wrench, world axes, torque about the origin), ``zmp`` (3, world), ``normal_force`` (N).
    """

    sensors = dg.Param(["ft_left_ankle", "ft_right_ankle"], kind="str_list", doc="wrench input names")
    frames = dg.Param(["leg_left_6_joint", "leg_right_6_joint"], kind="str_list", doc="sensor frames")
    compensate_feet = dg.Param(True, kind="bool", doc="add the weight of the body below each sensor")
    height = dg.Param(0.0, kind="float", doc="the ZMP plane's height when plane_height is not plugged or set (m)")
    min_normal_force = dg.Param(10.0, kind="float", minimum=0.0, doc="below it the ZMP is undefined (N)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, sensors: Sequence[str] = ("ft_left_ankle", "ft_right_ankle"),
            frames: Sequence[str] = ("leg_left_6_joint", "leg_right_6_joint"), compensate_feet: bool = True,
            height: float = 0.0, min_normal_force: float = 10.0,
        ) -> None: ...

    robot = dg.Input(dtype=RobotState, doc="a RobotModel's state (measured configuration)")

    def configure(self) -> None:
        """One wrench input per sensor, and the plane's height (default: the ``height`` parameter)."""
        if len(self.sensors) != len(self.frames) or not self.sensors:
            raise dg.ParamError(f"{self.name}: give one frame per sensor", entity=self.name)
        for name in self.sensors:
            if not name.isidentifier() or hasattr(type(self), name) or name == "plane_height":
                raise dg.ParamError(f"{self.name}: {name!r} cannot name an input", entity=self.name)
            self.declare(name, dg.Input(shape=(6,), doc="sensor wrench: [force, torque], sensor frame"))
        self.declare("plane_height", dg.Input(shape=(), default=self.height,
                                              doc="height h of the horizontal plane z = h of the ZMP (m)"))
        self._ids: tuple[object, list[int]] | None = None
        self._bodies: dict[tuple[object, int], tuple[int, np.ndarray, np.ndarray]] = {}

    def setup(self) -> None:
        """Collect the wrench inputs."""
        self._inputs = [getattr(self, name) for name in self.sensors]

    def check(self) -> list[str]:
        """The frames must exist in the plugged robot model."""
        return frame_problems(self.robot, list(self.frames))

    def _frame_ids(self, state: RobotState) -> list[int]:
        if self._ids is None or self._ids[0] is not state.model:
            try:
                self._ids = (state.model, [state.frame_id(f) for f in self.frames])
            except KeyError as exc:
                raise dg.ParamError(f"{self.name}: the robot model has no frame {exc}", entity=self.name) from None
        return self._ids[1]

    def _foot_weight(self, state: RobotState, frame: int) -> np.ndarray:
        """``[m g ẑ, c × m g ẑ]`` of the body carried by the sensor's joint (the joint, its mass
        and its centre of mass in the joint frame looked up once per model and frame)."""
        key = (state.model, frame)
        cached = self._bodies.get(key)
        if cached is None:
            joint = state.model.frames[frame].parentJoint
            inertia = state.model.inertias[joint]
            cached = self._bodies[key] = (joint, inertia.lever.copy(), np.array([0.0, 0.0, inertia.mass * GRAVITY]))
        joint, lever, weight = cached
        return point_force(state.data.oMi[joint].act(lever), weight)

    @dg.output(shape=(6,))
    def wrench(self, t: int) -> np.ndarray:
        """Total wrench of the ground on the robot, world axes, torque about the origin."""
        state: RobotState = self.robot(t)
        total = np.zeros(6)
        for inp, frame in zip(self._inputs, self._frame_ids(state), strict=True):
            placement = state.frame_placement(frame)
            total += world_wrench(placement.translation, placement.rotation, inp(t))
            if self.compensate_feet:
                total += self._foot_weight(state, frame)
        return total

    @dg.output(shape=(), depends=("wrench",))
    def normal_force(self, t: int) -> float:
        """Total vertical contact force (N)."""
        return float(self.wrench(t)[2])

    @dg.output(shape=(3,), depends=("wrench", "robot", "plane_height"), labels=("x", "y", "z"))
    def zmp(self, t: int) -> np.ndarray:
        """The ZMP on the plane ``z = plane_height`` (world)."""
        wrench, height = self.wrench(t), float(self.plane_height(t))
        if wrench[2] >= self.min_normal_force:
            return zero_moment_point(wrench, height)
        state: RobotState = self.robot(t)
        middle = np.mean([state.frame_placement(f).translation for f in self._frame_ids(state)], axis=0)
        return np.array([middle[0], middle[1], height])
