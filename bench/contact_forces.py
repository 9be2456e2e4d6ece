"""The soles' force variables: four corner forces (Contact6d ``forces: corners``, the default)
against the 6D wrench in their wrench cone (``forces: wrench``), on recorded sway ticks.

    python bench/contact_forces.py [--ticks 1000] [--warmup 1500] [--rounds 3] [--json PATH]

1. For each mode, run ``graphs/talos_sway.yaml`` (its four tasks and two feet, Rerun off) for
   ``--warmup`` ticks, then copy the solver's inputs at each of ``--ticks`` ticks (the
   contacts' constant rows stay the same arrays, as in the loop).
2. Replay each recording through a fresh :class:`InverseDynamicsQP` at the library's settings,
   tick after tick (warm-started, as in the loop), ``--rounds`` times with the two modes
   alternating (A/B/A/B). Reported per mode and round: the median and p99 of the solver's time
   (assembly + ProxQP, ``solution.solve_time``) and the mean ProxQP iterations; the ratio
   wrench / corners of the best rounds; the problem sizes; the calibration before and after.

The two recordings come from two closed loops (the modes' answers differ where a corner
pyramid binds, see docs/control.md), so they are the same scenario, not the same states.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))

from calibration import calibrate, calibration_line, single_threaded  # noqa: E402

single_threaded()

import numpy as np  # noqa: E402

import dgraph as dg  # noqa: E402
from dgraph.entities.solvers import InverseDynamicsQP  # noqa: E402
from dgraph.entities.solvers.inverse_dynamics_qp import SOLVED  # noqa: E402

MODES = ("corners", "wrench")


def record(mode: str, ticks: int, warmup: int) -> tuple[list[tuple], dict]:
    """The solver's inputs at ``ticks`` ticks of the sway with ``forces: mode`` (copies of what
    changes from tick to tick), and the solver's sizes."""
    overrides = {"left_foot.forces": mode, "right_foot.forces": mode, "recorder.rerun": "off", "view.rerun": "off"}
    with tempfile.TemporaryDirectory() as tmp:
        graph = dg.load(str(ROOT / "graphs" / "talos_sway.yaml"), {**overrides, "recorder.rrd_path": f"{tmp}/x.rrd"})
        with graph:
            graph.run(ticks=warmup, progress=False)
            solver, robot, problems = graph["solver"], graph["robot"], []
            originals: list[object] = [None] * len(solver._task_inputs)  # each task's last matrix, and its copy
            copies: list[np.ndarray | None] = [None] * len(solver._task_inputs)
            for _ in range(ticks):
                t = graph.t
                state = robot.state(t)
                tasks = []
                for i, task in enumerate(inp(t) for inp in solver._task_inputs):
                    if task.matrix is not originals[i]:  # a steady task's matrix stays one array, as in the loop
                        originals[i], copies[i] = task.matrix, task.matrix.copy()
                    tasks.append(dataclasses.replace(task, matrix=copies[i], vector=task.vector.copy()))
                contacts = [dataclasses.replace(c, jacobian=c.jacobian.copy(), motion_rhs=c.motion_rhs.copy())
                            for c in (inp(t) for inp in solver._contact_inputs) if c.active]
                problems.append((state.mass_matrix.copy(), state.bias_forces.copy(), tasks, contacts))
                graph.run(ticks=1, progress=False)
            info = {"nv": solver.nv, "n_unactuated": solver.n_unactuated, "effort_limit": solver._qp.effort_limit,
                    "variables": solver.nv + sum(c.n_forces for c in problems[-1][3])}
    return problems, info


def replay(problems: list[tuple], info: dict) -> dict[str, float]:
    """One pass of a fresh solver over the recording: median and p99 time (µs), mean iterations."""
    qp = InverseDynamicsQP(info["nv"], info["n_unactuated"], info["effort_limit"])
    times, iterations = [], []
    for tick, (mass_matrix, bias_forces, tasks, contacts) in enumerate(problems):
        solution = qp.solve(mass_matrix, bias_forces, tasks, contacts, tick)
        if solution.status != SOLVED:
            raise RuntimeError(f"tick {tick}: status {solution.status}")
        times.append(solution.solve_time * 1e6)
        iterations.append(solution.iterations)
    times = times[10:]  # the first solves start cold
    return {"median_us": statistics.median(times), "p99_us": float(np.percentile(times, 99)),
            "iterations": float(np.mean(iterations))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=1000)
    parser.add_argument("--warmup", type=int, default=1500)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    before = calibrate()
    recordings = {mode: record(mode, args.ticks, args.warmup) for mode in MODES}
    rounds: dict[str, list[dict[str, float]]] = {mode: [] for mode in MODES}
    for _ in range(args.rounds):
        for mode in MODES:
            rounds[mode].append(replay(*recordings[mode]))
    after = calibrate()
    print(f"{args.ticks} recorded sway ticks per mode (after {args.warmup}), {args.rounds} rounds, alternating\n")
    print("| mode | variables | round | solver median µs | p99 µs | ProxQP iterations |")
    print("|---|---:|---:|---:|---:|---:|")
    for mode in MODES:
        for i, run in enumerate(rounds[mode], start=1):
            print(f"| {mode} | {recordings[mode][1]['variables']} | {i} | {run['median_us']:.1f} | "
                  f"{run['p99_us']:.1f} | {run['iterations']:.2f} |")
    best = {mode: min(run["median_us"] for run in rounds[mode]) for mode in MODES}
    print(f"\nbest rounds: corners {best['corners']:.1f} µs, wrench {best['wrench']:.1f} µs; "
          f"ratio wrench / corners {best['wrench'] / best['corners']:.2f}")
    print(f"\n{calibration_line(before)}\n{calibration_line(after)}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"calibration": [before, after], "rounds": rounds, "best": best,
                                         "variables": {m: recordings[m][1]["variables"] for m in MODES}}, indent=1))


if __name__ == "__main__":
    main()
