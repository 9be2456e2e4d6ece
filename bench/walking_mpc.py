"""Re-plan time of the ZMP/LIPM pattern generator on the thesis' 20 cm straight walk.

    .venv/bin/python bench/walking_mpc.py [--length 0.2] [--period 0.005] [--rounds 3] [--json PATH]

A ``FootstepPlanner`` straight walk on TALOS (6 steps of ``--length`` and a closing step, SS
0.9 s, DS 0.115 s, 1 s initial and final double supports: thesis L4679-4686) feeds a
``ZmpPatternGenerator`` (its defaults: T 0.1 s, N 16, margin 0.02 m, re-planned every
``--period`` s from the measured state). Its ZMP drives an exact LIPM (the ZMP held over each
1 ms tick) that starts at rest with TALOS's half-sitting CoM, and the LIPM's CoM is the
generator's estimate: the closed loop of the tests, from tick 0 to 1 s after the plan's end.

Per round: every re-plan's time (``ComPlan.solve_time``: the QP's assembly and ProxQP's solve)
and iterations, and the entity's cost per tick (reading its seven reference outputs) on the
ticks that re-plan and on those that do not. Printed: median and p99 over all rounds, in µs and
in calibration loops (bench/calibration.py), the walk's outcome (the final CoM against the
final midpoint, the planned ZMP against the plan's reference, the statuses), the calibration
line before and after and the CPU other processes took meanwhile; ``--json`` keeps everything.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import calibration

calibration.single_threaded()  # before numpy: one BLAS/OpenMP thread, as the other benchmarks

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from calibration import BusyMeter, calibrate, calibration_line, in_loops  # noqa: E402

import dgraph as dg  # noqa: E402
from dgraph.entities.estimators.leg_odometry import standing_configuration  # noqa: E402
from dgraph.entities.robot.loading import load_model  # noqa: E402
from dgraph.entities.stabilizers.lipm import GRAVITY  # noqa: E402
from dgraph.entities.walking import FootstepPlanner, ZmpPatternGenerator  # noqa: E402

DT = 0.001
REFERENCES = ("com_position", "com_velocity", "com_acceleration", "zmp", "zmp_velocity", "dcm", "dcm_velocity")


def standing_com() -> np.ndarray:
    """TALOS's CoM at half-sitting, soles on the floor."""
    model = load_model("talos")
    return pin.centerOfMass(model, model.createData(), standing_configuration(model, ["left_sole_link",
                                                                                      "right_sole_link"]))


def walk(length: float, period: float, com: np.ndarray) -> dict:
    """One closed-loop run (see the module docstring): per-re-plan and per-tick times, the outcome."""
    graph = dg.Graph(dt=DT)
    planner = graph.add(FootstepPlanner("planner", length=length))
    pattern = graph.add(ZmpPatternGenerator("pattern", period=period))
    graph.plug(planner.plan, pattern.plan)
    plan = planner.plan(0)
    omega = math.sqrt(GRAVITY / com[2])
    cosh, sinh = math.cosh(omega * DT), math.sinh(omega * DT)
    position, velocity = com.copy(), np.zeros(3)
    run = {"replan_us": [], "iterations": [], "tick_replan_us": [], "tick_us": [], "statuses": set(), "zmp_error": []}
    readers = [getattr(pattern, name) for name in REFERENCES]
    for t in range(round((plan.duration + 1.0) / DT)):
        pattern.estimated_com_position.set(position)
        pattern.estimated_com_velocity.set(velocity)
        started = time.perf_counter()
        for reader in readers:
            reader(t)
        elapsed = (time.perf_counter() - started) * 1e6
        com_plan, zmp = pattern.com_plan(t), pattern.zmp(t)
        if com_plan.replan_tick == t:
            run["tick_replan_us"].append(elapsed)
            run["replan_us"].append(com_plan.solve_time * 1e6)
            run["iterations"].append(com_plan.iterations)
            run["statuses"].add(int(com_plan.status))
        else:
            run["tick_us"].append(elapsed)
        run["zmp_error"].append(zmp[:2] - plan.zmp_reference([t * DT])[0])
        graph.step()
        offset = position[:2] - zmp[:2]  # the LIPM over one tick, the ZMP held: exact
        position[:2], velocity[:2] = (zmp[:2] + offset * cosh + velocity[:2] * sinh / omega,
                                      offset * omega * sinh + velocity[:2] * cosh)
    run["final_com_error_mm"] = float(1e3 * np.linalg.norm(position[:2] - plan.final_midpoint()[:2]))
    run["zmp_rms_mm"] = (1e3 * np.sqrt(np.mean(np.square(run.pop("zmp_error")), axis=0))).tolist()
    run["statuses"] = sorted(run["statuses"])
    run["faults"] = graph.fault_log.degraded_ticks
    run["ticks"] = t + 1
    return run


