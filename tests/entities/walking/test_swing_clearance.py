"""swing_clearance: the soles' corners over the stairs and the tilted platforms (issue 14: the
swings clear the step edges), and the height and lift that give them 2 cm."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_footsteps_heights import LEFT0, RIGHT0

from dgraph.entities.walking.footsteps import Footstep, FootstepPlan, SoleShape, terrain_walk, yaw_placement
from dgraph.entities.walking.swing import SwingPath, swing_clearance, swing_clearances
from dgraph.entities.walking.terrain import Surface, Terrain, stairs, tilted_platforms

"""TALOS's soles at half-sitting: their centres at (-0.014, +-0.085, 0), as the terrains assume."""
TALOS_SOLE = SoleShape()


def step_to_stairs() -> FootstepPlan:
    """Up the stairs one tread at a time: the left foot onto the next tread's centre (0.30 m
    ahead, 0.10 m up), the right one beside it; five treads, then the landing."""
    steps = []
    for tread in range(1, 7):
        for side, y in (("left", 0.085), ("right", -0.085)):
            centre = [0.30 * tread, y, 0.10 * tread]  # the treads' centres: x = 0.30 k
            origin = np.add(centre, [0.5 * (TALOS_SOLE.back - TALOS_SOLE.front), 0.0, 0.0])
            last = tread == 6 and side == "right"
            steps.append(Footstep(side, yaw_placement(origin), 1.6, 1.0 if last else 0.3))
    return FootstepPlan(LEFT0, RIGHT0, tuple(steps), 1.0, 1.0)


PLANS = {
    "stairs": (stairs(), terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30)),
    "stairs_step_to": (stairs(), step_to_stairs()),
    "platforms_left_first": (tilted_platforms(), terrain_walk(tilted_platforms(), LEFT0, RIGHT0, steps=4, length=0.30,
                                                              width=0.28)),
    "platforms_right_first": (tilted_platforms(), terrain_walk(tilted_platforms(), LEFT0, RIGHT0, steps=4,
                                                               length=0.30, width=0.28, first_side="right")),
    # the footsteps of graphs/talos_stairs.yaml and graphs/talos_platforms.yaml
    "stairs_graph": (stairs(), terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30, gait="step_to",
                                            single_support=1.6, double_support=0.3)),
    "platforms_graph": (tilted_platforms(), terrain_walk(tilted_platforms(), LEFT0, RIGHT0, steps=4, length=0.31,
                                                         width=0.24, lateral_offset=-0.0085, gait="step_to",
                                                         single_support=1.6, double_support=0.3)),
}
RECOMMENDED = {"stairs": (0.09, 0.15), "stairs_step_to": (0.09, 0.15), "stairs_graph": (0.09, 0.15),
               "platforms_graph": (0.11, 0.15), "platforms_left_first": (0.19, 0.15),
               "platforms_right_first": (0.19, 0.15)}
"""(height, lift) per plan: with the lift of 0.15, the least height giving each of its swings 2 cm
of clearance, rounded up to the centimetre (measured: 0.0691 m for the stairs' 6 x 0.30 m walk,
0.0864 m for the step-to plan on the treads' centres, 0.070 m for the stairs graph's; 0.1025 m for
the platforms graph's step-to plan, set by the step up onto flat_1; 0.1775 and 0.1825 m for the
alternating platforms plans, set by their second swing, from the floor over flat_1, 0.16 m high,
onto a lower tilted pad). The stairs take the step-to plan's height."""


def test_the_step_to_plan_puts_both_soles_on_each_tread():
    terrain, plan = PLANS["stairs_step_to"]
    names = [terrain.surface_under(*plan.sole.center(step.placement)[:2]).name for step in plan.steps]
    assert names == [name for k in range(1, 6) for name in (f"step_{k}",) * 2] + ["landing", "landing"]
    for step in plan.steps:
        surface = terrain.surface_under(*plan.sole.center(step.placement)[:2])
        assert all(surface.contains(x, y) for x, y, _ in plan.sole.corners(step.placement))
        assert step.placement[2, 3] == pytest.approx(surface.center[2], abs=1e-12)


def test_a_swing_over_one_surface_has_nothing_to_clear():
    _, plan = PLANS["stairs"]
    assert swing_clearances(plan, Terrain(), 0.05) == [math.inf] * len(plan.steps)


def test_over_another_surface_the_clearance_is_the_lowest_corner_above_it():
    board = Surface("board", yaw_placement([0.3, 0.0, 0.05]), (0.1, 0.5))
    path = SwingPath(LEFT0, yaw_placement([0.591, 0.085, 0.0]), 0.9, 0.12, 0.1)
    expected = math.inf
    for x in np.arange(1, 200) / 200:
        sample = path.at(x)
        placement = np.eye(4)
        placement[:3, :3], placement[:3, 3] = sample.rotation, sample.position
        expected = min([expected] + [z - 0.05 for px, py, z in TALOS_SOLE.corners(placement) if board.contains(px, py)])
    assert 0.03 < expected < 0.1  # the floor, under the sole at both ends, does not count
    assert swing_clearance(path, Terrain((board,)), TALOS_SOLE) == pytest.approx(expected, abs=1e-15)


def test_onto_a_higher_surface_the_corners_count_where_they_cross_its_edge():
    board = Surface("board", yaw_placement([0.5, 0.0, 0.05]), (0.2, 0.5))
    path = SwingPath(LEFT0, yaw_placement([0.491, 0.085, 0.05]), 0.9, 0.08, 0.1)
    progresses = np.arange(0, 201) / 200
    samples = [path.at(x) for x in progresses]
    expected = math.inf
    for local in TALOS_SOLE.local_corners():
        corners = [sample.position + sample.rotation @ local for sample in samples]
        entry = next(i for i, c in enumerate(corners) if board.contains(c[0], c[1]))
        expected = min(expected, corners[entry][2] - 0.05, corners[entry - 1][2])
    assert 0.0 < expected < 0.08  # the toe, over the board's edge: not 0, the sole's height at both ends
    assert swing_clearance(path, Terrain((board,)), TALOS_SOLE) == pytest.approx(expected, abs=1e-15)


@pytest.mark.parametrize("name", PLANS)
def test_the_recommended_height_and_lift_clear_every_edge_by_2_cm(name):
    terrain, plan = PLANS[name]
    height, lift = RECOMMENDED[name]
    clearances = swing_clearances(plan, terrain, height, lift)
    assert len(clearances) == len(plan.steps) and min(clearances) >= 0.02


@pytest.mark.parametrize("name", PLANS)
def test_without_a_swing_height_the_soles_hit_the_edges(name):
    terrain, plan = PLANS[name]
    assert min(swing_clearances(plan, terrain, 0.0, 0.15)) < -0.01


def test_on_the_stairs_a_lift_is_worth_centimetres_at_one_height():
    terrain, plan = PLANS["stairs"]
    without, lifted = (min(swing_clearances(plan, terrain, 0.08, lift)) for lift in (0.0, 0.15))
    assert without < 0.0 < 0.02 < lifted
