"""RobotCamera: the whole robot in the image, whatever the aspect ratio; a still aim for small
motions, followed past its dead zone."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from dgraph_sim.camera import RobotCamera, bounding_box
from dgraph_sim.device import MujocoDevice


@pytest.fixture(scope="module")
def device():
    return MujocoDevice("sim")


def robot_pixels(device: MujocoDevice, camera: RobotCamera, width: int, height: int) -> np.ndarray:
    """A boolean image: where the robot's geoms are seen from ``camera`` (segmentation rendering)."""
    try:
        renderer = mujoco.Renderer(device.mj_model, height, width)
    except Exception as exc:  # only a machine without OpenGL/EGL skips
        pytest.skip(f"offscreen rendering unavailable: {exc}")
    try:
        renderer.enable_segmentation_rendering()
        renderer.update_scene(device.data, camera=camera.update(device.data, width, height))
        ids, types = np.moveaxis(renderer.render(), -1, 0)
    finally:
        renderer.close()
    bodies = device.sim.robot_bodies
    body_of = device.mj_model.geom_bodyid
    geom = (types == int(mujoco.mjtObj.mjOBJ_GEOM)) & (ids >= 0)
    robot = np.zeros_like(geom)
    robot[geom] = (body_of[ids[geom]] >= bodies.start) & (body_of[ids[geom]] < bodies.stop)
    return robot


def extent(mask: np.ndarray) -> tuple[int, int, int, int]:
    """Rows and columns spanned: (top, bottom, left, right), inclusive."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return rows[0], rows[-1], cols[0], cols[-1]


def set_base(device: MujocoDevice, xy: tuple[float, float]) -> None:
    """Put the standing robot's base at ``xy`` (the default configuration otherwise)."""
    q = device.sim.q0.copy()
    q[:2] = xy
    device.joint_map.qpos_from_q(q, device.data.qpos)
    mujoco.mj_forward(device.mj_model, device.data)


@pytest.mark.parametrize(("width", "height"), [(160, 120), (90, 160), (200, 60)])
def test_the_whole_robot_fills_the_image(device, width, height):
    set_base(device, (0.0, 0.0))
    robot = robot_pixels(device, RobotCamera(device.mj_model, device.sim.robot_bodies, device.joint_map.base_body),
                         width, height)
    top, bottom, left, right = extent(robot)
    assert top > 0 and left > 0 and bottom < height - 1 and right < width - 1  # nothing cut at an edge
    assert max((bottom - top + 1) / height, (right - left + 1) / width) > 0.7  # and not a small figure


def test_the_aim_is_still_for_a_sway_and_follows_a_robot_that_leaves(device):
    set_base(device, (0.0, 0.0))
    camera = RobotCamera(device.mj_model, device.sim.robot_bodies, device.joint_map.base_body)
    aim = camera.update(device.data, 160, 120).lookat.copy()
    low, high = bounding_box(device.mj_model, device.data, device.sim.robot_bodies)
    assert np.allclose(aim, (low + high) / 2.0)
    assert camera.radius == pytest.approx(0.15 * (high[2] - low[2]))  # 26 cm for TALOS
    set_base(device, (0.0, 0.05))  # the demo's sway: the camera does not move
    assert np.array_equal(camera.update(device.data, 160, 120).lookat, aim)
    set_base(device, (1.5, -1.0))  # walked away: followed, the base at the edge of the dead zone
    moved = camera.update(device.data, 160, 120).lookat.copy()
    assert np.hypot(*(np.array([1.5, -1.0]) - (moved[:2] - aim[:2]))) == pytest.approx(camera.radius)
    assert moved[2] == aim[2]
    top, bottom, left, right = extent(robot_pixels(device, camera, 160, 120))
    assert top > 0 and left > 0 and bottom < 119 and right < 159
    set_base(device, (0.0, 0.0))
