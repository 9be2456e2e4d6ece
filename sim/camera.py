"""A camera that frames the whole robot, whatever its size, and follows it when it walks away.

:class:`RobotCamera` is a MuJoCo free camera (``mjvCamera``): at its first use it measures the
robot's bounding box (every geom of the robot's bodies, at the pose of that moment: standing,
usually) and places itself at ``azimuth`` / ``elevation`` around the box's centre, at the
distance where every geom (the corners of its own bounding box) is in the image, with a
``margin``. The distance
depends on the image's aspect ratio, so it is computed per size.

It then follows the robot's base lazily: its aim stays fixed while the base stays within
``dead_zone`` (a fraction of the box's height) of where it was, horizontally, and moves by
what the base exceeds it. A robot swaying by a few centimetres therefore moves against a still
floor (the motion shows), and a robot that walks or is pushed away stays in frame.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)


def geom_corners(model: mujoco.MjModel, data: mujoco.MjData, bodies: slice) -> np.ndarray:
    """World positions ``(8 n, 3)`` of the corners of the boxes bounding the ``n`` geoms of
    ``bodies`` (a slice of body ids; each geom's own box, ``geom_aabb``, in its frame) at the pose
    in ``data`` (after ``mj_kinematics``)."""
    geoms = np.flatnonzero((model.geom_bodyid >= bodies.start) & (model.geom_bodyid < bodies.stop))
    if not len(geoms):
        raise ValueError("the robot has no geometry to frame")
    aabb = model.geom_aabb[geoms]  # (n, 6): centre, half sizes
    local = aabb[:, None, :3] + aabb[:, None, 3:] * _SIGNS  # (n, 8, 3)
    rotations = data.geom_xmat[geoms].reshape(-1, 3, 3)
    corners = data.geom_xpos[geoms][:, None, :] + np.einsum("nij,nkj->nki", rotations, local)
    return corners.reshape(-1, 3)


def bounding_box(model: mujoco.MjModel, data: mujoco.MjData, bodies: slice) -> tuple[np.ndarray, np.ndarray]:
    """World-aligned bounding box ``(low, high)`` of the geoms of ``bodies`` (see :func:`geom_corners`)."""
    corners = geom_corners(model, data, bodies)
    return corners.min(axis=0), corners.max(axis=0)


class RobotCamera:
    """A free camera framing the robot's bodies ``bodies`` (see the module docstring).

    ``azimuth`` and ``elevation`` are MuJoCo's (degrees; azimuth 180 looks along -x, at the front
    of a robot facing +x; a negative elevation looks down); ``base_body`` is the body followed.
    """

    def __init__(self, model: mujoco.MjModel, bodies: slice, base_body: int, azimuth: float = 150.0,
                 elevation: float = -10.0, margin: float = 1.05, dead_zone: float = 0.15):
        self.model, self.bodies, self.base_body = model, bodies, base_body
        self.azimuth, self.elevation, self.margin, self.dead_zone = azimuth, elevation, margin, dead_zone
        self.centre: np.ndarray | None = None  # the box's centre when measured
        self.corners: np.ndarray | None = None  # the geoms' box corners, relative to the centre
        self.radius = 0.0  # dead zone radius, m
        self._anchor = np.zeros(2)  # base position (x, y) the aim is tied to
        self._start = np.zeros(2)  # the same, when measured
        self._distances: dict[float, float] = {}  # by aspect ratio
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE

    def _measure(self, data: mujoco.MjData) -> None:
        corners = geom_corners(self.model, data, self.bodies)
        low, high = corners.min(axis=0), corners.max(axis=0)
        self.centre = (low + high) / 2.0
        self.corners = corners - self.centre
        self.radius = self.dead_zone * float(high[2] - low[2])
        self._anchor = data.xpos[self.base_body, :2].copy()
        self._start = self._anchor.copy()

    def distance(self, aspect: float) -> float:
        """Distance from the box's centre at which every geom's box corner is in an image of this
        aspect ratio (width / height), with the margin: the nearest that shows the whole robot."""
        if aspect not in self._distances:
            assert self.corners is not None
            az, el = math.radians(self.azimuth), math.radians(self.elevation)
            forward = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
            right = np.cross(forward, [0.0, 0.0, 1.0])
            right /= np.linalg.norm(right)
            up = np.cross(right, forward)
            tan_y = math.tan(math.radians(self.model.vis.global_.fovy) / 2.0) / self.margin
            tan_x = tan_y * aspect
            # a corner at (r, u, f) in the camera's axes, relative to the aim, is at depth d + f:
            # it is in the image if |r| <= (d + f) tan_x and |u| <= (d + f) tan_y
            r, u, f = self.corners @ right, self.corners @ up, self.corners @ forward
            need = np.maximum(np.abs(r) / tan_x, np.abs(u) / tan_y) - f
            self._distances[aspect] = float(need.max())
        return self._distances[aspect]

    def update(self, data: mujoco.MjData, width: int, height: int) -> mujoco.MjvCamera:
        """The camera for an image of ``width x height`` of the state in ``data`` (the box is
        measured at the first call; the aim follows the base past the dead zone)."""
        if self.centre is None:
            self._measure(data)
        assert self.centre is not None
        base = data.xpos[self.base_body, :2]
        offset = base - self._anchor
        gap = float(np.hypot(*offset))
        if gap > self.radius:
            self._anchor += offset * (1.0 - self.radius / gap)
        camera = self.camera
        camera.lookat[:2] = self.centre[:2] + (self._anchor - self._start)
        camera.lookat[2] = self.centre[2]
        camera.distance = self.distance(width / height)
        camera.azimuth, camera.elevation = self.azimuth, self.elevation
        return camera
