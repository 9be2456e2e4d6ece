"""Closed-loop quality of the TALOS graphs in MuJoCo: drift, CoM tracking, forces, estimator.

    .venv/bin/python bench/talos_closed_loop.py [--graphs talos_standing talos_sway]

Runs each graph file for its full duration with its recorder (.npz only) and prints, against
the simulator's ground truth: base drift, CoM tracking error (true CoM from ``device.q``), mean
vertical contact force over m g (MuJoCo's contact forces and the QP's), estimator position
error, worst torque over its limit, QP failures, falls, median QP iterations and solve time, and
the real-time factor of the whole loop (recording included). ``docs/control.md`` §9 quotes it.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.entities.robot import load_model

ROOT = Path(__file__).resolve().parents[1]


def metrics(name: str) -> dict[str, float]:
    """Run graphs/<name>.yaml and measure it."""
    graph = dg.load(str(ROOT / "graphs" / f"{name}.yaml"), {"recorder.rerun": "off", "view.rerun": "off"})
    start = time.perf_counter()
    with graph:
        graph.run(duration=graph.duration, progress=False)
    wall = time.perf_counter() - start
    data = graph["recorder"].data()
    model = load_model("talos")
    pin_data = model.createData()
    truth = data["device.q"]
    com = np.array([pin.centerOfMass(model, pin_data, q).copy() for q in truth])
    error = com - data["com_reference.output"]
    weight = sum(i.mass for i in model.inertias) * 9.81
    base = truth[:, :3]
    return {
        "simulated_s": graph.t * graph.dt, "real_time_factor": graph.t * graph.dt / wall,
        "base_drift_mm": 1e3 * np.linalg.norm(base - base[0], axis=1).max(),
        "com_rms_mm": 1e3 * np.sqrt((error**2).sum(axis=1).mean()), "com_max_mm": 1e3 * np.abs(error).max(),
        "fz_mujoco_over_mg": data["device.contact_force_total"][:, 2].mean() / weight,
        "fz_qp_over_mg": data["solver.normal_force_total"].mean() / weight,
        "estimator_position_error_mm": 1e3 * np.abs(data["estimator.q"][:, :3] - base).max(),
        "torque_over_limit_max": float((np.abs(data["solver.tau"]) / model.effortLimit[6:]).max()),
        "qp_failures": int((data["solver.status"] != 0).sum()), "fallen": bool(data["device.fallen"].any()),
        "qp_iterations_median": float(np.median(data["solver.iterations"])),
        "qp_solve_us_median": float(np.median(data["solver.solve_time"]) * 1e6),
    }


def main() -> None:
    """Print one markdown table, one column per graph."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--graphs", nargs="+", default=["talos_standing", "talos_sway"])
    args = parser.parse_args()
    results = {name: metrics(name) for name in args.graphs}
    print("| metric | " + " | ".join(results) + " |")
    print("|---|" + "---|" * len(results))
    for key in next(iter(results.values())):
        cells = [f"{r[key]:.4g}" if isinstance(r[key], float) else str(r[key]) for r in results.values()]
        print(f"| {key} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
