"""Passivity gait measure (Eq. 4.17–4.18) on synthetic torques with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.evaluation import passivity_gait_measure, rms_torque


def test_rms_sums_the_joints_then_averages_over_time():
    torque = np.array([[3.0, 4.0], [0.0, 0.0]])
    assert rms_torque(torque) == pytest.approx(np.sqrt(25 / 2))
    assert rms_torque(torque, mask=[True, False]) == 5.0


def test_passive_ankles_score_one_and_ankles_alone_score_zero():
    rng = np.random.default_rng(1)
    torque = rng.normal(size=(500, 4))
    passive = torque.copy()
    passive[:, :2] = 0.0
    assert passivity_gait_measure(passive, [0, 1]) == 1.0
    alone = torque.copy()
    alone[:, 2:] = 0.0
    assert passivity_gait_measure(alone, [0, 1]) == pytest.approx(0.0)


def test_one_ankle_among_two_equal_joints():
    """Two joints of equal RMS torque, one an ankle: PGM = 1 - 1 / sqrt(2)."""
    t = np.linspace(0, 1, 1000, endpoint=False)
    torque = np.column_stack([np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)]) * 30.0
    assert passivity_gait_measure(torque, [0]) == pytest.approx(1 - 1 / np.sqrt(2))


def test_gait_stages_are_masks():
    torque = np.zeros((10, 2))
    torque[:5, 0] = 1.0   # stage A: only the ankle works
    torque[5:, 1] = 1.0   # stage B: only the other joint
    stage_a = np.arange(10) < 5
    assert passivity_gait_measure(torque, [0], mask=stage_a) == 0.0
    assert passivity_gait_measure(torque, [0], mask=~stage_a) == 1.0
