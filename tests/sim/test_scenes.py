"""Scenes: floor, blocks, stairs and tilted platforms on a bare MjSpec (no robot: fast)."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from dgraph_sim.scenes import SCENES, Scene, add_scene


def test_a_free_block_falls_and_rests_on_the_floor():
    spec = mujoco.MjSpec()
    scene = Scene(spec)
    scene.floor(friction=1.0)
    scene.box("block", size=(0.2, 0.3, 0.4), pos=(0.0, 0.0, 0.5), free=True, mass=5.0)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_step(m, d, 2000)
    assert m.body("block").mass[0] == pytest.approx(5.0)
    assert d.qpos[2] == pytest.approx(0.2, abs=2e-3)  # half its height, resting
    assert np.abs(d.qvel).max() < 1e-2


def test_stairs_and_platform_geometry():
    spec = mujoco.MjSpec()
    scene = Scene(spec)
    scene.floor()
    scene.stairs(steps=3, rise=0.1, run=0.3, start=(1.0, 0.0), width=0.8)
    scene.platform("ramp", size=(1.0, 1.0, 0.05), pos=(3.0, 0.0, 0.1), roll=0.0, pitch=0.2)
    scene.platform("tilted", size=(1.0, 1.0, 0.05), pos=(6.0, 0.0, 0.1), roll=0.1, pitch=-0.3)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    for k in (1, 2, 3):
        geom = m.geom(f"step_{k}")
        top = d.geom_xpos[geom.id][2] + geom.size[2]
        front = d.geom_xpos[geom.id][0] - geom.size[0]
        assert top == pytest.approx(0.1 * k) and front == pytest.approx(1.0 + 0.3 * (k - 1))
        assert geom.size[1] == pytest.approx(0.4)
    ramp = d.geom_xmat[m.geom("ramp").id].reshape(3, 3)
    assert np.arccos(ramp[2, 2]) == pytest.approx(0.2)  # its normal is tilted by the pitch
    tilted = d.geom_xmat[m.geom("tilted").id].reshape(3, 3)
    assert np.allclose(tilted, pin.rpy.rpyToMatrix(0.1, -0.3, 0.0), atol=1e-12)  # Rz Ry Rx, signs included


def test_named_scenes_compile_with_light_and_camera():
    for name in SCENES:
        spec = mujoco.MjSpec()
        spec.worldbody.add_body(name="base").add_geom(size=[0.1, 0, 0])
        spec.worldbody.add_body(name="gripper_left_base_link")  # the push scene's tool hangs on TALOS's gripper
        spec.worldbody.add_body(name="panda_hand")  # the drill scene's on the Panda's hand
        add_scene(spec, name, tracked_body="base")
        m = spec.compile()
        assert m.nlight == 1 and m.ncam == 2 and m.geom("floor").id >= 0  # side and front cameras
    with pytest.raises(ValueError, match="unknown scene"):
        add_scene(mujoco.MjSpec(), "moon")
    with pytest.raises(ValueError, match="needs the robot body 'gripper_left_base_link'"):
        add_scene(mujoco.MjSpec(), "push")


def test_a_wall_with_a_window_is_four_boxes_around_a_removable_plate():
    spec = mujoco.MjSpec()
    Scene(spec).wall("wall", 0.65, center=(0.0, 0.45), size=(0.8, 0.5), thickness=0.02, window=(0.02, 0.45, 0.03))
    m = spec.compile()
    plate = m.body("wall_plate")
    assert m.body_mocapid[plate.id] == 0 and np.allclose(plate.pos, [0.66, 0.02, 0.45])
    boxes = [m.geom(n) for n in ("wall_left", "wall_right", "wall_bottom", "wall_top", "wall_plate")]
    # the front faces at x = 0.65; the boxes and the plate tile the 0.8 x 0.5 m wall
    assert all(np.isclose(m.geom_pos[g.id][0] if g.name != "wall_plate" else 0.66, 0.66) for g in boxes)
    area = sum(4 * m.geom_size[g.id][1] * m.geom_size[g.id][2] for g in boxes)
    assert np.isclose(area, 0.8 * 0.5)
    with pytest.raises(ValueError, match="not inside the wall"):
        Scene(mujoco.MjSpec()).wall("w", 0.65, center=(0.0, 0.45), size=(0.8, 0.5), window=(0.39, 0.45, 0.03))
