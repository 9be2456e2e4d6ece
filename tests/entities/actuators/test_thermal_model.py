"""ThermalModel: Eqs. 3.6-3.8, the idle temperature, the steady state and the 20 kg / 5 cm holding case."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.actuators import ActuatorModel, ThermalModel
from dgraph.entities.actuators.chain import TALOS_ELBOW_R_KM
from dgraph.entities.actuators.thermal_model import ALPHA_CU, steady_temperature, thermal_step

FILE = Path(__file__).parents[3] / "graphs" / "data" / "talos_actuators.yaml"
G = 9.81


def heat(current, seconds, dt=1.0, **params):
    g = dg.Graph(dt=dt)
    th = g.add(ThermalModel("thermal", size=len(current), **params))
    th.current.set(current)
    g.run(duration=seconds)
    return th


def test_idle_cools_back_to_43_with_the_time_constant():
    """From 80 °C without current the rise over T_A decays as exp(-t / (R_th C_th)): after one time
    constant (600 s) it is 37 / e."""
    th = heat([0.0, 0.0], 600.0, dt=0.5, T0=[80.0, 43.0])
    assert th.temperature.value[0] == pytest.approx(43.0 + 37.0 / np.e, abs=1e-9)
    assert th.temperature.value[1] == pytest.approx(43.0, abs=1e-12)  # idle stays idle
    assert th.joule_power(th.temperature.time) == pytest.approx([0.0, 0.0])


def test_alpha_is_copper_referred_to_43_c():
    # R(T) = R_20 (1 + 3.93e-3 (T - 20)): the slope at 43 °C relative to R(43)
    assert ALPHA_CU == pytest.approx(3.93e-3 / (1 + 3.93e-3 * 23.0), rel=1e-12)
    assert ThermalModel.alpha_Cu.default == ALPHA_CU


@pytest.mark.parametrize("current", [1.0, 3.0, 6.0])
def test_steady_state_solves_the_heat_balance(current):
    th = heat([current], 20 * 600.0, dt=5.0)  # 20 time constants R_th C_th
    T = th.temperature.value[0]
    t = th.temperature.time
    # T_ss = T_A + R_th R_el(T_ss) i^2, R_el linear in T: solved in closed form, and by the balance
    assert T == pytest.approx(steady_temperature(current, 1.5, 0.6)[()], abs=1e-6)
    assert T - 43.0 == pytest.approx(1.5 * th.joule_power(t)[0], abs=1e-6)
    assert th.resistance(t)[0] == pytest.approx(0.6 * (1 + ALPHA_CU * (T - 43.0)))


def test_step_is_exact_and_stable_for_large_dt():
    args = (np.array([400.0]), np.array([1.5]), np.array([0.6]), np.array([43.0]), np.array([ALPHA_CU]))
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
    # alpha R_th R_TA i^2 >= 1: i >= 1 / sqrt(3.604e-3 * 1.5 * 0.6) = 17.56 A
    assert np.isinf(steady_temperature(17.6, 1.5, 0.6))
    assert np.isfinite(steady_temperature(17.5, 1.5, 0.6))


def holding_current(q: float, mass: float = 20.0, lever: float = 0.05) -> tuple[float, bool]:
    """The elbow current (the actuator model, at rest) holding ``mass`` at ``lever`` from the elbow
    along the forearm, and whether it saturates. The thesis's convention (L3903-3907): the load's
    moment is ``g (L_Y sin q + L_X cos q)`` like the forearm's, its first moment ``L_Y = m l`` added to
    the forearm's ``M_Y`` (Table 3.1: 1.1 kg m, ``M_X`` -0.11); 34 kg at 5 cm gives the printed
    16.67 N m only perpendicular to gravity (the forearm horizontal)."""
    g = dg.Graph(dt=0.001)
    chain = g.add(ActuatorModel("chain", joints=["arm_left_4_joint"], path=str(FILE)))
    chain.tau_desired.set([G * ((1.1 + mass * lever) * np.sin(q) - 0.11 * np.cos(q))])
    chain.q_dot.set([0.0])
    return float(chain.current_desired(0)[0]), bool(chain.saturated(0)[0])


def test_the_load_moment_is_the_thesis_first_moment():
    # perpendicular (forearm horizontal): 34 kg at 5 cm is the thesis's 16.67 N m, on top of the forearm's
    perpendicular, _ = holding_current(-np.pi / 2, mass=34.0)
    forearm, _ = holding_current(-np.pi / 2, mass=0.0)
    assert (perpendicular - forearm) * TALOS_ELBOW_R_KM == pytest.approx(-34.0 * G * 0.05)
    assert 34.0 * G * 0.05 == pytest.approx(16.67, abs=0.01)
    hanging, _ = holding_current(0.0, mass=34.0)  # the forearm down: the load pulls along it
    assert hanging == pytest.approx(holding_current(0.0, mass=0.0)[0])


def test_holding_20_kg_at_5_cm_is_thermally_harmless():
    """30° of elbow flexion: the load's 20 kg x 5 cm x g sin 30° = 4.9 N m + the forearm's 6.3 N m -
    off_m 0.86 N m, 3.49 A, under the 6 A limit; an hour at that current from 43 °C ends at 54.3 °C
    (steady 54.4 °C), with the gap-filler thermal parameters (R_TA 0.6 Ohm, R_th 1.5 K/W, C_th 400 J/K).
    Past 62.2° of flexion the chain cannot hold 20 kg at 5 cm (more than 6 A with R K_m = 2.98 N m/A; the
    forearm horizontal needs 6.63 A); at the 6 A limit itself an hour ends at 79.5 °C, under T_max =
    100 °C: every load the chain can hold is harmless, with these parameters."""
    current, saturated = holding_current(-np.pi / 6)
    assert not saturated and abs(current) == pytest.approx((9.81 * (2.1 * 0.5 + 0.11 * np.cos(np.pi / 6)) - 0.86)
                                                           / TALOS_ELBOW_R_KM)
    assert abs(current) == pytest.approx(3.4855, abs=1e-4)
    assert not holding_current(-np.radians(62.1))[1] and holding_current(-np.radians(62.2))[1]
    assert holding_current(-np.pi / 2)[0] == pytest.approx(-6.6319, abs=1e-4)  # horizontal: not holdable
    th = heat([current, 6.0], 3600.0)
    T = th.temperature.value
    assert T == pytest.approx([54.346, 79.501], abs=1e-3)
    assert (T < 100.0).all() and (th.headroom(th.temperature.time) > 0).all()
    # the closed-form transient x(t) = x_ss (1 - exp(-a t)), a = (1/R_th - alpha R_TA i^2) / C_th
    a = (1 / 1.5 - ALPHA_CU * 0.6 * current**2) / 400.0
    rise = (steady_temperature(current, 1.5, 0.6)[()] - 43.0) * -np.expm1(-a * 3600.0)
    assert T[0] == pytest.approx(43.0 + rise, abs=1e-6)
    assert steady_temperature(current, 1.5, 0.6)[()] == pytest.approx(54.382, abs=1e-3)
