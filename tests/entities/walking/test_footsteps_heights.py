"""Footstep plans over changing heights (issue 14): terrain_walk's step-to gait and lateral offset,
the ZMP plane height (zmp_height, zmp_height_at), the CoM's support height, the tilted platforms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from dgraph.entities.walking.footsteps import GAITS, FootstepPlan, straight_walk, terrain_walk, yaw_placement
from dgraph.entities.walking.terrain import Terrain, flat, stairs, tilted_platforms

LEFT0 = yaw_placement([-0.009, 0.085, 0.0])
RIGHT0 = yaw_placement([-0.009, -0.085, 0.0])
"""TALOS's soles at half-sitting: their centres at (-0.014, +-0.085, 0), as the terrains assume."""
RISE = 0.10
"""The default stairs' rise (m)."""


def stairs_plan(**options) -> FootstepPlan:
    """The step-to climb of the default stairs: six pairs of 0.30 m steps."""
    return terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30, gait="step_to", **options)


def platforms_plan() -> FootstepPlan:
    """The crossing of the tilted platforms with graphs/talos_platforms.yaml's footstep parameters."""
    return terrain_walk(tilted_platforms(), LEFT0, RIGHT0, gait="step_to", steps=4, length=0.31, width=0.24,
                        lateral_offset=-0.0085)


def surface_names(terrain: Terrain, plan: FootstepPlan) -> list[str]:
    """The name of the surface under each footstep's sole centre."""
    centres = [plan.sole.center(step.placement) for step in plan.steps]
    return [terrain.surface_under(c[0], c[1]).name for c in centres]


def stance_centre_height(plan: FootstepPlan, time: float) -> float:
    """The height of the single stance sole's centre at ``time`` (in a single support)."""
    (placement,) = plan.stance_placements(time).values()
    return float(plan.sole.center(placement)[2])


def initial_midpoint(plan: FootstepPlan) -> np.ndarray:
    """(3,) the midpoint of the initial sole centres."""
    return 0.5 * (plan.sole.center(plan.initial_left) + plan.sole.center(plan.initial_right))


def keyframes(plan: FootstepPlan) -> tuple[np.ndarray, np.ndarray]:
    """The support height's keyframes, from the phases: (0, initial midpoint), (middle of each
    single support, stance sole centre), (duration, final midpoint)."""
    singles = [phase for phase in plan.phases if phase.kind == "single"]
    times = [0.0, *(0.5 * (phase.start + phase.end) for phase in singles), plan.duration]
    middles = [stance_centre_height(plan, time) for time in times[1:-1]]
    return np.array(times), np.array([initial_midpoint(plan)[2], *middles, plan.final_midpoint()[2]])


def phase_boundaries(plan: FootstepPlan) -> np.ndarray:
    """The times where a phase starts, and the end."""
    return np.array([phase.start for phase in plan.phases] + [plan.duration])


# -- the step-to gait ---------------------------------------------------------------------------
@pytest.mark.parametrize("first_side", ["left", "right"])
def test_step_to_puts_both_feet_on_each_tread_the_lead_foot_first(first_side):
    plan = stairs_plan(first_side=first_side)
    assert len(plan.steps) == 12
    other = "right" if first_side == "left" else "left"
    assert [step.side for step in plan.steps] == [first_side, other] * 6
    names = surface_names(stairs(), plan)
    assert names == [f"step_{k}" for k in (1, 1, 2, 2, 3, 3, 4, 4, 5, 5)] + ["landing", "landing"]
    heights = np.array([step.placement[2, 3] for step in plan.steps])
    np.testing.assert_allclose(heights, np.repeat(RISE * np.arange(1, 7), 2), rtol=0.0, atol=1e-9)
    xs = np.array([step.placement[0, 3] for step in plan.steps])
    np.testing.assert_allclose(xs, np.repeat(-0.009 + 0.30 * np.arange(1, 7), 2), rtol=0.0, atol=1e-12)
    ys = np.array([step.placement[1, 3] for step in plan.steps])
    lead_y = 0.085 if first_side == "left" else -0.085
    np.testing.assert_allclose(ys, [lead_y, -lead_y] * 6, rtol=0.0, atol=1e-12)


