"""The push files of graphs/push: each is its controller's graph plus a push and nothing else, the
walking pushes fall in the swing of the fourth step and the runs go on long enough to see a late
fall; one small and one large pelvis push on the standing ID solver (the only runs: 5 s each at
most, stopped at a fall)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.files import parse

PUSH = Path(__file__).resolve().parents[2] / "graphs" / "push"
WALKS = {"id": "talos_walk_20cm.yaml", "tank": "talos_walk_20cm_tank.yaml", "mptc": "talos_walk_20cm_mptc.yaml",
         "mptc_sensed": "talos_walk_20cm_mptc_sensed.yaml"}
STANDING = {"id": "talos_standing.yaml", "tank": "talos_standing_tank.yaml", "mptc": "talos_mptc_standing.yaml"}
PUSHED_BODY = {"swing_foot": "leg_right_6_link", "torso_x": "torso_2_link", "torso_y": "torso_2_link",
               "torso_xy": "torso_2_link", "pelvis_standing": "base_link"}
DIRECTION = {"swing_foot": [-1, 0, 0], "torso_x": [1, 0, 0], "torso_y": [0, 1, 0], "torso_xy": [1, 1, 0],
             "pelvis_standing": [1, 0, 0]}
FILES = [(controller, push) for controller in WALKS for push in PUSHED_BODY
         if push != "pelvis_standing" or controller in STANDING]  # sensed flags: walking only


def flat(path: Path) -> dict:
    return parse(path.read_text(), str(path))


def controller_file(controller: str, push: str) -> Path:
    return PUSH.parent / (STANDING if push == "pelvis_standing" else WALKS)[controller]


@pytest.mark.parametrize(("controller", "push"), FILES, ids=[f"{c}_{p}" for c, p in FILES])
def test_a_push_file_is_its_controller_plus_the_push_only(controller, push):
    pushed, base = flat(PUSH / f"{controller}_{push}.yaml"), flat(controller_file(controller, push))
    body = PUSHED_BODY[push]
    pulse = pushed["entities"].pop("push")
    assert pulse["type"] == "Pulse" and pulse["params"]["direction"] == [*map(float, DIRECTION[push]), 0.0, 0.0, 0.0]
    assert pushed["entities"].pop("device")["params"].pop("wrench_bodies") == [body]
    base_device = base["entities"].pop("device")
    pushed["plugs"].remove(f"push.value -> device.wrench_{body}")
    pushed["record"].remove("push.value")
    assert pushed["entities"] == base["entities"] and pushed["plugs"] == base["plugs"]
    assert pushed["record"] == base["record"] and pushed.get("set") == base.get("set")
    assert base_device["params"].get("wrench_bodies") is None


@pytest.mark.parametrize("controller", list(WALKS))
@pytest.mark.parametrize("push", ["swing_foot", "torso_x"])
def test_a_walking_push_is_in_the_right_swing_of_the_fourth_step_and_the_run_lasts_the_walk(controller, push):
    graph = dg.load(PUSH / f"{controller}_{push}.yaml")
    first, end = graph["push"].window
    start, stop = first * graph.dt, end * graph.dt
    plan = graph["footsteps"].plan(0)
    swings = [phase for phase in plan.phases if phase.kind == "single"]
    _, phase, _ = plan.phase_at(start)
    assert phase is swings[3] and phase.swing_side == "right" and len(swings) == 7
    assert start - phase.start == pytest.approx(0.1) and stop == pytest.approx(start + 0.3)
    assert stop < phase.end
    assert plan.phases[-1].end <= graph.duration  # the run lasts the whole walk: late falls come 5 s after


def run_pelvis_push(magnitude: float) -> tuple[float, bool]:
    """The ID solver standing, pushed at the pelvis: the last time reached and whether it fell."""
    graph = dg.load(PUSH / "id_pelvis_standing.yaml", {"push.magnitude": magnitude, "device.stop_on_fall": True,
                                                      "recorder.rerun": "off", "view.rerun": "off"})
    with graph:
        try:
            graph.run(duration=graph.duration, progress=False)
        except dg.DGraphError:
            pass
        data = graph["recorder"].data()
    return float(data["time"][-1]), bool(np.any(data["push.value"][:, 0] == magnitude))


def test_the_standing_id_solver_survives_a_small_pelvis_push_and_falls_under_a_large_one():
    reached, pushed = run_pelvis_push(20.0)
    assert reached > 4.99 and pushed
    reached, pushed = run_pelvis_push(2000.0)
    assert 1.0 < reached < 2.0 and pushed  # fell within 0.7 s of the push's end (1.35 s measured)
