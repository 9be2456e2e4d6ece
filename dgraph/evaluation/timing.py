"""Statistics of the control tick's duration (thesis Table 4.10)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TickStatistics:
    """Durations in seconds: ``mean``, ``median``, ``p99``, ``peak``, and the ``overruns``
    fraction of ticks longer than the period."""

    mean: float
    median: float
    p99: float
    peak: float
    overruns: float


def tick_statistics(durations: np.ndarray, period: float) -> TickStatistics:
    """Statistics of per-tick ``durations`` (s) against the control ``period`` (s)."""
    durations = np.asarray(durations, dtype=float)
    if durations.size == 0:
        raise ValueError("no tick to evaluate")
    return TickStatistics(mean=float(durations.mean()), median=float(np.median(durations)),
                          p99=float(np.percentile(durations, 99)), peak=float(durations.max()),
                          overruns=float(np.mean(durations > period)))