def statistics(samples: list[float], cal: dict) -> dict[str, float]:
    """Median and p99 in µs and in calibration loops."""
    median, p99 = float(np.median(samples)), float(np.percentile(samples, 99))
    return {"median_us": median, "p99_us": p99, "median_loops": in_loops(median * 1e3, cal),
            "p99_loops": in_loops(p99 * 1e3, cal), "count": len(samples)}


def main() -> None:
    """Run the rounds, print the table, keep the numbers."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--length", type=float, default=0.2, help="step length in m (thesis: 0.2 and 0.6)")
    parser.add_argument("--period", type=float, default=0.005, help="s between re-plans (thesis: 0.005)")
    parser.add_argument("--rounds", type=int, default=3, help="closed-loop runs of the whole walk")
    parser.add_argument("--json", type=Path, help="write the numbers to this file")
    args = parser.parse_args()
    before = calibrate()
    com = standing_com()
    busy = BusyMeter().start()
    runs = [walk(args.length, args.period, com) for _ in range(args.rounds)]
    load = busy.stop()
    after = calibrate()
    pooled = {key: [x for run in runs for x in run[key]]
              for key in ("replan_us", "iterations", "tick_replan_us", "tick_us")}
    table = {"re-plan (assembly + ProxQP)": statistics(pooled["replan_us"], before),
             "tick that re-plans (7 outputs)": statistics(pooled["tick_replan_us"], before),
             "tick between re-plans (7 outputs)": statistics(pooled["tick_us"], before)}
    print(f"ZmpPatternGenerator, TALOS straight walk of {args.length} m steps, re-plan every {args.period * 1e3:g} ms, "
          f"{args.rounds} rounds of {runs[0]['ticks']} ticks\n")
    print("| | median µs | p99 µs | median (loops) | p99 (loops) | count |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, s in table.items():
        print(f"| {name} | {s['median_us']:.1f} | {s['p99_us']:.1f} | {s['median_loops']:.0f} | {s['p99_loops']:.0f} "
              f"| {s['count']} |")
    iterations = pooled["iterations"]
    print(f"\nProxQP iterations per re-plan: mean {np.mean(iterations):.2f}, max {max(iterations)}")
    last = runs[-1]
    print(f"outcome: statuses {last['statuses']}, degraded ticks {last['faults']}, final CoM "
          f"{last['final_com_error_mm']:.3f} mm from the final midpoint, planned ZMP vs the plan's reference RMS "
          f"x {last['zmp_rms_mm'][0]:.1f} mm, y {last['zmp_rms_mm'][1]:.1f} mm")
    print(f"\nbefore: {calibration_line(before)}\nafter:  {calibration_line(after)}")
    print(f"other processes kept {load:.2f} CPUs busy meanwhile; command: `.venv/bin/python bench/walking_mpc.py "
          f"{' '.join(sys.argv[1:])}`")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"arguments": vars(args), "calibration": [before, after], "load": load,
                                         "table": table, "iterations_mean": float(np.mean(iterations)),
                                         "iterations_max": int(max(iterations)),
                                         "runs": [{k: v for k, v in run.items() if not k.endswith("_us")}
                                                  for run in runs]}, indent=1, default=str))


if __name__ == "__main__":
    main()
