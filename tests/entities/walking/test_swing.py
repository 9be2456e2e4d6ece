"""Swing trajectories: the path's ends, apex, orientation and exact derivatives; the entity along a plan."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.references.minimum_jerk import minimum_jerk
from dgraph.entities.walking.footsteps import straight_walk, yaw_placement
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


def test_velocity_and_acceleration_are_the_time_derivatives():
    duration = 0.9
    path = SwingPath(START, END, duration, 0.07)
    h = 1e-5 * duration
    speed = max(np.abs(path.at(x).velocity).max() for x in np.linspace(0, 1, 101))
    acceleration = max(np.abs(path.at(x).acceleration).max() for x in np.linspace(0, 1, 101))
    for x in np.linspace(0.02, 0.98, 25):
        before, now, after = path.at(x - h / duration), path.at(x), path.at(x + h / duration)
        linear = (after.position - before.position) / (2 * h)
        angular = pin.log3(after.rotation @ before.rotation.T) / (2 * h)  # world axes
        assert np.abs(np.concatenate([linear, angular]) - now.velocity).max() < 1e-6 * speed
        assert np.abs((after.velocity - before.velocity) / (2 * h) - now.acceleration).max() < 1e-6 * acceleration


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
