"""Swing trajectories: the path's ends, apex, orientation and exact derivatives; the entity along a plan."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.references.minimum_jerk import minimum_jerk
from dgraph.entities.walking.footsteps import lateral_walk, straight_walk, turning_walk, yaw_placement
from dgraph.entities.walking.swing import SwingPath, SwingTrajectory, bump
from tests.conftest import Ticker

LEFT0 = yaw_placement([0.0, 0.085, 0.0])
RIGHT0 = yaw_placement([0.0, -0.085, 0.0])


def tilted(position, rpy) -> np.ndarray:
    placement = np.eye(4)
    placement[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    placement[:3, 3] = position
    return placement


START = tilted([0.1, 0.2, 0.05], [0.1, -0.2, 0.4])
END = tilted([0.5, 0.1, 0.15], [-0.15, 0.1, 1.1])


@pytest.mark.parametrize("profile", [minimum_jerk, bump])
def test_profiles_derivatives_are_exact(profile):
    h = 1e-6
    for x in np.linspace(0.01, 0.99, 37):
        _, first, second = profile(x)
        assert first == pytest.approx((profile(x + h)[0] - profile(x - h)[0]) / (2 * h), rel=1e-6, abs=1e-8)
        assert second == pytest.approx((profile(x + h)[1] - profile(x - h)[1]) / (2 * h), rel=1e-6, abs=1e-8)
    assert profile(0.0) == (0.0, 0.0, 0.0) and profile(1.0)[1:] == (0.0, 0.0)
    assert minimum_jerk(1.0)[0] == 1.0 and bump(0.5)[0] == 1.0 and bump(1.0)[0] == 0.0


def test_the_path_starts_and_ends_on_the_placements_at_rest():
    path = SwingPath(START, END, 0.9, 0.05)
    first, last = path.at(0.0), path.at(1.0)
    assert np.abs(first.position - START[:3, 3]).max() == 0.0 and np.abs(first.rotation - START[:3, :3]).max() < 1e-15
    assert np.abs(last.position - END[:3, 3]).max() < 1e-15 and np.abs(last.rotation - END[:3, :3]).max() < 1e-12
    for sample in (first, last):
        assert np.abs(sample.velocity).max() == 0.0 and np.abs(sample.acceleration).max() == 0.0
    # and by finite differences: the path leaves and arrives with no speed nor acceleration (O(x^3))
    h = 1e-4
    near_start, near_end = path.at(h), path.at(1 - h)
    assert np.abs(near_start.position - START[:3, 3]).max() < 1e-9
    assert np.abs(near_end.position - END[:3, 3]).max() < 1e-9
    assert np.abs(near_start.velocity).max() < 1e-6 and np.abs(near_end.velocity).max() < 1e-6
    assert np.abs(near_start.acceleration).max() < 0.02 * np.abs(path.at(0.25).acceleration).max()


def test_the_apex_is_height_above_the_higher_end_at_mid_swing():
    flat = SwingPath(LEFT0, yaw_placement([0.2, 0.085, 0.0]), 0.9, 0.05)
    heights = [flat.at(x).position[2] for x in np.linspace(0, 1, 1001)]
    assert max(heights) == pytest.approx(0.05, abs=1e-15) and int(np.argmax(heights)) == 500
    up = SwingPath(LEFT0, yaw_placement([0.3, 0.085, 0.1]), 0.9, 0.05)
    assert up.at(0.5).position[2] == pytest.approx(0.15, abs=1e-15)
    down = SwingPath(yaw_placement([0.3, 0.085, 0.1]), LEFT0, 0.9, 0.05)
    assert down.at(0.5).position[2] == pytest.approx(0.15, abs=1e-15)
    assert flat.at(0.5).position[:2] == pytest.approx([0.1, 0.085])


def test_a_yawed_step_turns_about_the_vertical_with_the_minimum_jerk_profile():
    path = SwingPath(LEFT0, yaw_placement([0.2, 0.1, 0.0], 0.6), 1.0, 0.05)
    for x in (0.1, 0.25, 0.5, 0.8):
        rotation = path.at(x).rotation
        assert rotation == pytest.approx(pin.rpy.rpyToMatrix(0.0, 0.0, 0.6 * minimum_jerk(x)[0]), abs=1e-14)
    assert path.at(0.5).velocity[3:] == pytest.approx([0.0, 0.0, 0.6 * 1.875])


@pytest.mark.parametrize("lift", [0.0, 0.12])
def test_velocity_and_acceleration_are_the_time_derivatives(lift):
    duration = 0.9
    path = SwingPath(START, END, duration, 0.07, lift)
    h = 1e-5 * duration
    speed = max(np.abs(path.at(x).velocity).max() for x in np.linspace(0, 1, 101))
    acceleration = max(np.abs(path.at(x).acceleration).max() for x in np.linspace(0, 1, 101))
    for x in np.linspace(0.02, 0.98, 25):
        before, now, after = path.at(x - h / duration), path.at(x), path.at(x + h / duration)
        linear = (after.position - before.position) / (2 * h)
        angular = pin.log3(after.rotation @ before.rotation.T) / (2 * h)  # world axes
        assert np.abs(np.concatenate([linear, angular]) - now.velocity).max() < 1e-6 * speed
        assert np.abs((after.velocity - before.velocity) / (2 * h) - now.acceleration).max() < 1e-6 * acceleration


def vertical_bump_swing(start: np.ndarray, end: np.ndarray, duration: float, height: float, x: float):
    """The swing of the flat walks (issue 13), the arithmetic of its implementation then: minimum
    jerk from start to end, the vertical bump ``(height + |dz| / 2) b(x)``, exp3 for the turn."""
    s, ds, dds = minimum_jerk(x)
    b, db, ddb = bump(x)
    p0 = start[:3, 3]
    displacement = end[:3, 3] - p0
    rise = height + 0.5 * abs(displacement[2])
    position = p0 + displacement * s
    position[2] += rise * b
    linear_velocity = displacement * (ds / duration)
    linear_velocity[2] += rise * db / duration
    linear_acceleration = displacement * (dds / duration**2)
    linear_acceleration[2] += rise * ddb / duration**2
    w = pin.log3(start[:3, :3].T @ end[:3, :3])
    axis = start[:3, :3] @ w
    return (position, start[:3, :3] @ pin.exp3(w * s), np.concatenate([linear_velocity, axis * (ds / duration)]),
            np.concatenate([linear_acceleration, axis * (dds / duration**2)]))


def level_walks():
    """Flat walks at a constant height: straight (20 and 60 cm steps, at z = 0.02), turning, lateral."""
    left, right = yaw_placement([0.3, 0.085, 0.02], 0.3), yaw_placement([0.3, -0.085, 0.02], 0.3)
    yield straight_walk(LEFT0, RIGHT0, steps=6, length=0.2)
    yield straight_walk(left, right, steps=6, length=0.6)
    yield turning_walk(LEFT0, RIGHT0, steps=4, angle_per_step=0.2)
    yield lateral_walk(LEFT0, RIGHT0, steps=3, length=0.1)


def test_without_lift_on_level_ground_the_path_is_the_flat_walks_bit_for_bit():
    for plan in level_walks():
        for phase in (p for p in plan.phases if p.kind == "single"):
            path = SwingPath(phase.swing_from, phase.swing_to, phase.duration, 0.05)
            for x in np.linspace(0.0, 1.0, 181):
                sample = path.at(x)
                expected = vertical_bump_swing(phase.swing_from, phase.swing_to, phase.duration, 0.05, x)
                for value, reference in zip((sample.position, sample.rotation, sample.velocity, sample.acceleration),
                                            expected, strict=True):
                    assert np.array_equal(value, reference)
    # between two heights the sums are ordered differently: one rounding at most
    up = yaw_placement([0.35, 0.05, 0.1], 0.4)
    for x in np.linspace(0.0, 1.0, 101):
        sample, expected = SwingPath(LEFT0, up, 0.9, 0.05).at(x), vertical_bump_swing(LEFT0, up, 0.9, 0.05, x)
        assert np.abs(sample.position - expected[0]).max() <= 1e-15
        assert np.abs(sample.velocity - expected[2]).max() <= 1e-15
        assert np.abs(sample.acceleration - expected[3]).max() <= 1e-14


def test_with_a_lift_the_path_still_starts_and_ends_on_the_placements_at_rest():
    path = SwingPath(START, END, 1.6, 0.08, lift=0.15)
    first, last = path.at(0.0), path.at(1.0)
    assert np.abs(first.position - START[:3, 3]).max() == 0.0 and np.abs(first.rotation - START[:3, :3]).max() == 0.0
    assert np.abs(last.position - END[:3, 3]).max() < 1e-15 and np.abs(last.rotation - END[:3, :3]).max() < 1e-12
    for sample in (first, last):
        assert np.abs(sample.velocity).max() == 0.0 and np.abs(sample.acceleration).max() == 0.0
    h = 1e-4
    assert np.abs(path.at(h).position - START[:3, 3]).max() < 1e-9
    assert np.abs(path.at(1 - h).position - END[:3, 3]).max() < 1e-9
    assert np.abs(path.at(h).velocity).max() < 1e-6 and np.abs(path.at(1 - h).velocity).max() < 1e-6


@pytest.mark.parametrize("lift", [0.1, 0.15])
def test_during_the_lift_the_sole_moves_along_its_normal_without_turning(lift):
    path = SwingPath(START, END, 1.6, 0.08, lift)
    rise = (0.08 + 0.05) / (0.5 * (START[2, 2] + END[2, 2]))  # H: |z1 - z0| = 0.1
    for placement, progresses in ((START, np.linspace(0.0, lift, 11)), (END, np.linspace(1.0 - lift, 1.0, 11))):
        normal = placement[:3, 2]
        for x in progresses:
            sample = path.at(x)
            offset = sample.position - placement[:3, 3]
            assert np.abs(offset - normal * rise * bump(x)[0]).max() < 1e-15
            assert np.abs(sample.rotation - placement[:3, :3]).max() < 1e-12
            assert np.abs(sample.velocity[:3] - normal * rise * bump(x)[1] / 1.6).max() < 1e-14
            assert np.abs(sample.velocity[3:]).max() == 0.0 and np.abs(sample.acceleration[3:]).max() == 0.0
    # the sole has left along the normal (H b(lift) = 4.7 % of H at 0.1, 13 % at 0.15) and crosses after
    assert np.linalg.norm(path.at(lift).position - START[:3, 3]) == pytest.approx(rise * bump(lift)[0], rel=1e-12)
    assert np.abs(path.at(lift + 0.05).velocity[3:]).max() > 0.01


def test_with_a_lift_and_tilted_normals_the_apex_is_height_above_the_higher_end_at_mid_swing():
    for lift in (0.0, 0.1, 0.15):
        assert SwingPath(START, END, 1.6, 0.08, lift).at(0.5).position[2] == pytest.approx(0.15 + 0.08, abs=1e-15)
        assert SwingPath(END, START, 1.6, 0.08, lift).at(0.5).position[2] == pytest.approx(0.15 + 0.08, abs=1e-15)


def test_a_lift_outside_0_to_one_half_or_normals_that_do_not_point_up_are_refused():
    for lift in (-0.01, 0.5):
        with pytest.raises(ValueError, match="lift is a fraction of the swing in"):
            SwingPath(START, END, 0.9, 0.05, lift)
    upside_down = tilted([0.5, 0.1, 0.15], [math.pi, 0.0, 0.0])
    with pytest.raises(ValueError, match="do not point up on average"):
        SwingPath(LEFT0, upside_down, 0.9, 0.05)


def plan_graph(start: float = 0.0, **params):
    graph = dg.Graph(dt=0.001)
    graph.add(Ticker("clock"))
    plan = dataclasses.replace(straight_walk(LEFT0, RIGHT0, steps=2, initial_double_support=0.5), start=start)
    feet = {side: graph.add(SwingTrajectory(f"{side}_foot", side=side, **params)) for side in ("left", "right")}
    for foot in feet.values():
        foot.plan.set(plan)
    return graph, plan, feet


def test_the_entity_follows_the_plan_foot_by_foot():
    _, plan, feet = plan_graph(start=0.2)
    left, right = feet["left"], feet["right"]
    lift_off, touch_down = 700, 1600  # ticks: start 0.2 s + initial double support 0.5 s, then 0.9 s of swing
    assert left.position(lift_off - 1) == pytest.approx(LEFT0[:3, 3]) and not left.velocity(lift_off - 1).any()
    mid = SwingPath(LEFT0, plan.steps[0].placement, 0.9, 0.05).at(0.5)
    assert left.position(1150) == pytest.approx(mid.position, abs=1e-12)
    assert left.velocity(1150) == pytest.approx(mid.velocity, abs=1e-12)
    assert left.orientation(1150) == pytest.approx([0.0, 0.0, 0.0, 1.0])
    assert left.position(touch_down) == pytest.approx(plan.steps[0].placement[:3, 3], abs=1e-12)
    assert not left.acceleration(touch_down).any()
    assert right.position(1150) == pytest.approx(RIGHT0[:3, 3]) and not right.velocity(1150).any()
    # the sampled references are consistent from tick to tick (1 ms): v ~ dp/dt, a ~ dv/dt
    ticks = range(lift_off - 5, touch_down + 5)
    positions = np.array([left.position(t) for t in ticks])
    velocities = np.array([left.velocity(t) for t in ticks])
    accelerations = np.array([left.acceleration(t) for t in ticks])
    assert np.abs(np.gradient(positions, 0.001, axis=0) - velocities[:, :3]).max() < 2e-3 * np.abs(velocities).max()
    assert np.abs(np.gradient(velocities, 0.001, axis=0) - accelerations).max() < 2e-2 * np.abs(accelerations).max()
    assert max(positions[:, 2]) == pytest.approx(0.05, abs=1e-6)


def test_the_orientation_output_is_an_xyzw_quaternion():
    graph = dg.Graph(dt=0.001)
    graph.add(Ticker("clock"))
    turned = straight_walk(yaw_placement([0.0, 0.085, 0.0], 0.8), yaw_placement([0.0, -0.085, 0.0], 0.8), steps=1)
    foot = graph.add(SwingTrajectory("foot", side="right", height=0.0))
    foot.plan.set(turned)
    quaternion = foot.orientation(0)
    assert quaternion == pytest.approx([0.0, 0.0, math.sin(0.4), math.cos(0.4)])


def test_the_entity_lifts_along_the_normal_with_its_lift_parameter():
    _, plan, feet = plan_graph(start=0.2, lift=0.12)
    left = feet["left"]
    for tick in (745, 1150, 1591):  # lift-off at tick 700, 0.9 s of swing
        sample = SwingPath(LEFT0, plan.steps[0].placement, 0.9, 0.05, 0.12).at((tick - 700) / 900)
        assert left.position(tick) == pytest.approx(sample.position, abs=1e-12)
        assert left.velocity(tick) == pytest.approx(sample.velocity, abs=1e-12)
        assert left.acceleration(tick) == pytest.approx(sample.acceleration, abs=1e-12)
    assert left.position(745)[:2] == pytest.approx(LEFT0[:2, 3], abs=1e-15)  # straight up during the lift
    assert left.position(745)[2] == pytest.approx(0.05 * bump(0.05)[0], rel=1e-12)
    with pytest.raises(dg.ParamError, match="'lift' must be < 0.5"):
        SwingTrajectory("foot", side="left", lift=0.5)
