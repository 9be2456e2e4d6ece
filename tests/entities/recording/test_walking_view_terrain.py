"""WalkingView on a terrain (issue 14, item 3): the terrain's boxes, logged once as the MuJoCo scene
builds them, and the footprints and support polygons at the soles' heights and tilts on stairs,
tilted platforms and the obstacles' boards, read back from the .rrd."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.recording import WalkingView
from dgraph.entities.walking.footsteps import FootstepPlan, terrain_walk, yaw_placement
from dgraph.entities.walking.terrain import TERRAINS, Terrain, stairs, tilted_platforms
from tests.conftest import Ticker
from tests.entities.test_robot_view import read_rrd
from tests.entities.test_walking_view import over_time

LEFT0 = yaw_placement([-0.009, 0.085, 0.0])
RIGHT0 = yaw_placement([-0.009, -0.085, 0.0])
"""TALOS's soles at half-sitting, where the terrains expect the robot."""
FLOAT32 = 1e-6
"""What Rerun stores positions and quaternions in: float32, about 1e-7 relative."""
TICKS = 3600
"""The initial double support [0, 1) s, step 0 (left) [1, 1.9), a double support [1.9, 2.015),
step 1 (right) [2.015, 2.915), a double support [2.915, 3.03), step 2 (left) [3.03, 3.93)."""


def stairs_plan() -> tuple[Terrain, FootstepPlan]:
    """Up the stairs with 0.30 m strides: footstep k on tread k + 1 (0.1 (k + 1) m high)."""
    terrain = stairs()
    return terrain, terrain_walk(terrain, LEFT0, RIGHT0, steps=6, length=0.30)


def platforms_plan() -> tuple[Terrain, FootstepPlan]:
    """Over the tilted platforms: flat_1, then the right foot on tilted_2, the left on tilted_3."""
    terrain = tilted_platforms()
    return terrain, terrain_walk(terrain, LEFT0, RIGHT0, steps=4, length=0.30, width=0.28)


def record(rrd: Path, terrain: Terrain, plan: FootstepPlan, ticks: int = TICKS) -> dict[str, list[dict[str, list]]]:
    """A walking view drawing ``plan`` on ``terrain`` for ``ticks`` ticks, its recording read back."""
    g = dg.Graph(dt=0.001, name=rrd.stem)
    g.add(Ticker("dev"))
    view = g.add(WalkingView("walking", rrd_path=str(rrd)))
    view.plan.set(plan)
    view.terrain.set(terrain)
    view.zmp_reference.set([0.0, 0.0, 5.0])  # drawn at the stance soles' mean height, not at 5 m
    g.run(ticks=ticks)
    g.close()
    return read_rrd(rrd)


@pytest.fixture(scope="module")
def on_stairs(tmp_path_factory) -> tuple[dict[str, list[dict[str, list]]], Terrain, FootstepPlan]:
    terrain, plan = stairs_plan()
    return record(tmp_path_factory.mktemp("stairs") / "stairs.rrd", terrain, plan), terrain, plan


@pytest.fixture(scope="module")
def on_platforms(tmp_path_factory) -> tuple[dict[str, list[dict[str, list]]], Terrain, FootstepPlan]:
    terrain, plan = platforms_plan()
    return record(tmp_path_factory.mktemp("platforms") / "platforms.rrd", terrain, plan), terrain, plan


def quaternion_rotation(xyzw: list[float]) -> np.ndarray:
    x, y, z, w = xyzw
    return pin.Quaternion(w, x, y, z).normalized().matrix()


