"""A fault campaign on standing TALOS: every sensor signal the controller reads gets NaN, inf, a
frozen value and a jump, for one tick and for 100 ticks, with value checks on and off.

Per sensor and setting, one run of ``graphs/talos_standing.yaml`` with the eight faults in
sequence (a :class:`dgraph_sim.faults.SensorFault` between the device and the estimator, each window
0.4 s after the last). What must hold: the loop never stops; MuJoCo never receives a non-finite
torque (the device never had to replace one either); TALOS stays up, its base height within 2 cm
of standing (6 cm for the accelerometer: its 100-tick offset of 50 m/s2 is in range and is not
tested for jumps, since impacts are real spikes, so the filter integrates it); the first tick of
every NaN, inf or caught jump names ``estimator.<sensor>`` in the graph's fault log; a frozen
reading is named within ``frozen_ticks`` (50) ticks, except a frozen encoder position: the knee
of standing TALOS is at rest (its velocity moves it by less than ``encoder_step`` over
``frozen_ticks``), where a repeated value is what a joint at rest reads, so it is not reported
(and what the guard hands over is where the joint is); and once a window ends the sensor is trusted
again within a few ticks (the next tick proceeds with fresh data).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph_sim.faults import SensorFault

ROOT = Path(__file__).resolve().parents[2]
START, SPACING = 0.3, 0.4
FAULTS = [(kind, ticks) for kind in ("nan", "inf", "frozen", "jump") for ticks in (1, 100)]
SENSORS = {  # the jump of each (a glitch a real sensor can produce), and whether the guard tests jumps
    "imu_orientation": (0.5, True), "imu_angular_velocity": (5.0, True), "imu_linear_acceleration": (50.0, False),
    "encoder_position": (0.5, True), "encoder_velocity": (10.0, True), "ft_left_ankle": (500.0, False),
    "ft_right_ankle": (500.0, False)}
ELEMENT = {"encoder_position": 3, "encoder_velocity": 3}  # the left knee; element 0 elsewhere
AT_REST = {"encoder_position"}  # a position whose rate is too small for a frozen reading to be told from rest


def standing_with_faults(sensor: str) -> tuple[dg.Graph, list[tuple[str, int, int]]]:
    """The standing graph with the campaign's faults in series on ``sensor``; the plan
    ``(kind, ticks, first tick)``."""
    graph = dg.load(str(ROOT / "graphs" / "talos_standing.yaml"), {"recorder.rerun": "off", "view.rerun": "off"})
    magnitude = SENSORS[sensor][0]
    source = graph[f"estimator.{sensor}"].source
    graph.unplug(f"estimator.{sensor}")
    plan = []
    for i, (kind, ticks) in enumerate(FAULTS):
        start = START + SPACING * i
        fault = graph.add(SensorFault(f"fault{i}", kind=kind, start=start, ticks=ticks, magnitude=magnitude,
                                      indices=[ELEMENT.get(sensor, 0)]))
        graph.plug(source, fault.reading)
        source = fault.output
        plan.append((kind, ticks, round(start / graph.dt)))
    graph.plug(source, f"estimator.{sensor}")
    return graph, plan


def run_watched(graph: dg.Graph, duration: float, check_values: bool) -> dict:
    """Run ``graph`` for ``duration`` s, watching after each step what MuJoCo was given
    (``ctrl_finite``), whether the device had to replace a torque (``control_fault``) and the
    base height (``heights``)."""
    graph.check_values = check_values
    device = graph["device"]
    seen = {"ctrl_finite": True, "heights": [], "control_fault": 0}

    def watch(t: int) -> None:
        seen["ctrl_finite"] &= bool(np.isfinite(device.data.ctrl).all())
        seen["heights"].append(float(device.q.value[2]))
        seen["control_fault"] = max(seen["control_fault"], int(device.control_fault.value))

    device.after.add(watch)
    with graph:
        graph.run(duration=duration, progress=False)
    return seen


def run_campaign(sensor: str, check_values: bool) -> tuple[dg.Graph, list[tuple[str, int, int]], dict]:
    graph, plan = standing_with_faults(sensor)
    return graph, plan, run_watched(graph, START + SPACING * len(FAULTS), check_values)


def assert_safe_and_standing(graph: dg.Graph, seen: dict, duration: float, bound: float = 0.02) -> None:
    """The loop ran to the end, MuJoCo never got a non-finite torque (none was even replaced),
    TALOS did not fall and its base height stayed within ``bound`` of where it started."""
    assert graph.t == round(duration / graph.dt)  # the loop never stopped
    assert seen["ctrl_finite"] and seen["control_fault"] == 0
    heights = np.array(seen["heights"])
    assert not graph["device"].fallen.value and np.abs(heights - heights[0]).max() < bound, \
        f"base height moved by {np.abs(heights - heights[0]).max():.3f} m"


@pytest.mark.parametrize("check_values", [False, True], ids=["checks-off", "checks-on"])
@pytest.mark.parametrize("sensor", list(SENSORS))
def test_standing_talos_survives_every_fault_of_every_sensor(sensor, check_values):
    graph, plan, seen = run_campaign(sensor, check_values)
    assert_safe_and_standing(graph, seen, START + SPACING * len(FAULTS),
                             0.06 if sensor == "imu_linear_acceleration" else 0.02)
    name = f"estimator.{sensor}"
    faults = [f for f in graph.fault_log.faults if f.signal.startswith(name)]
    for kind, ticks, first in plan:
        at_first = [f for f in faults if f.tick == first]
        if kind in ("nan", "inf") or (kind == "jump" and SENSORS[sensor][1]):
            assert at_first, f"{kind} at tick {first}: no fault names {name}"
            expected = {"nan": "NaN", "inf": "inf", "jump": "jump"}[kind]
            assert at_first[0].cause in (expected, "not a unit quaternion"), at_first[0]
        if kind == "frozen" and ticks == 100:
            frozen = [f for f in faults if first <= f.tick < first + ticks and f.cause == "frozen"]
            if sensor in AT_REST:
                assert not frozen, f"a joint at rest taken for frozen: {frozen[0]}"
            else:
                assert frozen and frozen[0].tick <= first + 50, f"frozen from tick {first}: {frozen[:1]}"
        late = [f for f in faults if first + ticks + 5 <= f.tick < first + round(SPACING / graph.dt)]
        assert not late, f"{kind} over [{first}, {first + ticks}): still replaced after: {late[0]}"



WHOLE_START, WHOLE_TICKS, WHOLE_DURATION = 0.3, 100, 0.8


@pytest.mark.parametrize("sensor", ["encoder_position", "imu_orientation"])
def test_a_whole_sensor_vector_nan_for_100_ticks_does_not_make_talos_fall(sensor):
    """Every element of the reading NaN for 100 ticks (``indices`` empty), value checks on: the
    guard holds its prediction the whole window (the encoders move on with their velocities, the
    orientation is held), every tick of the window names the sensor, and 5 ticks after it the
    reading is trusted again."""
    graph = dg.load(str(ROOT / "graphs" / "talos_standing.yaml"), {"recorder.rerun": "off", "view.rerun": "off"})
    fault = graph.add(SensorFault("fault", kind="nan", start=WHOLE_START, ticks=WHOLE_TICKS))
    graph.plug(graph[f"estimator.{sensor}"].source, fault.reading)
    graph.plug(fault.output, f"estimator.{sensor}")
    seen = run_watched(graph, WHOLE_DURATION, check_values=True)
    assert_safe_and_standing(graph, seen, WHOLE_DURATION)
    first = round(WHOLE_START / graph.dt)
    name = f"estimator.{sensor}"
    named = {f.tick for f in graph.fault_log.faults if f.signal.startswith(name) and f.cause == "NaN"}
    assert named == set(range(first, first + WHOLE_TICKS))
    late = [f for f in graph.fault_log.faults if f.tick >= first + WHOLE_TICKS + 5 or f.tick < first]
    assert not late, late[0]


PUSH_FAULTS = (("nan", 2.0), ("inf", 2.1))  # s: the tool presses on the block from about 1.75 s
PUSH_DURATION = 2.3


@pytest.mark.parametrize("check_values", [False, True], ids=["checks-off", "checks-on"])
def test_a_bad_wrist_wrench_in_contact_costs_the_push_one_degraded_tick(check_values):
    """The push-tank graph with the tool on the block: the left wrist wrench (read by wrist_force,
    an ExternalForce, not the estimator) all NaN for one tick, then all inf for one tick. Before
    wrist_force guarded it, the force task's integral (checks off) or wrist_force.force (checks on)
    went NaN and every retry failed. Now each costs one degraded tick naming wrist_force.wrench,
    the force of that tick is the last trusted one, the contact is kept and TALOS stays up."""
    graph = dg.load(str(ROOT / "graphs" / "talos_push_tank.yaml"), {"recorder.rerun": "off", "view.rerun": "off"})
    source = graph["wrist_force.wrench"].source
    graph.unplug("wrist_force.wrench")
    ticks = []
    for i, (kind, start) in enumerate(PUSH_FAULTS):
        fault = graph.add(SensorFault(f"fault{i}", kind=kind, start=start, ticks=1))
        graph.plug(source, fault.reading)
        source = fault.output
        ticks.append(round(start / graph.dt))
    graph.plug(source, "wrist_force.wrench")
    wrist, detector = graph["wrist_force"], graph["detector"]
    trusted, phases = {}, {}
    keep = {t + d for t in ticks for d in (-1, 0)}
    graph["device"].before.add(
        lambda t: trusted.update({t: wrist.checked_wrench(t).copy()}) if t in keep else None)
    graph["device"].after.add(lambda t: phases.update({t: int(detector.phase.value)}))
    seen = run_watched(graph, PUSH_DURATION, check_values)
    assert_safe_and_standing(graph, seen, PUSH_DURATION)
    assert all(phases[t] == 1 for t in range(ticks[0] - 200, graph.t + 1))  # in contact throughout
    faults = graph.fault_log.faults
    assert {f.tick for f in faults} == set(ticks) and graph.fault_log.degraded_ticks == len(ticks)
    for (kind, _), tick in zip(PUSH_FAULTS, ticks, strict=True):
        at = [f for f in faults if f.tick == tick]
        assert at[0].signal == "wrist_force.wrench[0]" and at[0].cause == {"nan": "NaN", "inf": "inf"}[kind], at[0]
        assert all(f.signal.startswith("wrist_force.") for f in at)
        np.testing.assert_array_equal(trusted[tick], trusted[tick - 1])  # held at its last trusted value


def test_without_the_guard_a_nan_encoder_costs_one_fallback_tick():
    """``check_sensors`` off and value checks off: the NaN reaches the solver, which falls back on
    the last finite state (a finite torque), and the next tick is normal again."""
    graph = dg.load(str(ROOT / "graphs" / "talos_standing.yaml"),
                    {"recorder.rerun": "off", "view.rerun": "off", "estimator.check_sensors": False})
    fault = graph.add(SensorFault("fault", kind="nan", start=0.3, ticks=1, indices=[3]))
    graph.plug(graph["estimator.encoder_position"].source, fault.reading)
    graph.plug(fault.output, "estimator.encoder_position")
    torques, states = {}, {}
    keep = {299, 300, 301}

    def capture(t: int) -> None:
        if t == 299:  # the last state the QP is solved on
            state = graph["robot"].state(t)
            states[t] = (state.model, state.q.copy(), state.v.copy())
        if t in keep:
            torques[t] = graph["solver"].tau(t).copy()

    graph["device"].before.add(capture)
    with graph:
        graph.run(duration=1.0, progress=False)
    assert all(np.isfinite(tau).all() for tau in torques.values()) and len(torques) == 3
    [fault] = [f for f in graph.fault_log.faults if f.signal == "solver.tau"]
    assert (fault.tick, fault.cause) == (300, "solve failed: NOT_FINITE")
    assert fault.action == "fallback torque g(q) - d v on the last finite state"
    model, q, v = states[299]
    limit = model.effortLimit[6:]
    gravity = pin.computeGeneralizedGravity(model, model.createData(), q)[6:]
    expected = np.clip(gravity - graph["solver"].fallback_damping * v[6:], -limit, limit)
    np.testing.assert_allclose(torques[300], expected, rtol=0.0, atol=1e-9)
    assert np.abs(expected).max() > 5.0  # gravity compensation (N m), which zero torque would not match
    assert graph.fault_log.degraded_ticks == 1 and not graph["device"].fallen.value
    assert np.abs(torques[301] - torques[299]).max() < 5.0  # back to the QP's torque, not the fallback


FAULTY_STANDING = """\
extends: {base}
name: faulty_standing
entities:
  glitch: {{type: SensorFault, params: {{kind: inf, start: 0.2, ticks: 1, indices: [3]}}}}
