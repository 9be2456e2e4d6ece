"""Scenario 1 of thesis Ch. 6: the Panda drills ten holes in a wall, one breaks through.

``graphs/panda_drill.yaml`` runs once to its end (22 s, the ten holes, the passive QP with the
energy tank); ``graphs/panda_drill_no_tank.yaml`` runs to 13 s (past the breakthrough, 0.25 s
into hole 5's hold: an event of the sequence, not a time); the tank graph with the breakthrough
moved into hole 5's force ramp runs to 12.5 s. The tests assert on what the Recorder kept, and
on the MuJoCo contacts seen after every tick.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.references.drilling import HOLD, RAMP, RELEASE, RETRACT
from dgraph_sim.robots import robot_spec
from dgraph_sim.scenes import DRILL_BREAKTHROUGH, DRILL_HOLES, DRILL_TOOL_TIP, DRILL_WALL_X

pytestmark = pytest.mark.sim

ROOT = Path(__file__).resolve().parents[2]
TARGET = 20.0   # N, the hold force of the graph
CLAMP = 40.0    # N, f_clamp
BREAK_DELAY = 0.25  # s, the graph's sequence.break_delay: the plate goes this long into hole 5's hold
LUNGE_WINDOW = 50   # ticks (50 ms) after the breakthrough over which the tool's displacement is taken


def run(name: str, duration: float | None = None, overrides: dict | None = None) -> dict[str, np.ndarray]:
    graph = dg.load(str(ROOT / "graphs" / f"{name}.yaml"), {"recorder.rerun": "off", **(overrides or {})})
    with graph:
        device = graph["device"]
        m, d = device.mj_model, device.data
        robot = range(device.sim.robot_bodies.start, device.sim.robot_bodies.stop)
        tool = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "tool")
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or "" for g in range(m.ngeom)]
        wall = {g for g, name in enumerate(names) if name.startswith("wall")}
        assert tool >= 0 and len(wall) == 5
        others: list[tuple[int, str, str]] = []  # (tick, robot geom, wall geom) of every contact not the tool's
        tool_ticks: list[int] = []  # ticks with a tool-wall contact

        def contacts(t: int) -> None:
            for g1, g2 in d.contact.geom[:d.ncon]:
                for a, b in ((g1, g2), (g2, g1)):
                    if b in wall and a == tool:
                        tool_ticks.append(t)
                    elif b in wall and m.geom_bodyid[a] in robot:
                        others.append((t, names[a] or str(a), names[b]))

        device.after.add(contacts)
        graph.run(duration=graph.duration if duration is None else duration, progress=False)
        data = graph["recorder"].data()
        data["q0"] = np.asarray(device.q0, dtype=float)
        data["holes"] = np.asarray(graph["sequence"].holes, dtype=float).reshape(-1, 3)
        data["other_wall_contacts"] = others
        data["tool_wall_ticks"] = len(set(tool_ticks))
    return data


@pytest.fixture(scope="module")
def tank():
    return run("panda_drill")


@pytest.fixture(scope="module")
def no_tank():
    return run("panda_drill_no_tank", duration=13.0)


@pytest.fixture(scope="module")
def ramp_break():
    """The tank graph with hole 5's plate giving way 0.15 s into its force ramp (f_n* about 12.5 N)."""
    return run("panda_drill", duration=12.5, overrides={"sequence.break_phase": "ramp", "sequence.break_delay": 0.15})


def removal(data) -> int:
    """The tick at which the plate goes: the first with the sequence's breakthrough event (the
    device moves the plate away before the step from that tick)."""
    assert data["sequence.breakthrough"].any()
    return int(np.argmax(data["sequence.breakthrough"]))


def normal_force(data) -> np.ndarray:
    """The measured force of the wall on the tool along the wall normal (-x), N."""
    return -data["device.contact_force_total"][:, 0]


def lunge(data) -> float:
    """How far (m) the tool tip moved (3-D norm) from where it was at the breakthrough tick, over the
    50 ms after it."""
    tip, k = data["tool_contact.position"], removal(data)
    return float(np.linalg.norm(tip[k:k + LUNGE_WINDOW + 1] - tip[k], axis=1).max())


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
            held = held[held <= removal(tank)]
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


def test_the_slip_clamp_bound_holds_in_the_qp_and_the_measured_force_in_every_hold(tank):
    contact = (tank["sequence.phase"] >= RAMP) & (tank["sequence.phase"] <= RELEASE)
    # the QP's contact force on the tool along the normal (-x), within [f_slip, f_clamp]
    fn = -tank["solver.contact_wrenches"][contact, 0, 0]
    assert fn.min() >= 5.0 - 1e-3 and fn.max() <= CLAMP + 1e-3
    # the measured force (MuJoCo's) during every hold, with the tank: under f_clamp
    held = tank["sequence.phase"] == HOLD
    assert np.unique(tank["sequence.hole"][held]).size == 10
    assert normal_force(tank)[held].max() <= CLAMP


def test_only_the_tool_touches_the_wall(tank, no_tank, ramp_break):
    for data in (tank, no_tank, ramp_break):
        assert data["tool_wall_ticks"] > 1000  # the check sees the contacts
        assert data["other_wall_contacts"] == [], data["other_wall_contacts"][:5]


def test_the_breakthrough_is_seen_and_the_tool_does_not_lunge(tank, no_tank, ramp_break):
    for data, phase, delay in ((tank, HOLD, BREAK_DELAY), (no_tank, HOLD, BREAK_DELAY), (ramp_break, RAMP, 0.15)):
        time, phases, k = data["time"], data["sequence.phase"], removal(data)
        assert phases[k] == phase and data["sequence.hole"][k] == DRILL_BREAKTHROUGH
        # the event is timed from the phase's start, whenever that came (the contact made)
        start = k - int(np.argmax(phases[k::-1] != phase)) + 1
        assert time[k] - time[start] == pytest.approx(delay, abs=1.5e-3)
        assert int(data["sequence.breakthroughs"][-1]) == 1
        assert int(data["sequence.breakthrough_hole"][-1]) == DRILL_BREAKTHROUGH
        retract = k + int(np.argmax(phases[k:] == RETRACT))
        assert time[retract] - time[k] < 0.02  # seen within 20 ms
        assert 0.0 < lunge(data) < 0.01, lunge(data)
    # the hold case: well inside the hold (0.5 s), not at its ends
    assert 0.1 < BREAK_DELAY < 0.5 - 0.1


def test_the_tank_holds_its_bound_and_energy(tank):
    excess = tank["tank.power_bound"] - tank["tank.delivered_power"]
    assert excess.max() < 1e-6
    assert tank["tank.energy"].min() > 0.1
    assert float(tank["tank.correction"][-1]) == 0.0
