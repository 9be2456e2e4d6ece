"""Scenario 1 of thesis Ch. 6: the Panda drills ten holes in a wall, one breaks through.

``graphs/panda_drill.yaml`` runs once to its end (22 s, the ten holes, the passive QP with the
energy tank); ``graphs/panda_drill_no_tank.yaml`` runs to 13 s (past the breakthrough at
12.25 s). The tests assert on what the Recorder kept.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.references.drilling import HOLD, RAMP, RETRACT
from dgraph_sim.robots import robot_spec
from dgraph_sim.scenes import DRILL_BREAKTHROUGH, DRILL_HOLES, DRILL_TOOL_TIP, DRILL_WALL_X

pytestmark = pytest.mark.sim

ROOT = Path(__file__).resolve().parents[2]
TARGET = 20.0   # N, the hold force of the graph
REMOVAL = 12.25  # s, the plate of hole 5 goes


def run(name: str, duration: float | None = None) -> dict[str, np.ndarray]:
    graph = dg.load(str(ROOT / "graphs" / f"{name}.yaml"), {"recorder.rerun": "off"})
    with graph:
        graph.run(duration=graph.duration if duration is None else duration, progress=False)
        data = graph["recorder"].data()
        data["q0"] = np.asarray(graph["device"].q0, dtype=float)
        data["holes"] = np.asarray(graph["sequence"].holes, dtype=float).reshape(-1, 3)
    return data


@pytest.fixture(scope="module")
def tank():
    return run("panda_drill")


@pytest.fixture(scope="module")
def no_tank():
    return run("panda_drill_no_tank", duration=13.0)


def normal_force(data) -> np.ndarray:
    """The measured force of the wall on the tool along the wall normal (-x), N."""
    return -data["device.contact_force_total"][:, 0]


def lunge(data) -> float:
    """How far (m) the tool tip went into the wall's side (+x) beyond where it was just before the
    plate went, in the second after."""
    time, x = data["time"], data["tool_contact.position"][:, 0]
    removal = int(np.argmax(time >= REMOVAL))
    return float(x[removal:removal + 1000].max() - x[removal - 1])


def test_the_graph_uses_the_scene_holes_and_starts_at_the_first_standoff(tank):
    assert np.allclose(tank["holes"], DRILL_HOLES)
    # the tool frame, rebuilt independently of RobotModel
    pin_model = robot_spec("panda")[1].pin_model.copy()
    hand = pin_model.getFrameId("panda_hand")
    frame = pin.Frame("tip", pin_model.frames[hand].parentJoint, hand,
                      pin_model.frames[hand].placement * pin.SE3(np.eye(3), np.array(DRILL_TOOL_TIP)),
                      pin.FrameType.OP_FRAME)
    tip = pin_model.addFrame(frame)
    data = pin_model.createData()
    pin.framesForwardKinematics(pin_model, data, tank["q0"])
    standoff = np.array(DRILL_HOLES[0]) - np.array([0.03, 0.0, 0.0])
    assert np.linalg.norm(data.oMf[tip].translation - standoff) < 1e-3
    # the tool (the frame's x axis: panda_hand's) points at the wall
    tool_axis = data.oMf[tip].rotation[:, 0]
    assert tool_axis @ [1.0, 0.0, 0.0] > 0.999


def test_the_ten_holes_are_drilled_with_the_normal_force_within_10_percent_in_steady_state(tank):
    phase, hole, force = tank["sequence.phase"], tank["sequence.hole"], normal_force(tank)
    assert (tank["solver.status"] == 0).all()
    assert int(tank["sequence.missed"][-1]) == 0
    for k in range(10):
        held = np.flatnonzero((phase == HOLD) & (hole == k))
        if k == DRILL_BREAKTHROUGH:  # the hold is cut short by the breakthrough: its part before
            held = held[tank["time"][held] < REMOVAL]
        assert len(held) > 200, f"hole {k}: held {len(held)} ticks"
        steady = held[len(held) // 2:]
        error = np.abs(force[steady] - TARGET)
        assert error.max() < 0.1 * TARGET, f"hole {k}: {error.max():.2f} N"


def test_every_hole_is_pressed_where_it_is(tank):
    phase, hole, tip = tank["sequence.phase"], tank["sequence.hole"], tank["tool_contact.position"]
    for k in range(10):
        held = np.flatnonzero((phase == HOLD) & (hole == k))
        assert np.abs(tip[held, 0] - DRILL_WALL_X).max() < 2e-3  # on the wall (MuJoCo's soft contact)
        assert np.linalg.norm(tip[held][:, 1:] - DRILL_HOLES[k][1:], axis=1).max() < 5e-3


def test_the_slip_clamp_bound_holds_in_the_qp(tank):
    contact = (tank["sequence.phase"] >= RAMP) & (tank["sequence.phase"] <= HOLD + 1)
    # the QP's contact force on the tool along the normal (-x), within [f_slip, f_clamp]
    fn = -tank["solver.contact_wrenches"][contact, 0, 0]
    assert fn.min() >= 5.0 - 1e-3 and fn.max() <= 40.0 + 1e-3


def test_the_breakthrough_is_seen_and_the_tool_does_not_lunge(tank, no_tank):
    for data in (tank, no_tank):
        time = data["time"]
        removal = int(np.argmax(time >= REMOVAL))
        assert data["sequence.phase"][removal - 1] == HOLD and data["sequence.hole"][removal - 1] == DRILL_BREAKTHROUGH
        assert int(data["sequence.breakthroughs"][-1]) == 1
        assert int(data["sequence.breakthrough_hole"][-1]) == DRILL_BREAKTHROUGH
        retract = removal + int(np.argmax(data["sequence.phase"][removal:] == RETRACT))
        assert time[retract] - REMOVAL < 0.02  # seen within 20 ms
    assert 0.0 < lunge(tank) < 0.01
    assert 0.0 < lunge(no_tank) < 0.01


def test_the_tank_holds_its_bound_and_energy(tank):
    excess = tank["tank.power_bound"] - tank["tank.delivered_power"]
    assert excess.max() < 1e-6
    assert tank["tank.energy"].min() > 0.1
    assert float(tank["tank.correction"][-1]) == 0.0
