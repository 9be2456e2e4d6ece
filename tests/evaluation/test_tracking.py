"""Tracking errors on synthetic series with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.evaluation import tracking_error


def test_a_constant_offset():
    reference = np.zeros((100, 3))
    actual = reference + np.array([0.003, -0.004, 0.0])
    error = tracking_error(actual, reference)
    assert np.allclose(error.mean, [0.003, 0.004, 0.0]) and np.allclose(error.std, 0.0)
    assert np.allclose(error.peak, [0.003, 0.004, 0.0])
    assert error.rms == pytest.approx(0.005) and error.max == pytest.approx(0.005)


def test_a_sinusoidal_error_over_whole_periods():
    t = np.arange(1000) / 1000
    error = tracking_error(0.02 * np.sin(2 * np.pi * 5 * t), np.zeros(1000))
    assert error.rms == pytest.approx(0.02 / np.sqrt(2), rel=1e-6)
    assert error.mean[0] == pytest.approx(0.02 * 2 / np.pi, rel=1e-3)  # mean |sin| = 2 / pi
    assert error.max == pytest.approx(0.02, rel=1e-4)


def test_a_mask_keeps_only_its_ticks():
    actual = np.r_[np.zeros(50), np.ones(50)]
    assert tracking_error(actual, np.zeros(100), mask=np.arange(100) < 50).max == 0.0
    assert tracking_error(actual, np.zeros(100), mask=np.arange(100) >= 50).rms == 1.0
    with pytest.raises(ValueError):
        tracking_error(actual, np.zeros(100), mask=np.zeros(100, dtype=bool))
