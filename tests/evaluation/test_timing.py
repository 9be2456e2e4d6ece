"""Tick statistics on known durations."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.evaluation import tick_statistics


def test_statistics_of_known_durations():
    durations = np.r_[np.full(98, 0.4e-3), 0.9e-3, 2.0e-3]
    stats = tick_statistics(durations, period=1e-3)
    assert stats.mean == pytest.approx((98 * 0.4 + 0.9 + 2.0) * 1e-5)
    assert stats.median == pytest.approx(0.4e-3) and stats.peak == 2.0e-3
    assert stats.overruns == pytest.approx(0.01)
    assert 0.4e-3 < stats.p99 < 2.0e-3
    with pytest.raises(ValueError):
        tick_statistics(np.array([]), period=1e-3)
