"""Removals (scene bodies that vanish), the push scene's tool and RobotModel's tool frames."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.estimators import ExternalForce
from dgraph.entities.robot import RobotModel
from dgraph_sim.device import MujocoDevice
from dgraph_sim.disturbances import AWAY, Removals
from dgraph_sim.scenes import LEFT_TOOL_TIP, PUSH_BLOCK_TOP, Scene

TOOL = {"left_tool_tip": {"parent": "gripper_left_base_link", "translation": list(LEFT_TOOL_TIP)}}
REMOVAL_TICK = 300


def ball_on_a_mocap_block():
    spec = mujoco.MjSpec()
    scene = Scene(spec)
    scene.box("block", size=(0.4, 0.4, 0.2), pos=(0.0, 0.0, 0.1), mocap=True)
    ball = spec.worldbody.add_body(name="ball", pos=[0.0, 0.0, 0.25])
    ball.add_freejoint()
    ball.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.05, 0.0, 0.0], mass=1.0)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_step(m, d, 1000)  # resting on the block
    return m, d


def test_a_removed_block_no_longer_holds_what_rests_on_it_from_the_removal_step():
    m, d = ball_on_a_mocap_block()
    assert d.qpos[2] == pytest.approx(0.25, abs=2e-3) and d.ncon > 0
    removals = Removals(m, ["block"], [2.0])
    start = d.mocap_pos[0].copy()
    for time in (0.0, 1.0, 1.999):
        removals.apply(d, time)
        np.testing.assert_array_equal(d.mocap_pos[0], start)
    mujoco.mj_step1(m, d)  # the device's sequence: step1 of the last tick, then apply, then step2
    removals.apply(d, 2.0)
    np.testing.assert_array_equal(d.mocap_pos[0], AWAY)
    mujoco.mj_step2(m, d)
    assert d.ncon == 0
    assert d.qacc[2] == pytest.approx(-9.81, abs=1e-6)  # free fall in the very step after the removal
    removals.apply(d, 3.0)  # idempotent
    np.testing.assert_array_equal(d.mocap_pos[0], AWAY)


def push_run():
    """The push scene, the elbow bent so the tool presses on the block, the block removed at 0.3 s."""
    g = dg.Graph(dt=0.001, name="removal_test")
    dev = g.add(MujocoDevice("sim", scene="push", control_mode="position", remove_bodies=["block"],
                             remove_times=[REMOVAL_TICK * 0.001]))
    model = dev.sim.pin_model
    q0 = dev.q.value.copy()
    target = q0[7:].copy()
    target[model.joints[model.getJointId("arm_left_4_joint")].idx_v - 6] += 0.2  # tool tip ~4 cm down
    dev.control.set(target)
    dev.feedforward_torque.set(pin.rnea(model, model.createData(), q0, np.zeros(model.nv), np.zeros(model.nv))[6:])
    g.add(RobotModel("robot"))
    g.add(ExternalForce("wrist", frame="wrist_left_ft_link", payload_mass=1.384))
    for source, target_ in [("sim.q", "robot.q"), ("sim.v", "robot.v"), ("robot.state", "wrist.robot"),
                            ("sim.ft_left_wrist", "wrist.wrench")]:
        g.plug(source, target_)
    m, d = dev.mj_model, dev.data
    block, tool, gripper = m.geom("block").id, m.geom("tool").id, m.body("gripper_left_base_link").id
    log = {}

    def record(t):
        pairs = [{c.geom1, c.geom2} for c in d.contact[:d.ncon]]
        # cfrc_ext: the contact force on the gripper (and its tool) during the step that led to t, world
        log[t] = (any(block in p for p in pairs), {block, tool} in pairs, d.mocap_pos[0].copy(),
                  float(d.cfrc_ext[gripper, 5]), float(g["wrist"].force(t)[2]))

    dev.after.add(record)
    g.run(ticks=REMOVAL_TICK + 50)
    return log


def test_the_block_is_gone_from_its_removal_time_not_before():
    log = push_run()
    start = np.array([0.18, 0.49, PUSH_BLOCK_TOP / 2.0])
    for t, (_, _, mocap, _, _) in log.items():
        np.testing.assert_allclose(mocap, start if t <= REMOVAL_TICK else AWAY, err_msg=str(t))
    # the tool presses on the block until the removal tick...
    assert sum(log[t][1] for t in range(REMOVAL_TICK - 100, REMOVAL_TICK)) >= 90 and log[REMOVAL_TICK][1]
    assert log[REMOVAL_TICK][3] > 10.0  # the block pushes the tool up (N, world z)
    assert log[REMOVAL_TICK][4] == pytest.approx(log[REMOVAL_TICK][3], abs=2.0)  # as the wrist sensor sees it
    # ... and nothing touches it from then on, starting with the step from the removal tick
    assert not any(log[t][0] for t in range(REMOVAL_TICK + 1, REMOVAL_TICK + 51))
    assert all(log[t][3] == 0.0 for t in range(REMOVAL_TICK + 1, REMOVAL_TICK + 51))  # from the step at 0.3 s


@pytest.mark.parametrize(("params", "fragment"), [
    ({"remove_bodies": ["gripper_left_base_link"], "remove_times": [1.0]},
     "cannot remove 'gripper_left_base_link': not a mocap body"),
    ({"remove_bodies": ["nope"], "remove_times": [1.0]}, "cannot remove 'nope': not a mocap body"),
    ({"remove_bodies": ["block"], "remove_times": [1.0, 2.0]}, "1 bodies to remove but 2 removal times"),
    ({"remove_times": [1.0]}, "0 bodies to remove but 1 removal times"),
    ({"scene": "block", "remove_bodies": ["block"], "remove_times": [1.0]}, "'block': not a mocap body"),
])
def test_bad_removals_name_the_device(params, fragment):
    params = {"scene": "push", **params}
    with pytest.raises(dg.ParamError, match=fragment) as info:
        MujocoDevice("sim", **params)
    assert info.value.entity == "sim" and str(info.value).startswith("sim: ")


def test_the_tool_tip_site_is_the_pinocchio_tool_frame_and_the_tool_is_massless():
    dev = MujocoDevice("sim", scene="push")
    m, d = dev.mj_model, dev.data
    robot = RobotModel("robot", tool_frames=TOOL)
    model = robot.pin_model
    data = model.createData()
    pin.framesForwardKinematics(model, data, dev.sim.q0)
    tip = data.oMf[model.getFrameId("left_tool_tip")].translation
    np.testing.assert_allclose(d.site_xpos[m.site("tool_tip").id], tip, atol=1e-5)
    assert tip[2] - PUSH_BLOCK_TOP == pytest.approx(0.022, abs=1e-3)  # 2.2 cm above the block's top
    flat = MujocoDevice("flat_sim", scene="flat")
    base = m.body("base_link").id
    assert m.body_subtreemass[base] == pytest.approx(flat.mj_model.body_subtreemass[base], abs=1e-12)
    tool = m.geom("tool")
    assert tool.contype[0] == 1 and tool.conaffinity[0] == 0  # touches the scene, never the robot
    assert m.geom("tool").bodyid[0] == m.body("gripper_left_base_link").id


@pytest.mark.parametrize(("tool_frames", "fragment"), [
    ({"tip": {"parent": "no_such_link", "translation": [0.0, 0.0, 0.1]}}, "parent 'no_such_link' must be a frame"),
    ({"tip": {"parent": "gripper_left_base_link", "translation": [0.0, 0.1]}}, "translation 3 finite numbers"),
    ({"tip": {"parent": "gripper_left_base_link", "translation": [0.0, float("nan"), 0.1]}},
     "translation 3 finite numbers"),
    ({"base_link": {"parent": "gripper_left_base_link", "translation": [0.0, 0.0, 0.1]}},
     "tool frame 'base_link' must be a new identifier"),
    ({"my tip": {"parent": "gripper_left_base_link", "translation": [0.0, 0.0, 0.1]}},
     "tool frame 'my tip' must be a new identifier"),
    ({"tip": {"parent": "gripper_left_base_link"}}, "needs exactly 'parent' and 'translation'"),
    (["tip"], "tool_frames must map names"),
])
def test_bad_tool_frames_name_the_entity(tool_frames, fragment):
    with pytest.raises(dg.ParamError, match=fragment) as info:
        RobotModel("hands", tool_frames=tool_frames)
    assert info.value.entity == "hands" and str(info.value).startswith("hands: ")


def test_two_tool_frames_and_the_shared_model_is_untouched():
    frames = {"a": {"parent": "gripper_left_base_link", "translation": [0.0, 0.0, -0.2]},
              "b": {"parent": "a", "translation": [0.1, 0.0, 0.0]}}  # a tool frame on a tool frame
    robot = RobotModel("robot", tool_frames=frames)
    plain = RobotModel("plain")
    assert robot.pin_model.existFrame("b") and not plain.pin_model.existFrame("a")
    model = robot.pin_model
    data = model.createData()
    q = model.referenceConfigurations["half_sitting"]
    pin.framesForwardKinematics(model, data, q)
    gripper = data.oMf[model.getFrameId("gripper_left_base_link")]
    np.testing.assert_allclose(data.oMf[model.getFrameId("b")].translation, gripper.act(np.array([0.1, 0.0, -0.2])),
                               atol=1e-12)


def test_a_triggered_removal_happens_when_its_flag_fires_and_stays():
    m, d = ball_on_a_mocap_block()
    removals = Removals(m, [], [], triggered=["block"])
    start = d.mocap_pos[0].copy()
    removals.apply(d, 5.0, [False])
    np.testing.assert_array_equal(d.mocap_pos[0], start)
    removals.apply(d, 5.0, [True])
    np.testing.assert_array_equal(d.mocap_pos[0], AWAY)
    removals.apply(d, 6.0, [False])  # latched: nothing brings it back
    np.testing.assert_array_equal(d.mocap_pos[0], AWAY)
    with pytest.raises(ValueError, match="not a mocap body"):
        Removals(m, [], [], triggered=["ball"])
