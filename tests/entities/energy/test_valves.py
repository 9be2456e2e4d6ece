"""Valves alpha, beta, gamma (thesis Eqs. 5.20-5.23): logic, ranges and extreme inputs (§7.5-7.9)."""

import itertools
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dgraph.entities.energy.valves import TankLimits, power_limiter, smoothstep, valves

HARD = TankLimits(0.1, 5.0, -0.5, 0.0)
SMOOTH = TankLimits(0.1, 5.0, -0.5, 0.2)
EXTREME = [0.0, 1e-12, -1e-12, 1e-6, -1e-6, 0.01, -0.01, -0.5, -0.5000001, 1e6, -1e6, 1e300, -1e300]


@pytest.mark.parametrize("limits", [HARD, SMOOTH])
@pytest.mark.parametrize("b_sigma", EXTREME)
@pytest.mark.parametrize("b_phi", [0.0, 3.0, -1e6])
@pytest.mark.parametrize("energy", [0.0, 0.1, 0.15, 3.0, 4.9, 7.0])
def test_valves_are_finite_and_in_range_for_extreme_inputs(limits, b_sigma, b_phi, energy):
    out = valves(energy, b_sigma, b_phi, limits)
    for value in (out.alpha, out.beta, out.gamma):
        assert math.isfinite(value) and 0.0 <= value <= 1.0
    assert out.gamma > 0.0
    assert math.isfinite(out.energy_rate)


def test_gamma_caps_the_draw_at_p_low_and_is_continuous():
    for b_sigma in (-0.6, -1.0, -10.0, -1e6):
        assert power_limiter(b_sigma, -0.5) * b_sigma == pytest.approx(-0.5)
    for b_sigma in (-0.5, -0.4, 0.0, 1e-12, 3.0):
        assert power_limiter(b_sigma, -0.5) == 1.0
    assert power_limiter(-0.5 - 1e-12, -0.5) == pytest.approx(1.0)


@given(st.floats(0.0, 6.0), st.floats(-100, 100), st.floats(-100, 100))
@settings(max_examples=300, deadline=None)
def test_hard_valve_logic(energy, b_sigma, b_phi):
    out = valves(energy, b_sigma, b_phi, HARD)
    gamma = out.gamma
    if out.beta == 0.0:
        assert energy <= HARD.minimum and gamma * b_sigma - b_phi < 0.0
    if energy > HARD.minimum:
        assert out.beta == 1.0
    flow = out.beta * gamma * b_sigma - b_phi
    if out.alpha > 0.0:
        assert flow > 0.0 and energy >= HARD.maximum
        assert out.energy_rate == 0.0  # alpha = 1: E_dot = 0
    # the key inequality (5.27): -alpha (beta gamma B_sigma - B_phi) <= 0
    assert -out.alpha * flow <= 0.0


@given(st.floats(0.0, 6.0), st.floats(-100, 100), st.floats(-100, 100))
@settings(max_examples=300, deadline=None)
def test_smooth_valves_keep_the_logic(energy, b_sigma, b_phi):
    out = valves(energy, b_sigma, b_phi, SMOOTH)
    flow = out.beta * out.gamma * b_sigma - b_phi
    assert -out.alpha * flow <= 0.0
    if out.alpha > 0.0:
        assert flow > 0.0 and energy > SMOOTH.maximum - SMOOTH.band
    if out.beta < 1.0:
        assert energy < SMOOTH.minimum + SMOOTH.band
    if energy >= SMOOTH.maximum and flow > 0.0:
        assert out.alpha == 1.0 and out.energy_rate == 0.0
    if energy <= SMOOTH.minimum and out.gamma * b_sigma - b_phi < 0.0:
        assert out.beta == 0.0


def test_no_nan_at_an_empty_tank():
    """E = 0 (s = 0): everything is in the power domain, nothing divides by s."""
    for limits in (HARD, SMOOTH):
        out = valves(0.0, -2.0, 1.0, limits)
        assert out.beta == 0.0 and out.energy_rate == -1.0


def test_smoothstep_is_monotone_and_clamped():
    values = [smoothstep(x / 100) for x in range(-10, 111)]
    assert values[0] == 0.0 and values[-1] == 1.0
    assert all(b >= a for a, b in itertools.pairwise(values))