def test_step_to_does_not_read_the_half_steps():
    plan = stairs_plan()
    for half_first, half_last in ((False, True), (True, False), (False, False)):
        other = stairs_plan(half_first=half_first, half_last=half_last)
        for step, reference in zip(other.steps, plan.steps, strict=True):
            assert step.side == reference.side
            np.testing.assert_array_equal(step.placement, reference.placement)


@pytest.mark.parametrize("gait", GAITS)
@pytest.mark.parametrize("offset", [0.05, -0.12])
def test_the_lateral_offset_moves_every_footstep_sideways(gait, offset):
    plan = terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30, gait=gait)
    moved = terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30, gait=gait, lateral_offset=offset)
    for step, reference in zip(moved.steps, plan.steps, strict=True):
        shift = step.placement[:3, 3] - reference.placement[:3, 3]
        np.testing.assert_allclose(shift, [0.0, offset, 0.0], rtol=0.0, atol=1e-12)
        np.testing.assert_array_equal(step.placement[:3, :3], reference.placement[:3, :3])


@pytest.mark.parametrize("gait", GAITS)
@pytest.mark.parametrize("yaw", [0.7, -2.0])
def test_the_lateral_offset_is_to_the_left_of_the_walks_heading(gait, yaw):
    left = yaw_placement([1.0, 2.0, 0.0], yaw)
    right = yaw_placement([1.0 + 0.17 * math.sin(yaw), 2.0 - 0.17 * math.cos(yaw), 0.0], yaw)
    plan = terrain_walk(flat(), left, right, steps=3, length=0.2, gait=gait)
    moved = terrain_walk(flat(), left, right, steps=3, length=0.2, gait=gait, lateral_offset=0.07)
    to_the_left = 0.07 * np.array([-math.sin(yaw), math.cos(yaw), 0.0])
    for step, reference in zip(moved.steps, plan.steps, strict=True):
        np.testing.assert_allclose(step.placement[:3, 3] - reference.placement[:3, 3], to_the_left, rtol=0.0,
                                   atol=1e-12)


def test_an_offset_that_puts_a_sole_over_a_treads_side_is_refused_naming_the_step():
    stairs_plan(lateral_offset=-0.34)  # the right sole's outer edge at -0.494 m: on the 1 m wide tread
    with pytest.raises(ValueError, match=r"step 1: .*surface 'step_1'.*over 'floor'"):
        stairs_plan(lateral_offset=-0.35)  # the right foot steps second: its outer edge at -0.504 m
    with pytest.raises(ValueError, match=r"step 0: .*surface 'step_1'.*over 'floor'"):
        stairs_plan(lateral_offset=0.35)


def test_an_unknown_gait_is_refused():
    with pytest.raises(ValueError, match=r"gait must be one of alternate, step_to, got 'hop'"):
        terrain_walk(stairs(), LEFT0, RIGHT0, steps=6, length=0.30, gait="hop")


# -- the ZMP plane height -----------------------------------------------------------------------
@pytest.mark.parametrize(("plan", "changes"), [(stairs_plan(), 6), (platforms_plan(), 6)], ids=["stairs", "platforms"])
def test_the_zmp_plane_is_the_stance_soles_in_single_support_and_linear_between_the_soles_in_double(plan, changes):
    changing = 0
    for index, phase in enumerate(plan.phases):
        fractions = np.array([0.0, 0.25, 0.5, 0.75])
        heights = plan.zmp_height(phase.start + fractions * phase.duration)
        if phase.kind == "single":
            np.testing.assert_array_equal(heights, stance_centre_height(plan, phase.start))
            continue
        before = plan.phases[index - 1] if index else None
        after = plan.phases[index + 1] if index + 1 < len(plan.phases) else None
        start = stance_centre_height(plan, before.start) if before else initial_midpoint(plan)[2]
        end = stance_centre_height(plan, after.start) if after else plan.final_midpoint()[2]
        np.testing.assert_allclose(heights, start + fractions * (end - start), rtol=0.0, atol=1e-12)
        changing += abs(end - start) > 1e-3
    assert changing == changes  # stairs: the six rises; platforms: onto flat_1, the four pads, onto flat_2


