"""Mechanical energy of the joints and cost of transport (thesis Eq. 4.16)."""

from __future__ import annotations

import numpy as np

GRAVITY = 9.81


def mechanical_energy(torque: np.ndarray, velocity: np.ndarray, dt: float) -> tuple[float, float]:
    """``(E_m, E_m⁺)`` in J from joint torques and velocities (ticks x joints), rectangle rule:
    ``E_m = ∫ Σ_i |τ_i ω_i| dt`` and ``E_m⁺ = ∫ Σ_i max(τ_i ω_i, 0) dt`` (positive work only;
    the thesis does not define E_m⁺ further)."""
    power = np.asarray(torque, dtype=float) * np.asarray(velocity, dtype=float)
    return float(np.abs(power).sum() * dt), float(np.clip(power, 0.0, None).sum() * dt)


def path_length(positions: np.ndarray) -> float:
    """Length of the polyline through ``positions`` (ticks x axes), e.g. the distance ``D``."""
    return float(np.linalg.norm(np.diff(np.asarray(positions, dtype=float), axis=0), axis=1).sum())


def cost_of_transport(energy: float, mass: float, distance: float, gravity: float = GRAVITY) -> float:
    """``C = E / (m g D)`` (Eq. 4.16, dimensionless): ``C_et`` with ``E_m``, ``C_mt`` with ``E_m⁺``."""
    if distance <= 0.0:
        raise ValueError("the cost of transport needs a distance travelled > 0")
    return energy / (mass * gravity * distance)
