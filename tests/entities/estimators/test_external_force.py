"""ExternalForce: the force beyond TALOS's left wrist sensor in MuJoCo, at rest and under a known push.

Tolerance: the estimate is quasi-static (it neglects the hand's acceleration). Standing in
position mode the whole robot sways slowly; measured over these runs, the hand's inertial force
makes the estimate wander by up to 0.34 N (x) at rest and 0.3 N under the push, once the
transients have died out (0.2 s from the start, 0.3 s after the push, a step that makes the robot
sway). 0.5 N is 4 % of the hand's weight (13.6 N) that the estimate
compensates, and 2.5 % of the 20 N push, so a wrong payload, sign or frame fails it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.estimators import ExternalForce
from dgraph.entities.estimators.external_force import payload_mass
from dgraph.entities.robot import RobotModel, RobotState, load_model
from dgraph.entities.robot.robot_state import DataFields
from sim.device import MujocoDevice

HAND_MASS = 1.384  # URDF mass beyond the wrist sensor (graphs/talos_push_tank.yaml)
PUSH = np.array([12.0, -8.0, 15.0])  # world force on the gripper (up and sideways: the tool stays off the block)
SETTLE, TICKS, PUSH_SETTLE, PUSH_TICKS = 200, 400, 300, 700
TOLERANCE = 0.5


@pytest.fixture(scope="module")
def run():
    """400 ticks at rest, then 700 with PUSH on the gripper: the estimates of every tick."""
    g = dg.Graph(dt=0.001, name="external_force_test")
    dev = g.add(MujocoDevice("sim", scene="push", control_mode="position", wrench_bodies=["gripper_left_base_link"]))
    model = dev.sim.pin_model
    q0 = dev.q.value.copy()
    dev.control.set(q0[7:])
    dev.feedforward_torque.set(pin.rnea(model, model.createData(), q0, np.zeros(model.nv), np.zeros(model.nv))[6:])
    g.add(RobotModel("robot"))
    g.add(ExternalForce("wrist", frame="wrist_left_ft_link", payload_mass=HAND_MASS))
    g.add(ExternalForce("wrist_default", frame="wrist_left_ft_link"))
    for source, target in [("sim.q", "robot.q"), ("sim.v", "robot.v"), ("robot.state", "wrist.robot"),
                           ("robot.state", "wrist_default.robot"), ("sim.ft_left_wrist", "wrist.wrench"),
                           ("sim.ft_left_wrist", "wrist_default.wrench")]:
        g.plug(source, target)
    rows = []
    dev.after.add(lambda t: rows.append([g["wrist"].force(t), g["wrist_default"].force(t)]))
    g.run(ticks=TICKS)
    dev.wrench_gripper_left_base_link.set([*PUSH, 0.0, 0.0, 0.0])
    g.run(ticks=PUSH_TICKS)
    return g, dev, np.array(rows)  # (ticks, [given, default payload], 3)


def test_the_force_is_zero_at_rest_with_the_hand_free(run):
    _, dev, rows = run
    rest = rows[SETTLE:TICKS, 0]
    assert np.abs(rest).max() < TOLERANCE
    assert np.abs(rows[SETTLE:TICKS, 0].mean(axis=0)).max() < 0.2
    m = dev.mj_model
    assert m.body_subtreemass[m.body("wrist_left_ft_link").id] == pytest.approx(HAND_MASS, abs=1e-3)


def test_the_force_is_the_wrench_applied_to_the_gripper(run):
    _, _, rows = run
    pushed = rows[TICKS + PUSH_SETTLE:, 0]
    assert len(pushed) == PUSH_TICKS - PUSH_SETTLE
    assert np.abs(pushed - PUSH).max() < TOLERANCE


def test_default_payload_is_the_subtree_of_the_parent_joint(run):
    g, _, rows = run
    model = load_model("talos")
    joint = model.frames[model.getFrameId("wrist_left_ft_link")].parentJoint
    data = model.createData()
    pin.centerOfMass(model, data, pin.neutral(model))  # data.mass[j]: mass of the subtree of joint j
    assert g["wrist_default"].payload(g.t) == pytest.approx(data.mass[joint], abs=1e-9)
    assert g["wrist"].payload(g.t) == HAND_MASS
    # the reduced model merges arm_left_7_link (before the sensor) into that joint: the default
    # over-compensates by its weight, upwards
    extra = data.mass[joint] - HAND_MASS
    assert extra == pytest.approx(0.3084, abs=1e-3)  # arm_left_7_link: 0.308441 kg
    offset = rows[SETTLE:, 1] - rows[SETTLE:, 0]
    np.testing.assert_allclose(offset, np.tile([0.0, 0.0, 9.81 * extra], (len(offset), 1)), atol=1e-9)
    state = RobotState(model, DataFields(model.createData()), pin.neutral(model), np.zeros(model.nv))
    assert payload_mass(state, model.getFrameId("wrist_left_ft_link")) == pytest.approx(data.mass[joint])
    assert payload_mass(state, model.getFrameId("universe")) == pytest.approx(data.mass[0])


def test_the_force_is_the_rotated_reading_minus_the_weight():
    model = load_model("talos")
    g = dg.Graph(dt=0.001)
    robot = g.add(RobotModel("robot"))
    rng = np.random.default_rng(0)
    q = pin.randomConfiguration(model, np.r_[-np.ones(3), model.lowerPositionLimit[3:]],
                                np.r_[np.ones(3), model.upperPositionLimit[3:]])
    robot.q.set(q)
    robot.v.set(np.zeros(model.nv))
    est = g.add(ExternalForce("est", frame="wrist_left_ft_link", payload_mass=2.0))
    g.plug("robot.state", "est.robot")
    reading = rng.normal(size=6)
    est.wrench.set(reading)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    rotation = data.oMf[model.getFrameId("wrist_left_ft_link")].rotation
    np.testing.assert_allclose(est.force(0), rotation @ reading[:3] + [0.0, 0.0, 2.0 * 9.81], atol=1e-9)