def test_on_the_stairs_the_plane_rises_one_tread_in_the_double_support_after_the_lead_foot_lands():
    plan = stairs_plan()
    rising = plan.phases[2::4]  # the double supports after each left (lead) touch-down
    assert len(rising) == 6
    for tread, phase in enumerate(rising, start=1):
        assert (phase.zmp_from[2], phase.zmp_to[2]) == pytest.approx(((tread - 1) * RISE, tread * RISE), abs=1e-12)
        middle = plan.zmp_height([0.5 * (phase.start + phase.end)])[0]
        assert middle == pytest.approx((tread - 0.5) * RISE, abs=1e-12)


@pytest.mark.parametrize(("plan", "first_rise"), [(stairs_plan(), RISE), (platforms_plan(), 0.16)],
                         ids=["stairs", "platforms"])
def test_the_zmp_plane_height_is_continuous(plan, first_rise):
    heights = plan.zmp_height(np.arange(-0.5, plan.duration + 0.5, 0.001))
    steepest = max(abs(phase.zmp_to[2] - phase.zmp_from[2]) / phase.duration for phase in plan.phases)
    assert steepest == pytest.approx(first_rise / 0.115, abs=1e-9)  # from the floor onto the first tread or pad
    assert np.abs(np.diff(heights)).max() <= steepest * 0.001 + 1e-12
    assert heights[-1] - heights[0] == pytest.approx(plan.final_midpoint()[2], abs=1e-12)


@pytest.mark.parametrize("plan", [stairs_plan(), platforms_plan()], ids=["stairs", "platforms"])
def test_zmp_height_at_is_zmp_height_and_its_rate_the_slope(plan):
    rng = np.random.default_rng(14)
    times = np.concatenate([rng.uniform(-1.0, plan.duration + 1.0, 1000), phase_boundaries(plan)])
    values = np.array([plan.zmp_height_at(time) for time in times])
    np.testing.assert_allclose(values[:, 0], plan.zmp_height(times), rtol=0.0, atol=1e-12)
    step = 1e-4
    clear = np.abs(times[:, None] - phase_boundaries(plan)[None, :]).min(axis=1) > 2.0 * step
    difference = (plan.zmp_height(times + step) - plan.zmp_height(times - step)) / (2.0 * step)
    np.testing.assert_allclose(values[clear, 1], difference[clear], rtol=0.0, atol=1e-9)
    assert np.abs(values[:, 1]).max() > 0.5  # some times are in a rising double support


def test_on_flat_ground_the_zmp_plane_is_the_initial_height_exactly():
    for height in (0.0, 0.1):
        left, right = LEFT0.copy(), RIGHT0.copy()
        left[2, 3] = right[2, 3] = height
        plan = straight_walk(left, right, steps=4)
        times = np.arange(-0.5, plan.duration + 0.5, 0.001)
        np.testing.assert_array_equal(plan.zmp_height(times), height)
        assert {plan.zmp_height_at(time) for time in times[::10]} == {(height, 0.0)}
        assert {plan.support_height(time) for time in times[::10]} == {(height, 0.0, 0.0)}


# -- the support height -------------------------------------------------------------------------
def support_heights(plan: FootstepPlan, times: np.ndarray) -> np.ndarray:
    """(n, 3) ``support_height`` (g, g_dot, g_ddot) at ``times``."""
    return np.array([plan.support_height(time) for time in times])


