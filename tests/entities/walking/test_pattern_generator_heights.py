"""ZmpPatternGenerator over changing heights (issue 14): the CoM and DCM carried over the plan's
support height, the ZMP on the plan's ZMP plane, run open loop on the step-to stairs climb; on
flat ground the vertical references unchanged."""

from __future__ import annotations

import numpy as np
import pytest
from test_footsteps_heights import stairs_plan

import dgraph as dg
from dgraph.control.status import SOLVED
from dgraph.entities.walking.footsteps import FootstepPlan, straight_walk, yaw_placement
from dgraph.entities.walking.pattern_generator import ZmpPatternGenerator

DT = 0.001
HEIGHT = 0.87
"""The estimated CoM height above the ground at the first tick: the generator's ``h``."""
"""TALOS's soles at half-sitting: their centres at (-0.014, +-0.085, 0), as the terrains assume."""
OUTPUTS = ("com_position", "com_velocity", "com_acceleration", "zmp", "zmp_velocity", "dcm", "dcm_velocity")


def run_open_loop(plan: FootstepPlan, seconds: float, **params) -> dict[str, np.ndarray]:
    """The generator on ``plan`` for ``seconds``, open loop (feedback 0) from a fixed estimate at
    rest over the initial feet, ``HEIGHT`` above them: every output at every tick."""
    graph = dg.Graph(dt=DT)
    pattern = graph.add(ZmpPatternGenerator("pattern", feedback=0.0, **params))
    pattern.plan.set(plan)
    midpoint = 0.5 * (plan.sole.center(plan.initial_left) + plan.sole.center(plan.initial_right))
    pattern.estimated_com_position.set(np.array([midpoint[0], midpoint[1], plan.ground_height() + HEIGHT]))
    pattern.estimated_com_velocity.set(np.zeros(3))
    rows = {name: [] for name in (*OUTPUTS, "zmp_plane_height", "status")}
    for t in range(round(seconds / DT)):
        for name in rows:
            rows[name].append(getattr(pattern, name)(t))
        graph.step()
    run = {name: np.array(values) for name, values in rows.items()}
    run["faults"] = np.array(graph.fault_log.degraded_ticks)
    return run


@pytest.fixture(scope="module")
def climb() -> tuple[FootstepPlan, dict[str, np.ndarray]]:
    plan = stairs_plan()
    return plan, run_open_loop(plan, plan.duration + 0.5)


def plan_heights(plan: FootstepPlan, ticks: int) -> tuple[np.ndarray, np.ndarray]:
    """Per tick: the plan's ``support_height`` (g, g_dot, g_ddot) and ``zmp_height_at`` (z_p, z_p_dot)."""
    times = np.arange(ticks) * DT
    return (np.array([plan.support_height(time) for time in times]),
            np.array([plan.zmp_height_at(time) for time in times]))


def test_the_stairs_climb_is_planned_without_a_failed_replan(climb):
    plan, run = climb
    assert set(run["status"]) == {SOLVED} and int(run["faults"]) == 0
    np.testing.assert_allclose(run["com_position"][-1, :2], plan.final_midpoint()[:2], rtol=0.0, atol=0.01)


