"""Linear inverted pendulum relations (thesis Eq. 2.22–2.28), on arrays of any leading shape."""

from __future__ import annotations

import numpy as np

GRAVITY = 9.81


def natural_frequency(com_height: np.ndarray | float, gravity: float = GRAVITY) -> np.ndarray | float:
    """``ω = √(g / c_z)``, ``c_z`` the CoM height above the ground (Eq. 2.23)."""
    return np.sqrt(gravity / com_height)


def lipm_zmp(com: np.ndarray, com_acceleration: np.ndarray, omega: np.ndarray | float) -> np.ndarray:
    """``p = c − c̈ / ω²`` on the horizontal axes (Eq. 2.22; the last axis is x, y[, z])."""
    return com[..., :2] - com_acceleration[..., :2] / np.square(np.asarray(omega))[..., None]


def divergent_component(com: np.ndarray, com_velocity: np.ndarray, omega: np.ndarray | float) -> np.ndarray:
    """The DCM ``ξ = c + ċ / ω`` on the horizontal axes (Eq. 2.27)."""
    return com[..., :2] + com_velocity[..., :2] / np.asarray(omega)[..., None]
