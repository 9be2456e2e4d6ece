"""terrain_walk: straight_walk's footsteps put on a terrain (issue 14, item 2, the plan)."""

from __future__ import annotations

import numpy as np
import pytest
from test_footsteps_heights import LEFT0, RIGHT0, surface_names

from dgraph.entities.walking.footsteps import straight_walk, terrain_walk, yaw_placement
from dgraph.entities.walking.terrain import Terrain, flat, stairs, tilted_platforms

"""TALOS's soles at half-sitting: their centres at (-0.014, +-0.085, 0), as the terrains assume."""


def test_on_the_stairs_a_0_30m_stride_puts_each_footstep_on_the_next_tread_at_its_height():
    terrain = stairs()
    plan = terrain_walk(terrain, LEFT0, RIGHT0, steps=6, length=0.30)
    names = surface_names(terrain, plan)
    assert names == ["step_1", "step_2", "step_3", "step_4", "step_5", "landing", "landing"]
    for step, name in zip(plan.steps, names, strict=True):
        surface = terrain.surface(name)
        height = 0.6 if name == "landing" else 0.1 * int(name[-1])
        assert step.placement[2, 3] == pytest.approx(height, abs=1e-9)
        np.testing.assert_allclose(step.placement[:3, :3], np.eye(3), atol=1e-12)
        corners = plan.sole.corners(step.placement)
        np.testing.assert_allclose(corners[:, 2], height, atol=1e-9)
        assert all(surface.contains(x, y) for x, y, _ in corners)
    np.testing.assert_allclose(plan.steps[-1].placement[:2, 3], [-0.009 + 6 * 0.30, 0.085], atol=1e-12)


@pytest.mark.parametrize(("first_side", "tilted"), [("left", ["tilted_2", "tilted_3"]),
                                                    ("right", ["tilted_1", "tilted_4"])])
def test_on_a_tilted_pad_the_sole_normal_is_the_pads_and_the_heading_is_kept_in_projection(first_side, tilted):
    terrain = tilted_platforms()
    plan = terrain_walk(terrain, LEFT0, RIGHT0, steps=4, length=0.30, width=0.28, first_side=first_side)
    names = surface_names(terrain, plan)
    assert names == ["flat_1", *tilted, "flat_2", "flat_2"]
    for step, name in zip(plan.steps, names, strict=True):
        surface = terrain.surface(name)
        rotation, origin = step.placement[:3, :3], step.placement[:3, 3]
        np.testing.assert_allclose(rotation[:, 2], surface.normal, atol=1e-9)
        heading = np.array([1.0, 0.0, 0.0]) - surface.normal[0] * surface.normal
        np.testing.assert_allclose(rotation[:, 0], heading / np.linalg.norm(heading), atol=1e-12)
        assert abs(rotation[1, 0]) < 1e-12 and rotation[0, 0] > 0.0
        assert surface.normal @ (origin - surface.center) == pytest.approx(0.0, abs=1e-12)
        assert all(surface.contains(x, y) for x, y, _ in plan.sole.corners(step.placement))
    tilted_normals = [step.placement[:3, 2] for step in plan.steps[1:3]]
    assert all(abs(n[2] - np.cos(np.radians(15.0))) < 1e-9 for n in tilted_normals)
    centre = plan.sole.center(plan.steps[1].placement)
    flat_centre = np.array([-0.014 + 0.60, 0.14 if first_side == "right" else -0.14])
    np.testing.assert_allclose(centre[:2], flat_centre, atol=1e-12)


@pytest.mark.parametrize("initial", [(LEFT0, RIGHT0), (yaw_placement([1.0, 2.1, 0.0], 0.7),
                                                       yaw_placement([1.1, 1.95, 0.0], 0.7))])
@pytest.mark.parametrize("options", [{}, {"first_side": "right", "half_first": False, "half_last": False,
                                          "width": 0.2, "single_support": 0.8, "double_support": 0.1}])
def test_on_flat_ground_the_plan_is_straight_walks(initial, options):
    expected = straight_walk(*initial, steps=5, length=0.25, **options)
    plan = terrain_walk(flat(), *initial, steps=5, length=0.25, **options)
    assert len(plan.steps) == len(expected.steps) == 6
    for step, reference in zip(plan.steps, expected.steps, strict=True):
        assert step.side == reference.side
        np.testing.assert_allclose(step.placement, reference.placement, rtol=0.0, atol=1e-12)
    assert [(p.kind, p.start, p.end) for p in plan.phases] == [(p.kind, p.start, p.end) for p in expected.phases]


def test_a_footstep_straddling_an_edge_is_refused_naming_the_step_and_the_surface():
    with pytest.raises(ValueError, match=r"step 0: .*surface 'step_1'.*over 'floor'"):
        terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.225)
    with pytest.raises(ValueError, match=r"step 1: .*surface 'step_2'.*over 'step_1'"):
        terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.28)


def test_the_margin_keeps_the_sole_that_far_inside_the_surface():
    terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30, margin=0.03)
    with pytest.raises(ValueError, match=r"step 0: .*surface 'step_1' \(margin 0.04 m\).*within 0.04 m of its edge"):
        terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30, margin=0.04)


def test_a_sole_centre_over_no_surface_is_refused():
    no_floor = Terrain(stairs().surfaces, floor=False)
    terrain_walk(no_floor, LEFT0, RIGHT0, steps=8, length=0.30)
    with pytest.raises(ValueError, match=r"step 8: no surface under the sole centre \(2.6860, 0.0850\)"):
        terrain_walk(no_floor, LEFT0, RIGHT0, steps=9, length=0.30)
