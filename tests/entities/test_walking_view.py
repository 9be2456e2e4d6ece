"""WalkingView: footprints, support polygons and ZMP/CoM/DCM points of a walk, read back from the .rrd."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.recording import Recorder, WalkingView
from dgraph.entities.walking import FootstepPlanner, ZmpPatternGenerator
from dgraph.entities.walking.footsteps import FootstepPlan
from tests.conftest import Ticker
from tests.entities.test_robot_view import read_rrd

START = 0.5
"""s: plan time 0 is tick 500."""
TICKS = 3500
"""0.5 s before the plan's start, then 3 s of the 20 cm walk: the initial double support [0, 1),
step 0 (the left foot swings) [1, 1.9), a double support [1.9, 2.015), step 1 [2.015, 2.915)..."""
SINGLE_SUPPORT_TICKS = (2200, 2380, 2520)
DOUBLE_SUPPORT_TICKS = (2420, 2440, 2460, 2480, 2500)
MEASURED_OFFSET = np.array([0.01, -0.02, 0.3])
"""What the stand-in ZMP estimator adds to the planned ZMP (its z must not be drawn)."""


class MeasuredZmp(dg.Entity):
    """A stand-in for a ZmpEstimator: the planned ZMP moved by ``MEASURED_OFFSET``."""

    planned = dg.Input(shape=(3,))

    @dg.output(shape=(3,), depends=("planned",), labels=("x", "y", "z"))
    def zmp(self, t: int) -> np.ndarray:
        return self.planned(t) + MEASURED_OFFSET


def walking_graph(rrd: Path, name: str = "walking_view") -> tuple[dg.Graph, WalkingView]:
    """TALOS's planned 20 cm walk starting at ``START``, its open-loop pattern (CoM estimate held
    over the initial feet), a measured ZMP, all drawn by a walking view into ``rrd``; the
    planned and measured ZMP recorded (``.npz`` next to ``rrd``)."""
    g = dg.Graph(dt=0.001, name=name)
    g.add(Ticker("dev"))
    footsteps = g.add(FootstepPlanner("footsteps", start=START))
    pattern = g.add(ZmpPatternGenerator("pattern", feedback=0.0))
    plan = footsteps.plan(0)
    centre = 0.5 * (plan.sole.center(plan.initial_left) + plan.sole.center(plan.initial_right))
    pattern.estimated_com_position.set([centre[0], centre[1], 0.87])
    pattern.estimated_com_velocity.set(np.zeros(3))
    g.add(MeasuredZmp("zmp"))
    view = g.add(WalkingView("walking", rrd_path=str(rrd)))
    for source, target in (("footsteps.plan", "pattern.plan"), ("pattern.zmp", "zmp.planned"),
                           ("footsteps.plan", "walking.plan"), ("pattern.zmp", "walking.zmp_reference"),
                           ("zmp.zmp", "walking.zmp_measured"), ("pattern.com_position", "walking.com_reference"),
                           ("pattern.dcm", "walking.dcm_reference")):
        g.plug(source, target)
    g.add(Recorder("rec", signals=["pattern.zmp", "zmp.zmp"], rerun="off", npz_path=str(rrd.with_suffix(".npz"))))
    return g, view


@pytest.fixture(scope="module")
def walk(tmp_path_factory) -> tuple[dict[str, list[dict[str, list]]], FootstepPlan, dict[str, np.ndarray]]:
    rrd = tmp_path_factory.mktemp("walking") / "walk.rrd"
    g, _ = walking_graph(rrd)
    g.run(ticks=TICKS)
    g.close()
    return read_rrd(rrd), g["footsteps"].plan(0), dict(np.load(rrd.with_suffix(".npz")))


def over_time(chunks: list[dict[str, list]], column: str) -> dict[int, np.ndarray]:
    """Tick -> the first instance of ``column`` logged at that tick."""
    values = {}
    for c in chunks:
        if "tick" in c:
            values.update({tick: np.array(rows[0]) for tick, rows in zip(c["tick"], c[column], strict=True)})
    return dict(sorted(values.items()))


def inside(point: np.ndarray, strip: np.ndarray, tolerance: float = 1e-9) -> bool:
    """Whether ``point`` (x, y) is in the counter-clockwise closed ``strip``'s polygon."""
    edges, to_point = np.diff(strip[:, :2], axis=0), point[:2] - strip[:-1, :2]
    return bool((edges[:, 0] * to_point[:, 1] - edges[:, 1] * to_point[:, 0] >= -tolerance).all())


def test_every_footprint_is_drawn_once_as_its_sole_outline(walk):
    entities, plan, _ = walk
    placements = {"left": [plan.initial_left], "right": [plan.initial_right]}
    labels = {"left": ["start"], "right": ["start"]}
    for index, step in enumerate(plan.steps):
        placements[step.side].append(step.placement)
        labels[step.side].append(str(index))
    colors = {}
    for side in ("left", "right"):
        (chunk,) = entities[f"/world/walking/footprints/{side}"]
        assert "tick" not in chunk  # static
        strips = np.array(chunk["LineStrips3D:strips"][0])
        assert strips.shape == (len(placements[side]), 5, 3)
        for strip, placement in zip(strips, placements[side], strict=True):
            assert np.abs(strip[:4] - plan.sole.corners(placement)).max() < 1e-6
            assert np.array_equal(strip[4], strip[0])
        assert chunk["LineStrips3D:labels"][0] == labels[side]
        colors[side] = chunk["LineStrips3D:colors"][0]
    assert sum(len(p) for p in placements.values()) == len(plan.steps) + 2 == 9
    assert colors["left"] != colors["right"]