remove:
  plugs: [device.encoder_position -> estimator.encoder_position]
plugs:
  - device.encoder_position -> glitch.reading
  - glitch.output -> estimator.encoder_position
"""


def test_a_graph_file_with_a_glitch_runs_and_reports_its_degraded_tick(tmp_path):
    """From a graph file, through the CLI: the run completes, its summary counts the degraded
    tick and names the encoder, and the .npz carries the fault."""
    graph_file = tmp_path / "faulty.yaml"
    graph_file.write_text(FAULTY_STANDING.format(base=ROOT / "graphs" / "talos_standing.yaml"))
    npz = tmp_path / "faulty.npz"
    result = subprocess.run([str(Path(sys.executable).parent / "dgraph"), "run", str(graph_file), "--duration", "0.5",
                             "--no-rerun", "--npz", str(npz), "-q"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "degraded ticks: 1 of 500 (first: tick 200: estimator.encoder_position[3]: inf" in result.stdout, \
        result.stdout
    data = np.load(npz)
    assert data["fault_tick"].tolist() == [200] and data["fault_signal"].tolist() == ["estimator.encoder_position[3]"]
    assert data["degraded"].sum() == 1 and data["tick"][data["degraded"]].tolist() == [200]


def test_the_position_scheme_reads_the_guarded_ankle_wrenches():
    """The TSID-position graph's ZMP estimator reads the estimator's checked wrenches: a NaN on
    an ankle sensor costs one degraded tick there too, value checks on."""
    graph = dg.load(str(ROOT / "graphs" / "talos_tsid_position.yaml"), {"recorder.rerun": "off"})
    graph.check_values = True
    fault = graph.add(SensorFault("fault", kind="nan", start=0.3, ticks=1))
    graph.unplug("estimator.ft_left_ankle")
    graph.plug("device.ft_left_ankle", fault.reading)
    graph.plug(fault.output, "estimator.ft_left_ankle")
    with graph:
        graph.run(duration=0.8, progress=False)
    assert graph.t == 800 and not graph["device"].fallen.value
    assert graph.fault_log.degraded_ticks == 1
    assert {f.signal for f in graph.fault_log.faults} == {f"estimator.ft_left_ankle[{i}]" for i in range(4)} | \
        {"estimator.sensors"}