@pytest.mark.parametrize(("plan", "final"), [(stairs_plan(), 6 * RISE), (platforms_plan(), 0.16)],
                         ids=["stairs", "platforms"])
def test_the_support_height_passes_through_its_keyframes_at_rest_and_is_constant_outside(plan, final):
    times, heights = keyframes(plan)
    assert len(times) == len(plan.steps) + 2
    at_keyframes = support_heights(plan, times)
    np.testing.assert_allclose(at_keyframes[:, 0], heights, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(at_keyframes[:, 1:], 0.0, rtol=0.0, atol=1e-12)
    before = support_heights(plan, np.array([-10.0, -1.0, -1e-9]))
    after = support_heights(plan, plan.duration + np.array([1e-9, 1.0, 10.0]))
    np.testing.assert_array_equal(before, [[heights[0], 0.0, 0.0]] * 3)
    np.testing.assert_array_equal(after, [[heights[-1], 0.0, 0.0]] * 3)
    assert (heights[0], heights[-1]) == pytest.approx((0.0, final), abs=1e-12)


@pytest.mark.parametrize("plan", [stairs_plan(), platforms_plan()], ids=["stairs", "platforms"])
def test_the_support_heights_rates_are_its_derivatives(plan):
    """Central differences with 1e-6 s steps: truncation step^2 g''' / 6 < 1e-11, rounding
    1e-16 g / step ~ 1e-10; at a keyframe the jerk g''' jumps (by up to 120 rise / span^3, some
    10 m/s^3), so there the difference of g_dot is off by up to that jump x step / 4."""
    rng = np.random.default_rng(140)
    key_times = keyframes(plan)[0]
    times = np.concatenate([rng.uniform(-0.5, plan.duration + 0.5, 400), key_times])
    step = 1e-6
    centre, ahead, behind = (support_heights(plan, times + shift) for shift in (0.0, step, -step))
    np.testing.assert_allclose(centre[:, 1], (ahead[:, 0] - behind[:, 0]) / (2 * step), rtol=0.0, atol=1e-8)
    acceleration = (ahead[:, 1] - behind[:, 1]) / (2 * step)
    smooth = np.abs(times[:, None] - key_times[None, :]).min(axis=1) > 2 * step
    assert smooth.sum() == 400
    np.testing.assert_allclose(centre[smooth, 2], acceleration[smooth], rtol=0.0, atol=1e-7)
    np.testing.assert_allclose(centre[~smooth, 2], acceleration[~smooth], rtol=0.0, atol=1e-5)
    assert np.abs(centre[:, 1]).max() > 0.05 and np.abs(centre[:, 2]).max() > 0.05  # it does move


@pytest.mark.parametrize(("single_support", "double_support"), [(1.6, 0.3), (0.9, 0.115)])
def test_on_the_stairs_the_vertical_acceleration_is_the_minimum_jerk_peak_over_a_stride(single_support,
                                                                                       double_support):
    """One rise from the middle of a single support to the middle of the next, SS + DS apart:
    a minimum-jerk move's peak acceleration is 10 / sqrt(3) rise / (SS + DS)^2, 0.160 m/s^2 at
    1.6 s and 0.3 s (the docstrings' bound, 1.6 % of g), 0.560 m/s^2 at 0.9 s and 0.115 s."""
    plan = stairs_plan(single_support=single_support, double_support=double_support)
    peak = np.abs(support_heights(plan, np.arange(0.0, plan.duration, 0.001))[:, 2]).max()
    expected = 10.0 / math.sqrt(3.0) * RISE / (single_support + double_support) ** 2
    assert peak == pytest.approx(expected, rel=1e-4)
    if single_support == 1.6:
        assert peak < 0.16
    else:
        assert peak > 0.3


def test_on_the_stairs_the_support_height_climbs_without_ever_descending():
    plan = stairs_plan()
    heights = support_heights(plan, np.arange(-0.5, plan.duration + 0.5, 0.001))
    assert np.diff(heights[:, 0]).min() >= 0.0
    assert heights[:, 1].min() >= 0.0
    assert (heights[0, 0], heights[-1, 0]) == pytest.approx((0.0, 6 * RISE), abs=1e-12)


# -- the tilted platforms -----------------------------------------------------------------------
def test_the_platforms_walk_puts_each_sole_on_its_pad_with_the_pads_normal():
    terrain = tilted_platforms()
    plan = platforms_plan()
    names = surface_names(terrain, plan)
    assert names == ["flat_1", "flat_1", "tilted_1", "tilted_2", "tilted_3", "tilted_4", "flat_2", "flat_2"]
    assert [step.side for step in plan.steps] == ["left", "right"] * 4
    for step, name in zip(plan.steps, names, strict=True):
        surface = terrain.surface(name)
        np.testing.assert_allclose(step.placement[:3, 2], surface.normal, rtol=0.0, atol=1e-9)
        corners = plan.sole.corners(step.placement)
        np.testing.assert_allclose(corners @ surface.normal, surface.center @ surface.normal, rtol=0.0, atol=1e-12)
        assert all(surface.contains(x, y) for x, y, _ in corners)
    sine = math.sin(math.radians(15.0))
    expected_normals = [(0, sine), (sine, 0), (-sine, 0), (0, -sine)]  # tilted_1 .. tilted_4, (n_x, n_y)
    np.testing.assert_allclose([step.placement[:2, 2] for step in plan.steps[2:6]], expected_normals, atol=1e-12)


def hull_distances(normals: np.ndarray, offsets: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, m) the distance of each point inside each edge line of a polygon ``A z <= b``."""
    return offsets[None, :] - points @ normals.T


def test_a_double_support_with_one_sole_tilted_has_the_hull_of_the_projected_corners():
    """The double support after the left foot lands on tilted_1 (rolled 15 degrees about x) beside the
    right one on flat_1: its polygon is the convex hull of the eight corners projected on the
    horizontal plane, the tilted sole's projected width 2 x 0.069 cos 15 degrees."""
    plan = platforms_plan()
    tilted_landing = plan.phases[2 * 2 + 2]  # phase 2 k + 2: the double support after footstep k
    assert tilted_landing.kind == "double" and plan.phases[5].swing_side == "left"
    time = 0.5 * (tilted_landing.start + tilted_landing.end)
    feet = plan.stance_placements(time)
    assert feet["left"][:3, 2] @ [0.0, 0.0, 1.0] == pytest.approx(math.cos(math.radians(15.0)), abs=1e-12)
    assert feet["right"][:3, 2] @ [0.0, 0.0, 1.0] == pytest.approx(1.0, abs=1e-12)
    corners = {side: plan.sole.corners(placement)[:, :2] for side, placement in feet.items()}
    left_width = corners["left"][:, 1].max() - corners["left"][:, 1].min()
    assert left_width == pytest.approx(2 * plan.sole.half_width * math.cos(math.radians(15.0)), abs=1e-12)
    points = np.vstack([corners["left"], corners["right"]])
    normals, offsets = plan.support_polygon(time)
    distances = hull_distances(normals, offsets, points)
    assert distances.min() >= -1e-9  # every corner inside or on the boundary
    assert (np.abs(distances) <= 1e-9).sum(axis=0).min() >= 2  # every edge through two corners: a hull edge
    assert len(offsets) == len(ConvexHull(points).vertices)
    for side in ("left", "right"):  # each sole supports the hull: a corner of it on the boundary
        on_boundary = np.abs(hull_distances(normals, offsets, corners[side])).min(axis=1) <= 1e-9
        assert on_boundary.sum() >= 2