@pytest.mark.parametrize("fixture", ["on_stairs", "on_platforms"])
def test_the_terrain_is_logged_once_static_as_its_boxes(fixture, request):
    entities, terrain, _ = request.getfixturevalue(fixture)
    (chunk,) = entities["/world/walking/terrain"]
    assert "tick" not in chunk  # static
    assert chunk["Boxes3D:labels"] == [[surface.name for surface in terrain.surfaces]]  # one row: logged once
    centres, half_sizes = np.array(chunk["Boxes3D:centers"][0]), np.array(chunk["Boxes3D:half_sizes"][0])
    quaternions = chunk["Boxes3D:quaternions"][0]
    assert len(centres) == len(half_sizes) == len(quaternions) == len(terrain.surfaces) == 6
    for k, surface in enumerate(terrain.surfaces):
        centre, half_size, _ = surface.box()
        np.testing.assert_allclose(centres[k], centre, atol=FLOAT32)
        np.testing.assert_allclose(half_sizes[k], half_size, atol=FLOAT32)
        np.testing.assert_allclose(quaternion_rotation(quaternions[k]), surface.placement[:3, :3], atol=FLOAT32)
    colors = chunk["Boxes3D:colors"][0]
    assert colors[0] != colors[1] and colors[0] == colors[2]
    assert not any("floor" in path for path in entities)


def test_the_boxes_of_the_stairs_are_its_treads_down_to_the_floor(on_stairs):
    entities, _, _ = on_stairs
    (chunk,) = entities["/world/walking/terrain"]
    centres, half_sizes = np.array(chunk["Boxes3D:centers"][0]), np.array(chunk["Boxes3D:half_sizes"][0])
    np.testing.assert_allclose(centres[:, 2] + half_sizes[:, 2], [0.1, 0.2, 0.3, 0.4, 0.5, 0.6], atol=FLOAT32)
    np.testing.assert_allclose(centres[:, 2] - half_sizes[:, 2], 0.0, atol=FLOAT32)
    np.testing.assert_allclose(centres[:5, 0] - half_sizes[:5, 0], 0.15 + 0.30 * np.arange(5), atol=FLOAT32)


def test_footprints_on_a_tread_sit_on_the_tread(on_stairs):
    entities, terrain, plan = on_stairs
    strips = {side: np.array(entities[f"/world/walking/footprints/{side}"][0]["LineStrips3D:strips"][0])
              for side in ("left", "right")}
    counts = {"left": 1, "right": 1}  # after the initial footprint
    treads = []
    for step in plan.steps:
        strip = strips[step.side][counts[step.side]]
        counts[step.side] += 1
        centre = plan.sole.center(step.placement)
        tread = terrain.surface_under(centre[0], centre[1])
        treads.append(tread.name)
        np.testing.assert_allclose(strip[:, 2], tread.center[2], atol=FLOAT32)
    assert treads == ["step_1", "step_2", "step_3", "step_4", "step_5", "landing", "landing"]
    np.testing.assert_allclose(strips["left"][0][:, 2], 0.0, atol=FLOAT32)  # the initial feet on the floor


def test_the_support_polygon_on_the_stairs_is_at_the_stance_treads_heights(on_stairs):
    entities, _, _ = on_stairs
    polygons = over_time(entities["/world/walking/support_polygon"], "LineStrips3D:strips")
    zmp = over_time(entities["/world/walking/zmp_reference"], "Points3D:positions")
    np.testing.assert_allclose(polygons[1500][:, 2], 0.0, atol=FLOAT32)  # step 0: the right foot on the floor
    np.testing.assert_allclose(polygons[2500][:, 2], 0.1, atol=FLOAT32)  # step 1: the left foot on step_1
    assert polygons[2500].shape == (5, 3)
    for tick, low, high in ((1960, 0.0, 0.1), (2960, 0.1, 0.2)):  # double supports across two treads
        heights = polygons[tick][:, 2]
        assert np.all((np.abs(heights - low) < FLOAT32) | (np.abs(heights - high) < FLOAT32))
        assert heights.min() == pytest.approx(low, abs=FLOAT32) and heights.max() == pytest.approx(high, abs=FLOAT32)
        assert zmp[tick][2] == pytest.approx(0.5 * (low + high), abs=FLOAT32)  # the stance origins' mean height
    assert zmp[2500][2] == pytest.approx(0.1, abs=FLOAT32)


