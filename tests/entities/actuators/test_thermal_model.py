"""ThermalModel: Eqs. 3.6-3.8, the idle temperature, the steady state and the 20 kg / 5 cm holding case."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.actuators import ActuatorModel, ThermalModel
from dgraph.entities.actuators.thermal_model import steady_temperature, thermal_step

FILE = Path(__file__).parents[3] / "graphs" / "data" / "talos_actuators.yaml"
G = 9.81


def heat(current, seconds, dt=1.0, **params):
    g = dg.Graph(dt=dt)
    th = g.add(ThermalModel("thermal", size=len(current), **params))
    th.current.set(current)
    g.run(duration=seconds)
    return th


def test_idle_stays_at_43():
    th = heat([0.0], 3600.0)
    assert th.temperature.value == pytest.approx([43.0], abs=1e-12)
    assert th.joule_power(th.temperature.time) == pytest.approx([0.0])


@pytest.mark.parametrize("current", [1.0, 3.0, 6.0])
def test_steady_state_solves_the_heat_balance(current):
    th = heat([current], 20 * 600.0, dt=5.0)  # 20 time constants R_th C_th
    T = th.temperature.value[0]
    t = th.temperature.time
    # T_ss = T_A + R_th R_el(T_ss) i^2, R_el linear in T: solved in closed form, and by the balance
    assert T == pytest.approx(steady_temperature(current, 1.5, 0.6)[()], abs=1e-6)
    assert T - 43.0 == pytest.approx(1.5 * th.joule_power(t)[0], abs=1e-6)
    assert th.resistance(t)[0] == pytest.approx(0.6 * (1 + 3.93e-3 * (T - 43.0)))


def test_step_is_exact_and_stable_for_large_dt():
    args = (np.array([400.0]), np.array([1.5]), np.array([0.6]), np.array([43.0]), np.array([3.93e-3]))
    fine = np.array([43.0])
    for _ in range(6000):
        fine = thermal_step(fine, np.array([5.0]), 0.1, *args)
    coarse = thermal_step(np.array([43.0]), np.array([5.0]), 600.0, *args)
    assert coarse == pytest.approx(fine, abs=1e-9)
    huge = thermal_step(np.array([43.0]), np.array([5.0]), 1e6, *args)  # Euler would blow up
    assert huge[0] == pytest.approx(steady_temperature(5.0, 1.5, 0.6)[()], abs=1e-9)
    # explicit Euler's first step agrees for small dt: C T_dot = P_J at T_A
    first = thermal_step(np.array([43.0]), np.array([5.0]), 1e-3, *args)
    assert first - 43.0 == pytest.approx(1e-3 * 0.6 * 25.0 / 400.0, rel=1e-6)


def test_runaway_has_no_steady_state():
    # alpha R_th R_TA i^2 >= 1: i >= 1 / sqrt(3.93e-3 * 1.5 * 0.6) = 16.8 A
    assert np.isinf(steady_temperature(17.0, 1.5, 0.6))
    assert np.isfinite(steady_temperature(16.0, 1.5, 0.6))


def holding_current(q: float, mass: float = 20.0, lever: float = 0.05) -> float:
    """The elbow current (the actuator model, at rest) holding ``mass`` at ``lever`` from the
    elbow (the thesis's convention: 34 kg at 5 cm = 16.67 N m) plus the forearm's own gravity
    ``g (M_Y sin q + M_X cos q)`` of Table 3.1, at elbow angle ``q``; and whether it saturates."""
    g = dg.Graph(dt=0.001)
    chain = g.add(ActuatorModel("chain", joints=["arm_left_4_joint"], path=str(FILE)))
    gravity = G * (1.1 * np.sin(q) - 0.11 * np.cos(q))
    chain.tau_desired.set([np.sign(gravity) * mass * G * lever + gravity])
    chain.q_dot.set([0.0])
    return float(chain.current_desired(0)[0]), bool(chain.saturated(0)[0])


def test_holding_20_kg_at_5_cm_is_thermally_harmless():
    """30° of elbow flexion: 9.81 N m of load + 6.3 N m of forearm - off_m 0.86 N m, 5.13 A,
    under the 6 A limit; an hour at that current from 43 °C ends at 69.0 °C (steady 69.2 °C),
    under T_max = 100 °C, with the gap-filler thermal parameters (R_TA 0.6 Ohm, R_th 1.5 K/W,
    C_th 400 J/K). Past about 50° of flexion the chain cannot hold 20 kg at 5 cm (more than 6 A
    with R K_m = 2.98 N m/A; the forearm horizontal needs 6.6 A); at the 6 A limit itself an hour
    ends at 79.9 °C, so every load the chain can hold is harmless, with these parameters."""
    current, saturated = holding_current(-np.pi / 6)
    assert not saturated and 5.0 < abs(current) < 5.3
    assert holding_current(-np.pi / 2)[1]  # the forearm horizontal: not holdable
    th = heat([current, 6.0], 3600.0)
    T = th.temperature.value
    assert (T < 100.0).all() and (th.headroom(th.temperature.time) > 0).all()
    # the closed-form transient x(t) = x_ss (1 - exp(-a t)), a = (1/R_th - alpha R_TA i^2) / C_th
    a = (1 / 1.5 - 3.93e-3 * 0.6 * current**2) / 400.0
    rise = (steady_temperature(current, 1.5, 0.6)[()] - 43.0) * -np.expm1(-a * 3600.0)
    assert T[0] == pytest.approx(43.0 + rise, abs=1e-6)
