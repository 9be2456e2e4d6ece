"""Walking evaluation on synthetic series with known answers: the PGM per gait stage, the ZMP error
of a walk cut at its fall, the normal-force jumps at the contact switches, the distance to a
support polygon's edge and the CoM jerk."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dgraph.evaluation import (
    before_fall,
    contact_switch_force_jumps,
    first_fall,
    jerk_statistics,
    phase_passivity,
    polygon_margin,
    tracking_error,
)

LEFT_ANKLE, RIGHT_ANKLE = [0], [1]


def gait(ticks_per_stage: int = 100) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """double support, left swing, right swing: one stage after the other."""
    stage = np.repeat(np.arange(3), ticks_per_stage)
    return stage == 0, stage == 1, stage == 2


def test_pgm_per_stage_takes_both_ankles_then_the_stance_one_then_the_flying_one():
    double, left_swing, right_swing = gait()
    torque = np.zeros((300, 3))  # columns: left ankle, right ankle, another joint
    torque[double] = [3.0, 4.0, 12.0]                # RMS ankles 5, all 13
    torque[left_swing] = [2.0, 6.0, 3.0]             # stance: the right ankle (6), flying: the left (2); all 7
    torque[right_swing] = [1.0, 0.0, math.sqrt(48)]  # stance: the left ankle (1), flying: the right (0); all 7
    pgm = phase_passivity(torque, LEFT_ANKLE, RIGHT_ANKLE, double, left_swing, right_swing)
    assert pgm.double_support == pytest.approx(1 - 5 / 13)
    assert pgm.single_support == pytest.approx(1 - math.sqrt((36 + 1) / 2) / 7)
    assert pgm.flying_foot == pytest.approx(1 - math.sqrt((4 + 0) / 2) / 7)


def test_a_passive_flying_foot_scores_one_and_a_stage_without_ticks_is_nan():
    double, left_swing, right_swing = gait()
    torque = np.ones((300, 3))
    torque[left_swing, 0] = 0.0
    torque[right_swing, 1] = 0.0
    pgm = phase_passivity(torque, LEFT_ANKLE, RIGHT_ANKLE, double, left_swing, right_swing)
    assert pgm.flying_foot == 1.0
    assert pgm.single_support == pytest.approx(1 - 1 / math.sqrt(2))
    standing = phase_passivity(np.ones((300, 3)), LEFT_ANKLE, RIGHT_ANKLE, np.ones(300, bool),
                               np.zeros(300, bool), np.zeros(300, bool))
    assert math.isnan(standing.single_support) and math.isnan(standing.flying_foot)
    assert standing.double_support == pytest.approx(1 - math.sqrt(2 / 3))


def test_the_zmp_error_of_a_walk_stops_at_its_fall():
    t = np.arange(1000) * 1e-3
    planned = np.column_stack([0.2 * t, 0.08 * np.sin(2 * np.pi * t)])
    error = np.zeros((1000, 2))
    error[:600:2, 0] = 0.02      # x: 0.02 on every other tick, so mean 0.01, std 0.01, peak 0.02
    error[:600, 1] = -0.015      # y: a constant offset
    error[600:] = 1.0            # on the floor
    fallen = t >= 0.6
    assert first_fall(fallen) == 600 and first_fall(np.zeros(5, bool)) is None
    assert before_fall(fallen).sum() == 600 and before_fall(np.zeros(5, bool)).all()
    zmp = tracking_error(planned + error, planned, mask=before_fall(fallen))
    assert np.allclose(zmp.mean, [0.01, 0.015]) and np.allclose(zmp.std, [0.01, 0.0], atol=1e-12)
    assert np.allclose(zmp.peak, [0.02, 0.015])


def load_transfer() -> tuple[np.ndarray, np.ndarray]:
    """The left foot unloads 400 N over ticks 400-500 (4 N per tick) and lifts off at tick 500;
    the right one carries the rest (800 N in all), with a 100 N step at tick 50 and 30 N at 550."""
    left = np.clip(400.0 - 4.0 * (np.arange(1000) - 400), 0.0, 400.0)
    right = 800.0 - left
    right[50:] += 100.0
    right[550:] += 30.0
    contact = np.ones((1000, 2), dtype=bool)
    contact[500:, 0] = False
    return np.column_stack([left, right]), contact


def test_force_jumps_are_looked_for_near_the_contact_switches_only():
    force, contact = load_transfer()
    left, right = contact_switch_force_jumps(force, contact, window=100)
    assert left.largest == pytest.approx(4.0) and 400 <= left.tick <= 500
    assert right.largest == pytest.approx(30.0) and right.tick == 550  # not the 100 N step at tick 50
    left, right = contact_switch_force_jumps(force, contact, window=10)
    assert left.largest == pytest.approx(4.0) and right.largest == pytest.approx(4.0)  # 550 is out of the window
    assert contact_switch_force_jumps(force, np.ones((1000, 2), bool), window=100) == [None, None]


def test_polygon_margin_is_the_signed_distance_to_the_nearest_edge():
    square = (np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0], [0.0, 0.0]]),
              np.array([1.0, 1.0, 0.0, 0.0, np.inf]))  # [0, 1]^2 and a padding row
    points = np.array([[0.5, 0.5], [0.1, 0.7], [1.2, 0.5], [1.3, 1.4], [2.5, 0.5]])
    normals = np.repeat(square[0][None], 5, axis=0)
    offsets = np.repeat(square[1][None], 5, axis=0)
    offsets[4] += [2.0, 0.0, -2.0, 0.0, 0.0]  # the last point's square is [2, 3] x [0, 1]
    assert polygon_margin(points, normals, offsets) == pytest.approx([0.5, 0.1, -0.2, -0.4, 0.5])


def test_jerk_of_a_constant_jerk_then_of_a_stop():
    dt = 1e-3
    ramp = np.outer(np.arange(101) * dt, [3.0, 4.0])  # jerk (3, 4): norm 5
    assert jerk_statistics(ramp, dt) == pytest.approx((5.0, 5.0))
    stopped = np.vstack([ramp, np.repeat(ramp[-1:], 100, axis=0)])  # then 100 steps of zero jerk
    rms, peak = jerk_statistics(stopped, dt)
    assert rms == pytest.approx(5.0 / math.sqrt(2)) and peak == pytest.approx(5.0)
    with pytest.raises(ValueError):
        jerk_statistics(ramp[:1], dt)
