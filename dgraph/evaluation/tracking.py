"""Tracking errors of a recorded signal against its reference (thesis Tables 4.4–4.7)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TrackingError:
    """Per axis: ``mean`` |e|, ``std`` of |e| and ``peak`` |e| (the thesis's Average / Std / Peak);
    over the vector: ``rms`` = sqrt(mean ||e||²) and ``max`` = max ||e||."""

    mean: np.ndarray
    std: np.ndarray
    peak: np.ndarray
    rms: float
    max: float


def tracking_error(actual: np.ndarray, reference: np.ndarray, mask: np.ndarray | None = None) -> TrackingError:
    """Errors of ``actual`` against ``reference`` (ticks x axes, or ticks), on the ticks where
    ``mask`` (bool, one per tick) is true (default: all)."""
    error = np.asarray(actual, dtype=float) - np.asarray(reference, dtype=float)
    if error.ndim == 1:
        error = error[:, None]
    if mask is not None:
        error = error[np.asarray(mask, dtype=bool)]
    if len(error) == 0:
        raise ValueError("no tick to evaluate")
    magnitude = np.abs(error)
    norm = np.linalg.norm(error, axis=1)
    return TrackingError(mean=magnitude.mean(axis=0), std=magnitude.std(axis=0), peak=magnitude.max(axis=0),
                         rms=float(np.sqrt(np.mean(norm**2))), max=float(norm.max()))