def test_the_support_polygon_on_a_tilted_pad_is_the_tilted_sole(on_platforms):
    entities, terrain, plan = on_platforms
    polygons = over_time(entities["/world/walking/support_polygon"], "LineStrips3D:strips")
    stance = plan.steps[1]  # the right foot on tilted_2 while the left one swings (step 2)
    (placement,) = plan.stance_placements(3.5).values()
    assert stance.side == "right" and np.array_equal(placement, stance.placement)
    corners = plan.sole.corners(stance.placement)
    polygon = polygons[3500][:-1]
    assert polygon.shape == (4, 3)
    distances = np.linalg.norm(polygon[:, None, :] - corners[None, :, :], axis=2)
    assert distances.min(axis=1).max() < FLOAT32 and set(distances.argmin(axis=1)) == {0, 1, 2, 3}
    pad = terrain.surface("tilted_2")
    np.testing.assert_allclose((polygon - pad.center) @ pad.normal, 0.0, atol=FLOAT32)  # on the pad's plane
    assert np.ptp(polygon[:, 2]) > 0.05  # tilted by 15 degrees along the sole's 0.21 m


def test_the_obstacles_are_drawn_as_their_boards_and_the_footprints_on_them(tmp_path):
    """The 20 cm walk over the obstacles: three boxes, 0.25 x 0.16 m, 1, 2 and 1 cm high, in the
    right, left and right lanes (y = -+0.085) under footsteps 1-3; the footprints at those heights."""
    terrain = TERRAINS["obstacles"]()
    plan = terrain_walk(terrain, LEFT0, RIGHT0, steps=6, length=0.2)
    entities = record(tmp_path / "obstacles.rrd", terrain, plan, ticks=100)
    (chunk,) = entities["/world/walking/terrain"]
    assert chunk["Boxes3D:labels"] == [["obstacle_1", "obstacle_2", "obstacle_3"]]
    np.testing.assert_allclose(chunk["Boxes3D:centers"][0], [[0.386, -0.085, 0.005], [0.586, 0.085, 0.01],
                                                             [0.786, -0.085, 0.005]], atol=FLOAT32)
    np.testing.assert_allclose(chunk["Boxes3D:half_sizes"][0], [[0.125, 0.08, 0.005], [0.125, 0.08, 0.01],
                                                                [0.125, 0.08, 0.005]], atol=FLOAT32)
    strips = {side: entities[f"/world/walking/footprints/{side}"][0]["LineStrips3D:strips"][0]
              for side in ("left", "right")}  # the initial footprint, then the footsteps in order
    heights = {side: [strip[0][2] for strip in strips[side]] for side in strips}
    assert heights["left"] == pytest.approx([0.0, 0.0, 0.02, 0.0, 0.0], abs=FLOAT32)
    assert heights["right"] == pytest.approx([0.0, 0.01, 0.01, 0.0], abs=FLOAT32)


def test_without_a_terrain_nothing_is_drawn_and_a_new_terrain_replaces_the_drawn_one(tmp_path):
    terrain, plan = stairs_plan()
    g = dg.Graph(dt=0.001, name="terrains")
    g.add(Ticker("dev"))
    view = g.add(WalkingView("walking", rrd_path=str(tmp_path / "terrains.rrd")))
    view.plan.set(plan)
    g.run(ticks=100)  # the default terrain, the floor alone
    view.terrain.set(terrain)
    g.run(ticks=100)
    view.terrain.set(tilted_platforms())
    g.run(ticks=100)
    view.terrain.reset()
    g.run(ticks=100)
    g.close()
    chunks = read_rrd(tmp_path / "terrains.rrd")["/world/walking/terrain"]
    assert all("tick" not in chunk for chunk in chunks)
    assert [labels for chunk in chunks for labels in chunk["Boxes3D:labels"]] == [
        [s.name for s in terrain.surfaces], [s.name for s in tilted_platforms().surfaces], []]
