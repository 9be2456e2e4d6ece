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
from dgraph_sim.device import MujocoDevice

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


class Reading(dg.Entity):
    """A raw wrench as a driver hands it over, one row per tick (NaN included: a constant may not be NaN)."""

    def setup(self):
        self.rows = np.zeros((0, 6))

    @dg.output(shape=(6,), depends=("t",), finite=None)
    def output(self, t):
        return self.rows[t]


def guarded_wrist(rows: np.ndarray, **params) -> tuple[dg.Graph, ExternalForce]:
    """An ExternalForce at half-sitting, its wrench from ``rows``, value checks on."""
    g = dg.Graph(dt=0.001, name="guarded_wrist")
    g.check_values = True
    model = load_model("talos")
    robot = g.add(RobotModel("robot"))
    robot.q.set(model.referenceConfigurations["half_sitting"])
    robot.v.set(np.zeros(model.nv))
    reading = g.add(Reading("sensor"))
    reading.rows = rows
    est = g.add(ExternalForce("wrist", frame="wrist_left_ft_link", payload_mass=2.0, **params))
    g.plug("robot.state", "wrist.robot")
    g.plug("sensor.output", "wrist.wrench")
    return g, est


def run_ticks(g: dg.Graph, est: ExternalForce, ticks: int) -> tuple[np.ndarray, np.ndarray]:
    """The trusted wrench and the force at each tick, read as a controller would, then committed."""
    wrenches, forces = [], []
    for _ in range(ticks):
        wrenches.append(est.checked_wrench(g.t).copy())
        forces.append(est.force(g.t).copy())
        g.step()
    return np.array(wrenches), np.array(forces)


def test_a_bad_wrench_element_is_replaced_by_the_last_good_one_and_reported():
    """NaN, inf and out of range (2 kN m > torque_range 1 kN m), for two ticks: the force stays
    finite, each bad element is the last trusted reading of it, the faults name wrist.wrench[i];
    the tick after, the reading is trusted again as it is."""
    rows = np.arange(1.0, 7.0) + 0.1 * np.arange(6)[:, None]  # every element moves every tick
    rows[2:4, 2] = np.nan
    rows[2:4, 1] = np.inf
    rows[2:4, 4] = 2000.0
    g, est = guarded_wrist(rows)
    wrenches, forces = run_ticks(g, est, 6)
    assert np.isfinite(forces).all()
    expected = rows.copy()
    expected[2:4, [1, 2, 4]] = rows[1, [1, 2, 4]]  # the last trusted value, at both bad ticks
    np.testing.assert_array_equal(wrenches, expected)
    state = g["robot"].state(g.t)
    rotation = state.frame_placement(est.frame_index(state)).rotation
    np.testing.assert_allclose(forces, expected[:, :3] @ rotation.T + [0.0, 0.0, 2.0 * 9.81], atol=1e-9)
    faults = [(f.tick, f.signal, f.cause, f.action) for f in g.fault_log.faults]
    action = "replaced by its prediction"
    assert faults == [(t, f"wrist.wrench[{i}]", cause, action) for t in (2, 3)
                      for i, cause in ((1, "inf"), (2, "NaN"), (4, "out of range"))]
    assert "from sensor.output" in g.fault_log.faults[0].detail
    assert g.fault_log.degraded_ticks == 2


def test_the_ranges_are_parameters_and_the_check_can_be_turned_off():
    rows = np.tile([0.0, 0.0, 600.0, 0.0, 0.0, 0.0], (3, 1)) + 0.1 * np.arange(3)[:, None]
    rows[1, 2] = 700.0  # a real contact jump: never refused for a jump
    rows[2, 2] = 2000.0
    g, est = guarded_wrist(rows, force_range=1000.0)
    wrenches, _ = run_ticks(g, est, 3)
    assert wrenches[1, 2] == 700.0 and wrenches[2, 2] == 700.0
    assert [(f.tick, f.signal, f.cause) for f in g.fault_log.faults] == [(2, "wrist.wrench[2]", "out of range")]
    rows[1, 2] = np.nan
    g, est = guarded_wrist(rows, check_sensors=False)
    with pytest.raises(dg.SpecError, match=r"wrist\.checked_wrench at tick 1: computed a value containing NaN"):
        run_ticks(g, est, 2)


def test_a_frozen_wrench_is_reported_and_kept():
    rows = np.tile(np.arange(1.0, 7.0), (8, 1)) + 0.1 * np.arange(8)[:, None]
    rows[3:] = rows[3]  # the driver stopped at tick 3: the same bits from then on
    g, est = guarded_wrist(rows, frozen_ticks=3)
    wrenches, _ = run_ticks(g, est, 8)
    np.testing.assert_array_equal(wrenches, rows)  # nothing better than the last reading
    frozen = [(f.tick, f.signal) for f in g.fault_log.faults if f.cause == "frozen"]
    assert frozen[0] == (6, "wrist.wrench[0]") and {s for _, s in frozen} == {f"wrist.wrench[{i}]" for i in range(4)}
    g, est = guarded_wrist(rows, frozen_ticks=3)
    g.run(ticks=8)  # nothing reads the force: the reading is checked at every tick all the same
    assert [(f.tick, f.signal) for f in g.fault_log.faults if f.cause == "frozen"] == frozen
