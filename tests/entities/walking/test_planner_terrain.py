"""FootstepPlanner on a terrain (issue 14): the terrain, gait and lateral_offset parameters, the
walked_terrain output, and their parameter errors."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.walking.footsteps import FootstepPlan, terrain_walk
from dgraph.entities.walking.planner import FootstepPlanner
from dgraph.entities.walking.terrain import Terrain, stairs, tilted_platforms
from dgraph.files import loads

PLATFORMS_WALK = {"terrain": "platforms", "gait": "step_to", "steps": 4, "length": 0.31, "width": 0.24,
                  "lateral_offset": -0.0085, "single_support": 1.6, "double_support": 0.3}
"""The footstep parameters of graphs/talos_platforms.yaml."""


def assert_same_plan(plan: FootstepPlan, expected: FootstepPlan) -> None:
    """The same footsteps (sides, placements bit for bit) and the same phases."""
    assert [step.side for step in plan.steps] == [step.side for step in expected.steps]
    for step, reference in zip(plan.steps, expected.steps, strict=True):
        np.testing.assert_array_equal(step.placement, reference.placement)
        assert (step.single_support, step.double_support) == (reference.single_support, reference.double_support)
    assert [(p.kind, p.start, p.end) for p in plan.phases] == [(p.kind, p.start, p.end) for p in expected.phases]


def test_a_step_to_climb_of_stairs10_is_terrain_walks_plan_from_the_standing_soles():
    planner = FootstepPlanner("planner", terrain="stairs10", gait="step_to", length=0.30)
    plan = planner.plan(0)
    expected = terrain_walk(stairs(), planner.initial_left, planner.initial_right, steps=6, length=0.30,
                            gait="step_to")
    assert_same_plan(plan, expected)
    assert len(plan.steps) == 12 and [step.side for step in plan.steps] == ["left", "right"] * 6
    heights = [step.placement[2, 3] for step in plan.steps]
    np.testing.assert_allclose(heights, np.repeat(0.1 * np.arange(1, 7), 2), rtol=0.0, atol=1e-9)
    assert plan.support_height(plan.duration) == pytest.approx((0.6, 0.0, 0.0), abs=1e-9)


def test_a_graph_file_walks_a_named_terrain_with_a_gait_and_an_offset():
    graph = loads("""
name: stairs_plan
dt: 0.001
entities:
  footsteps:
    type: FootstepPlanner
    params: {terrain: stairs10, gait: step_to, length: 0.30, lateral_offset: 0.05, first_side: right}
""")
    planner = graph["footsteps"]
    expected = terrain_walk(stairs(), planner.initial_left, planner.initial_right, steps=6, length=0.30,
                            gait="step_to", lateral_offset=0.05, first_side="right")
    assert_same_plan(planner.plan(0), expected)
    assert planner.plan(0).steps[0].side == "right"
    assert planner.plan(0).steps[0].placement[1, 3] - planner.initial_right[1, 3] == pytest.approx(0.05, abs=1e-12)


def test_walked_terrain_is_the_terrain_walked_on():
    planner = FootstepPlanner("planner", terrain="stairs10", gait="step_to", length=0.30)
    walked = planner.walked_terrain(0)
    assert isinstance(walked, Terrain) and walked.floor
    assert [surface.name for surface in walked.surfaces] == ["step_1", "step_2", "step_3", "step_4", "step_5",
                                                            "landing"]
    for surface, expected in zip(walked.surfaces, stairs().surfaces, strict=True):
        np.testing.assert_array_equal(surface.placement, expected.placement)
        assert surface.half_extents == expected.half_extents
    assert planner.walked_terrain(500) is walked


def test_a_terrain_given_as_plain_data_is_walked_as_the_same_terrain_by_name():
    plain = stairs().to_plain()
    by_data = FootstepPlanner("data", terrain=plain, gait="step_to", length=0.30)
    by_name = FootstepPlanner("name", terrain="stairs10", gait="step_to", length=0.30)
    assert by_data.walked_terrain(0).to_plain() == plain
    assert_same_plan(by_data.plan(0), by_name.plan(0))


def test_without_a_terrain_the_walked_terrain_is_the_floor_alone():
    walked = FootstepPlanner("planner").walked_terrain(0)
    assert walked.surfaces == () and walked.floor
    assert walked.height_at(0.3, 0.0) == 0.0


def test_the_platforms_walk_of_talos_platforms_yaml_builds_from_the_standing_soles():
    planner = FootstepPlanner("planner", **PLATFORMS_WALK)
    plan = planner.plan(0)
    terrain = tilted_platforms()
    centres = [plan.sole.center(step.placement) for step in plan.steps]
    names = [terrain.surface_under(c[0], c[1]).name for c in centres]
    assert names == ["flat_1", "flat_1", "tilted_1", "tilted_2", "tilted_3", "tilted_4", "flat_2", "flat_2"]
    for step, name in zip(plan.steps, names, strict=True):
        np.testing.assert_allclose(step.placement[:3, 2], terrain.surface(name).normal, rtol=0.0, atol=1e-9)
    assert plan.duration == pytest.approx(1.0 + 8 * 1.6 + 7 * 0.3 + 1.0, abs=1e-12)
    middle = 0.5 * (planner.initial_left[1, 3] + planner.initial_right[1, 3])
    ys = [centre[1] - middle for centre in centres]
    assert ys == pytest.approx([0.12 - 0.0085, -0.12 - 0.0085] * 4, abs=1e-9)


@pytest.mark.parametrize(("params", "parameter", "reason"), [
    ({"gait": "step_to"}, "gait", "read only on a terrain"),
    ({"lateral_offset": 0.1}, "lateral_offset", "read only on a terrain"),
    ({"terrain": "stairs", "length": 0.3}, "terrain", "unknown terrain 'stairs'; known: flat, stairs10"),
    ({"terrain": {"surfaces": [{"name": "board"}]}, "length": 0.3}, "terrain", "surface 0: half_extents is missing"),
    ({"terrain": "stairs10", "walk": "lateral", "length": 0.1}, "terrain", "not used by walk 'lateral'"),
    ({"terrain": "stairs10", "length": 0.225}, "walk", r"step 0: .*surface 'step_1'.*over 'floor'"),
    ({"terrain": "stairs10", "gait": "step_to", "length": 0.3, "lateral_offset": 0.36}, "walk",
     r"step 0: .*surface 'step_1'.*over 'floor'"),
])
def test_terrain_parameters_errors_are_param_errors_naming_the_parameter(params, parameter, reason):
    with pytest.raises(dg.ParamError, match=f"planner.*parameter '{parameter}'.*{reason}") as error:
        FootstepPlanner("planner", **params)
    assert error.value.entity == "planner"