def test_the_support_polygon_follows_the_phases_of_the_plan_time(walk):
    entities, plan, _ = walk
    polygons = over_time(entities["/world/walking/support_polygon"], "LineStrips3D:strips")
    assert list(polygons) == list(range(0, TICKS, 20))
    assert plan.steps[0].side == "left"
    right_sole = plan.sole.corners(plan.initial_right)
    for tick in SINGLE_SUPPORT_TICKS[:2]:  # step 0: the left foot swings, the polygon is the right sole
        assert polygons[tick].shape == (5, 3)
        distances = np.linalg.norm(polygons[tick][:4, None, :2] - right_sole[None, :, :2], axis=2)
        assert distances.min(axis=1).max() < 1e-6 and set(distances.argmin(axis=1)) == {0, 1, 2, 3}
    for tick in DOUBLE_SUPPORT_TICKS:  # the left foot 0.2 m ahead: a hexagon
        assert polygons[tick].shape == (7, 3) and np.array_equal(polygons[tick][0], polygons[tick][-1])
        feet = np.vstack([plan.sole.corners(p) for p in plan.stance_placements(tick * 0.001 - START).values()])
        assert all(inside(corner, polygons[tick]) for corner in feet)  # the hull of both soles
    assert polygons[1000].shape == (5, 3)  # the initial double support: feet side by side, a rectangle
    assert len(polygons[2460]) > len(polygons[2380])


def test_the_planned_and_measured_zmp_are_drawn_on_the_ground_at_their_ticks(walk):
    entities, plan, recorded = walk
    polygons = over_time(entities["/world/walking/support_polygon"], "LineStrips3D:strips")
    planned = over_time(entities["/world/walking/zmp_reference"], "Points3D:positions")
    measured = over_time(entities["/world/walking/zmp_measured"], "Points3D:positions")
    assert list(planned) == list(measured) == list(polygons)
    for tick in (0, 1000, *SINGLE_SUPPORT_TICKS, *DOUBLE_SUPPORT_TICKS):
        ground = np.mean([p[2, 3] for p in plan.stance_placements(tick * 0.001 - START).values()])
        assert abs(ground) < 1e-9  # the planner's sole origins are on z = 0
        assert np.abs(polygons[tick][:, 2]).max() < 2e-4  # the polygon at the corners: TALOS's soles rolled 1.7 mrad
        assert np.abs(planned[tick] - [*recorded["pattern.zmp"][tick][:2], ground]).max() < 1e-6
        assert np.abs(measured[tick] - [*recorded["zmp.zmp"][tick][:2], ground]).max() < 1e-6
        assert np.abs(measured[tick][:2] - planned[tick][:2] - MEASURED_OFFSET[:2]).max() < 1e-6
    for tick in (*SINGLE_SUPPORT_TICKS, *DOUBLE_SUPPORT_TICKS):
        assert inside(planned[tick], polygons[tick]), tick


def test_plugged_points_only_are_drawn(walk):
    entities, _, _ = walk
    assert {"/world/walking/com_reference", "/world/walking/dcm_reference"} <= set(entities)
    assert "/world/walking/com_measured" not in entities
    com = over_time(entities["/world/walking/com_reference"], "Points3D:positions")
    assert com[0][2] == pytest.approx(0.0, abs=1e-9)  # projected: the CoM's 0.87 m is not drawn
    assert com[3480][0] > com[0][0] + 0.1  # the CoM moved forward with the steps


def test_nothing_is_written_when_rerun_is_off(tmp_path):
    g = dg.Graph(dt=0.001, name="walking_off")
    g.add(Ticker("dev"))
    g.add(FootstepPlanner("footsteps"))
    views = [g.add(WalkingView("default")), g.add(WalkingView("off", rerun="off", rrd_path="off.rrd"))]
    for view in views:
        g.plug("footsteps.plan", f"{view.name}.plan")
    g.run(ticks=50)
    g.close()
    assert [view.rerun for view in views] == ["off", "off"] and all(view.stream is None for view in views)
    assert list(tmp_path.rglob("*")) == []  # the test runs in tmp_path


def test_parameters_are_checked():
    with pytest.raises(dg.ParamError, match="path must be an entity path"):
        WalkingView("v", path="world//walking")
    with pytest.raises(dg.ParamError, match="decimation"):
        WalkingView("v", decimation=0)
    assert WalkingView("v", path="/a/b/").path == "a/b"
    assert WalkingView("v", rrd_path="x.rrd").rerun == "save"
    assert WalkingView("v").flush_every == 1000 and WalkingView("v", rerun="spawn").flush_every == 200
