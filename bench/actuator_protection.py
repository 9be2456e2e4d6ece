"""Cost per tick of TorqueProtection's iLQR (thesis §3.4: 300 us per solve, C++).

    .venv/bin/python bench/actuator_protection.py [--ticks 500]

The elbow (TALOS_ELBOW, R K_m = TALOS_ELBOW_R_KM = 2.977 N m/A) with 10 kg at 5 cm follows a 0.5 Hz
sinusoid that asks more than the 6 A limit (30 kg at 5 cm cannot be held at all within 6 A at
2.977 N m/A), through the protection into the chain (Eq. 3.5 at 0.1 ms), one
solve per 1 ms tick, warm started. Timed: the wall time of each solve (``solve_time``), median
and p99, per call and per joint, for one joint and for 32 joints solved together (the arrays
hold all joints; the 32 copies follow the same motion), at the thesis's two settings: 15 ms at
3 ms knots (5 knots; the thesis says 3.3 ms), and 100 ms at 1 ms (100 knots).
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import calibration

calibration.single_threaded()  # before numpy: one BLAS/OpenMP thread, as the other benchmarks

import numpy as np  # noqa: E402
from calibration import calibrate, calibration_line  # noqa: E402

from dgraph.entities.actuators.chain import GRAVITY, TALOS_ELBOW, TALOS_ELBOW_R_KM  # noqa: E402
from dgraph.entities.actuators.protection import Model, TorqueProtection  # noqa: E402

LOAD_KG, LOAD_ARM = 10.0, 0.05
LOADED = replace(TALOS_ELBOW, R_Km=TALOS_ELBOW_R_KM, M_Y=TALOS_ELBOW.M_Y + LOAD_KG * LOAD_ARM,
                 I_j=TALOS_ELBOW.I_j + LOAD_KG * LOAD_ARM ** 2)


def run(joints: int, horizon: float, knot_step: float, ticks: int) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Solve times (s) and iterations per tick of the closed loop, the peak |current| and the number
    of joint-ticks where the output clip acted."""
    dt = 0.001
    protection = TorqueProtection("protection", chains=[LOADED] * joints, dt=dt, horizon=horizon, knot_step=knot_step)
    plant = Model.from_chains([LOADED] * joints)
    q, v = np.full(joints, -1.2), np.zeros(joints)
    times, iterations, peak, saturated = [], [], 0.0, 0
    w = 2 * np.pi * 0.5
    for t in range(ticks):
        s = t * dt
        q_ref, v_ref, a_ref = -1.2 + 0.9 * np.sin(w * s), 0.9 * w * np.cos(w * s), -0.9 * w * w * np.sin(w * s)
        gravity = GRAVITY * (LOADED.M_Y * np.sin(q) + LOADED.M_X * np.cos(q))
        protection.torque.set(LOADED.I_j * a_ref + 400.0 * (q_ref - q) + 40.0 * (v_ref - v) + gravity)
        protection.q.set(q.copy())
        protection.q_dot.set(v.copy())
        current = protection.current(t)
        times.append(protection.solve_time(t))
        iterations.append(protection.iterations(t))
        peak = max(peak, float(np.abs(current).max()))
        saturated += int(protection.saturated(t).sum())
        for _ in range(10):
            q, v = plant.step(q, v, current, dt / 10)
    return np.array(times), np.array(iterations), peak, saturated


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=500)
    args = parser.parse_args()
    print(f"# {calibration_line(calibrate())}")
    print("| setting | joints | per call median / p99 (us) | per joint median (us) | iterations median / max "
          "| peak abs(i) (A) | clipped joint-ticks | thesis |")
    print("|---|---|---|---|---|---|---|---|")
    for horizon, knot_step, thesis in ((0.015, 0.003, "300 us per joint (C++, i7-3612QE)"),
                                       (0.1, 0.001, "200 us per joint (C++, i7-8850H)")):
        for joints in (1, 32):
            times, iterations, peak, saturated = run(joints, horizon, knot_step, args.ticks)
            med, p99 = np.median(times) * 1e6, np.percentile(times, 99) * 1e6
            print(f"| {horizon * 1e3:.0f} ms at {knot_step * 1e3:.0f} ms ({round(horizon / knot_step)} knots) "
                  f"| {joints} | {med:.0f} / {p99:.0f} | {med / joints:.0f} | {np.median(iterations):.0f} / "
                  f"{iterations.max()} | {peak:.2f} | {saturated} | {thesis} |")
    print(f"# {calibration_line(calibrate())}")


if __name__ == "__main__":
    main()