def test_the_com_and_the_dcm_are_carried_over_the_support_height(climb):
    plan, run = climb
    support, _ = plan_heights(plan, len(run["status"]))
    np.testing.assert_allclose(run["com_position"][:, 2], support[:, 0] + HEIGHT, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(run["com_velocity"][:, 2], support[:, 1], rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(run["com_acceleration"][:, 2], support[:, 2], rtol=0.0, atol=1e-12)
    np.testing.assert_array_equal(run["dcm"][:, 2], run["com_position"][:, 2])
    np.testing.assert_array_equal(run["dcm_velocity"][:, 2], run["com_velocity"][:, 2])
    assert run["com_position"][0, 2] == pytest.approx(HEIGHT, abs=1e-12)
    assert run["com_position"][-1, 2] == pytest.approx(0.6 + HEIGHT, abs=1e-9)
    assert run["com_velocity"][:, 2].max() > 0.1  # it climbs


def test_the_zmp_is_on_the_plans_zmp_plane(climb):
    plan, run = climb
    _, zmp_plane = plan_heights(plan, len(run["status"]))
    np.testing.assert_array_equal(run["zmp"][:, 2], run["zmp_plane_height"])
    np.testing.assert_allclose(run["zmp_plane_height"], plan.zmp_height(np.arange(len(run["status"])) * DT),
                               rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(run["zmp_velocity"][:, 2], zmp_plane[:, 1], rtol=0.0, atol=1e-12)
    assert run["zmp_plane_height"][-1] == pytest.approx(0.6, abs=1e-9)
    assert run["zmp_velocity"][:, 2].max() == pytest.approx(0.1 / 0.115, abs=1e-9)  # one rise per double support


def test_the_vertical_velocities_are_the_derivatives_of_the_heights(climb):
    """The trapezoid rule over each 1 ms tick, off by dt^2 f''' / 12: for the CoM height 4.8e-7 m/s
    (a minimum-jerk rise of 0.1 m over 1.015 s: |g'''| <= 60 x 0.1 / 1.015^3 = 5.7 m/s^3), for its
    velocity 2.8e-6 m/s^2 (|g''''| <= 360 x 0.1 / 1.015^4 = 34 m/s^4); for the ZMP plane exact
    but where a tick straddles a double support's start or end (a kink)."""
    plan, run = climb
    for position, velocity, tolerance in (("com_position", "com_velocity", 5e-7),
                                          ("com_velocity", "com_acceleration", 3e-6)):
        difference = np.diff(run[position][:, 2]) / DT
        np.testing.assert_allclose(difference, 0.5 * (run[velocity][1:, 2] + run[velocity][:-1, 2]), rtol=0.0,
                                   atol=tolerance)
    difference = np.diff(run["zmp"][:, 2]) / DT
    trapezoid = 0.5 * (run["zmp_velocity"][1:, 2] + run["zmp_velocity"][:-1, 2])
    kinks = np.flatnonzero(np.abs(difference - trapezoid) > 1e-9)
    rising = [phase for phase in plan.phases if phase.zmp_to[2] - phase.zmp_from[2] > 0.05]
    assert len(rising) == 6
    times = np.arange(len(run["status"])) * DT
    # the kinks: the ticks just before each rising double support's start and end
    boundaries = np.searchsorted(times, [time for phase in rising for time in (phase.start, phase.end)]) - 1
    assert kinks.tolist() == boundaries.tolist()


def test_the_height_transition_adds_to_the_support_height():
    """A standing transition from 0.87 m to com_height 0.80 m over 1 s, on a climb whose first
    rise starts at 0.55 s: the CoM height is g + h + (h0 - h) (1 - s(x)), x = t dt / 1 s."""
    plan = stairs_plan(initial_double_support=0.1)
    run = run_open_loop(plan, 1.5, com_height=0.80, height_transition=1.0)
    support, _ = plan_heights(plan, 1500)
    x = np.minimum(np.arange(1500) * DT / 1.0, 1.0)
    remaining = 0.07 * (1.0 - (10 * x**3 - 15 * x**4 + 6 * x**5))
    np.testing.assert_allclose(run["com_position"][:, 2], support[:, 0] + 0.80 + remaining, rtol=0.0, atol=1e-12)
    np.testing.assert_array_equal(run["dcm"][:, 2], run["com_position"][:, 2])
    assert support[1000, 0] > 0.01  # the climb has begun within the transition


def test_on_flat_ground_the_vertical_references_are_unchanged_constants():
    plan = straight_walk(yaw_placement([0.0, 0.085, 0.0]), yaw_placement([0.0, -0.085, 0.0]))  # the 20 cm walk
    run = run_open_loop(plan, plan.duration + 0.5)
    assert set(run["status"]) == {SOLVED}
    for name in ("com_position", "dcm"):
        np.testing.assert_array_equal(run[name][:, 2], HEIGHT)
    for name in ("com_velocity", "com_acceleration", "zmp", "zmp_velocity", "dcm_velocity"):
        np.testing.assert_array_equal(run[name][:, 2], 0.0)
    np.testing.assert_array_equal(run["zmp_plane_height"], 0.0)
    assert np.abs(run["com_position"][-1, 0] - run["com_position"][0, 0]) > 1.0  # it walked 1.2 m
