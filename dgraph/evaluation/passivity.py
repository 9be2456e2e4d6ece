"""Passivity gait measure (thesis Eq. 4.17–4.18, after Mummolo and Kim)."""

from __future__ import annotations

import numpy as np


def rms_torque(torque: np.ndarray, mask: np.ndarray | None = None) -> float:
    """``sqrt(∫ Σ_i τ_i² dt / T)`` over the ticks where ``mask`` is true (Eq. 4.18; uniform ticks,
    so the integral over T is the mean over ticks)."""
    torque = np.asarray(torque, dtype=float)
    if torque.ndim == 1:
        torque = torque[:, None]
    if mask is not None:
        torque = torque[np.asarray(mask, dtype=bool)]
    if len(torque) == 0:
        raise ValueError("no tick to evaluate")
    return float(np.sqrt(np.mean(np.sum(torque**2, axis=1))))


def passivity_gait_measure(torque: np.ndarray, stance_ankle: list[int] | np.ndarray,
                           mask: np.ndarray | None = None) -> float:
    """``PGM = 1 − RMS(τ_sa) / RMS(τ_tot)`` (Eq. 4.17): ``torque`` holds every joint (ticks x
    joints), ``stance_ankle`` the columns of the stance ankle(s), ``mask`` the ticks of one gait
    stage (double support, single support, ...). 1: passive ankles, 0: only the ankles work."""
    torque = np.asarray(torque, dtype=float)
    return 1.0 - rms_torque(torque[:, stance_ankle], mask) / rms_torque(torque, mask)
