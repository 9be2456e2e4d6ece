"""The tank's valves (thesis Eqs. 5.21-5.23) and its energy rate (Eq. 5.20), in the power domain.

```
gamma = P_low / B_sig    if B_sig < P_low <= 0, else 1              power limiter   (5.21)
beta  = 0  if E <= E_min and gamma B_sig - B_phi < 0, else 1        output valve    (5.22)
alpha = 1  if E >= E_max and beta gamma B_sig - B_phi > 0, else 0   overflow valve  (5.23)
E_dot = (1 - alpha) (beta gamma B_sig - B_phi)                                       (5.20)
```

The thesis smooths the switches "as Kronander and Billard" without a formula. Here ``gamma``
keeps its hard form (it is continuous: ``gamma -> 1`` as ``B_sig -> P_low``), while ``beta``
and ``alpha`` blend with the quintic smoothstep over a band of ``band`` joules above ``E_min``
and below ``E_max``: ``beta = smoothstep((E - E_min) / band)`` while draining and
``alpha = smoothstep((E - E_max + band) / band)`` while filling. Every value is finite and in
``[0, 1]`` for every finite input, ``B_sig = 0`` included, and nothing divides by the tank
state ``s = sqrt(2 E)`` (errata table, §2.5 of the notes: the public reference code's
``gamma`` blend goes negative or infinite for small ``B_sig``).
"""

from __future__ import annotations

from dataclasses import dataclass


def smoothstep(x: float) -> float:
    """``6 x^5 - 15 x^4 + 10 x^3`` on ``[0, 1]``, 0 below and 1 above (C2 at both ends)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)


@dataclass(frozen=True, slots=True)
class TankLimits:
    """``E_min``, ``E_max`` (J), ``P_low`` (W, <= 0) and the smoothing band (J, >= 0; 0: hard switches)."""

    minimum: float = 0.1
    maximum: float = 5.0
    power_low: float = -0.5
    band: float = 0.0


@dataclass(frozen=True, slots=True)
class Valves:
    """``alpha``, ``beta``, ``gamma`` and the resulting planned tank rate ``E_dot`` (W)."""

    alpha: float
    beta: float
    gamma: float
    energy_rate: float


def power_limiter(controllable_power: float, power_low: float) -> float:
    """``gamma`` (Eq. 5.21): caps the tasks' draw at ``|P_low|``; in ``[0, 1]``."""
    if controllable_power < power_low <= 0.0:
        return min(1.0, max(0.0, power_low / controllable_power))
    return 1.0


def output_valve(energy: float, draining: bool, limits: TankLimits) -> float:
    """``beta`` (Eq. 5.22): 1, or towards 0 near ``E_min`` while the tank drains."""
    if not draining:
        return 1.0
    if limits.band <= 0.0:
        return 0.0 if energy <= limits.minimum else 1.0
    return smoothstep((energy - limits.minimum) / limits.band)


def overflow_valve(energy: float, filling: bool, limits: TankLimits) -> float:
    """``alpha`` (Eq. 5.23): 0, or towards 1 near ``E_max`` while the tank fills."""
    if not filling:
        return 0.0
    if limits.band <= 0.0:
        return 1.0 if energy >= limits.maximum else 0.0
    return smoothstep((energy - limits.maximum + limits.band) / limits.band)


def valves(energy: float, controllable_power: float, uncontrollable_power: float, limits: TankLimits) -> Valves:
    """The three valves and ``E_dot = (1 - alpha)(beta gamma B_sig - B_phi)`` (Eqs. 5.20-5.23)."""
    gamma = power_limiter(controllable_power, limits.power_low)
    beta = output_valve(energy, gamma * controllable_power - uncontrollable_power < 0.0, limits)
    flow = beta * gamma * controllable_power - uncontrollable_power
    alpha = overflow_valve(energy, flow > 0.0, limits)
    return Valves(alpha, beta, gamma, (1.0 - alpha) * flow)
