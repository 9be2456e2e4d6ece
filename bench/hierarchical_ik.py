"""Hierarchical IK tick on TALOS: the five-level stack of thesis Table 4.1, against Table 4.10.

    .venv/bin/python bench/hierarchical_ik.py [--ticks 5000] [--rounds 3] [--json out/hierarchical_ik.json]

Stack (``tests/entities/hierarchy/talos_ik.py``): 0 feet contacts (VelocityContact x2) and joint
limits, I CoM height, II CoM lateral-sagittal, III waist orientation, IV posture (half-sitting);
Table 4.3 IK gains. The CoM reference sways +-5 cm laterally at 0.5 Hz so every level works,
on a KinematicDevice integrating the velocity (``q+ = q (+) dt v``).

- **graph tick**: a ``before`` hook of the device pulls ``solver.velocity(t)`` and times it
  (``time.perf_counter_ns``): RobotModel (one Pinocchio pass), 5 features, 4 velocity tasks,
  2 contacts, the limits, assembly and the cascade, with dgraph's signal overhead. This is what
  Table 4.10 times for SoT (0.5-0.7 ms average, C++).
- **cascade**: the solver's own ``solve_time`` (elimination, closed-form levels, ProxQP levels).
- variants interleaved round by round: the stack as Table 4.1 lists it (equalities only) and
  with the joint limits (32 inequalities) on a level of their own above the feet; each with the default ``closed_form``
  (ProxQP only for a level whose closed-form step violates an inequality) and with every level
  sent to ProxQP (``closed_form=False``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import calibration

calibration.single_threaded()  # before numpy: one BLAS/OpenMP thread, as the other benchmarks

import numpy as np  # noqa: E402
from calibration import calibrate, calibration_line  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "entities" / "hierarchy"))

import talos_ik  # noqa: E402

THESIS_AVERAGE_MS = (0.5, 0.7)  # Table 4.10, IK, average over the scenarios (C++, SoT)


def stats(values: np.ndarray) -> dict[str, float]:
    return {"median": float(np.median(values)), "p99": float(np.percentile(values, 99)),
            "mean": float(values.mean()), "max": float(values.max())}


def run(ticks: int, closed_form: bool, limits: bool, warmup: int = 500) -> dict[str, object]:
    graph = talos_ik.build(closed_form=closed_form, limits=limits)
    solver, feature = graph["solver"], graph["com_xy_feature"]
    centre = feature.reference_position(0).copy()
    tick_ns: list[int] = []
    cascade_s: list[float] = []
    qp_levels: list[int] = []

    def control(t: int) -> None:
        feature.reference_position.set(centre + np.array([0.0, 0.05 * np.sin(np.pi * t * graph.dt), 0.0]))
        start = time.perf_counter_ns()
        solver.velocity(t)
        tick_ns.append(time.perf_counter_ns() - start)
        solution = solver.solution(t)
        cascade_s.append(solution.solve_time)
        qp_levels.append(solution.qp_levels)
        if solution.status != 0:
            raise RuntimeError(f"status {solution.status} at tick {t}")

    graph["device"].before.add(control)
    graph.run(ticks=warmup, progress=False)
    tick_ns.clear()
    cascade_s.clear()
    qp_levels.clear()
    graph.run(ticks=ticks, progress=False)
    com_error = np.abs(feature.feature.value.error).max()
    return {"tick_us": stats(np.array(tick_ns) / 1e3), "cascade_us": stats(np.array(cascade_s) * 1e6),
            "ticks_with_a_qp_level": int(np.count_nonzero(qp_levels)), "com_xy_error_m": float(com_error)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=5000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    cal = calibrate()
    print(calibration_line(cal))  # names the machine
    print(f"numpy {np.__version__}; {args.ticks} ticks x {args.rounds} rounds")
    variants = {"table_4_1": (True, False), "table_4_1_every_level_proxqp": (False, False),
                "with_joint_limits": (True, True), "with_joint_limits_every_level_proxqp": (False, True)}
    results: dict[str, list[dict[str, object]]] = {name: [] for name in variants}
    for round_index in range(args.rounds):
        for name, (closed_form, limits) in variants.items():
            result = run(args.ticks, closed_form, limits)
            results[name].append(result)
            tick, cascade = result["tick_us"], result["cascade_us"]
            print(f"round {round_index} {name:>36}: graph tick median {tick['median']:7.1f} us  p99 "
                  f"{tick['p99']:7.1f}  mean {tick['mean']:7.1f} | cascade median {cascade['median']:6.1f} us  "
                  f"p99 {cascade['p99']:6.1f} | ticks with a ProxQP level {result['ticks_with_a_qp_level']}")
    print(f"thesis Table 4.10 (SoT IK, C++): average {THESIS_AVERAGE_MS[0]}-{THESIS_AVERAGE_MS[1]} ms per loop")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"machine": cal["cpu"], "calibration": cal, "ticks": args.ticks,
                                          "results": results}, indent=1))


if __name__ == "__main__":
    main()
