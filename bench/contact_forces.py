"""The soles' force variables: four corner forces (Contact6d ``forces: corners``, the default)
against the 6D wrench in their wrench cone (``forces: wrench``), on recorded sway ticks.

    python bench/contact_forces.py [--ticks 1000] [--warmup 1500] [--rounds 3] [--closed-loop S] [--json PATH]

1. For each mode, run ``graphs/talos_sway.yaml`` (its four tasks and two feet, Rerun off) for
   ``--warmup`` ticks, then copy the solver's inputs at each of ``--ticks`` ticks (the
   contacts' constant rows stay the same arrays, as in the loop).
2. Replay each recording through a fresh :class:`InverseDynamicsQP` at the library's settings,
   tick after tick (warm-started, as in the loop), ``--rounds`` times with the two modes
   alternating (A/B/A/B). Reported per mode and round: the median and p99 of the solver's time
   (assembly + ProxQP, ``solution.solve_time``), the mean ProxQP iterations, the mean number of
   active inequality rows (a nonzero multiplier) and the share of ticks with one; the ratio
   wrench / corners of the best rounds; the problem sizes; the calibration before and after.

3. With ``--closed-loop S``: S seconds of the sway in MuJoCo per mode (recorder in memory, Rerun
   off), for what the modes do to the robot: how far each sole crept on the floor between the
   first and the last tick (MuJoCo's state, the sole frames placed by Pinocchio), the
   estimator's largest base-position error, the CoM tracking RMS (true CoM against its
   reference, every 10th tick), the mean lateral (world y) force of each sole, and, for
   information only (one run per mode), the loop's median time per tick over 100-tick chunks.

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
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))

from calibration import calibrate, calibration_line, single_threaded  # noqa: E402

single_threaded()

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

import dgraph as dg  # noqa: E402
from dgraph.control import SOLVED  # noqa: E402
from dgraph.control.inverse_dynamics import InverseDynamicsQP  # noqa: E402
from dgraph.entities.robot import load_model  # noqa: E402

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
    times, iterations, active = [], [], []
    for tick, (mass_matrix, bias_forces, tasks, contacts) in enumerate(problems):
        solution = qp.solve(mass_matrix, bias_forces, tasks, contacts, tick)
        if solution.status != SOLVED:
            raise RuntimeError(f"tick {tick}: status {solution.status}")
        times.append(solution.solve_time * 1e6)
        iterations.append(solution.iterations)
        active.append(np.count_nonzero(qp.workspace(contacts, False).free.latest[2]))  # rows with a multiplier
    times = times[10:]  # the first solves start cold
    return {"median_us": statistics.median(times), "p99_us": float(np.percentile(times, 99)),
            "iterations": float(np.mean(iterations)), "active_rows": float(np.mean(active)),
            "ticks_with_active_rows": float(np.mean(np.array(active) > 0))}


SOLES = ("left_sole_link", "right_sole_link")


def closed_loop(mode: str, seconds: float) -> dict[str, object]:
    """The sway in MuJoCo for ``seconds`` with ``forces: mode``: the soles' creep, the estimator's
    base error, the CoM tracking RMS, the mean lateral sole forces, the loop's time per tick."""
    overrides = {"left_foot.forces": mode, "right_foot.forces": mode, "recorder.rerun": "off", "view.rerun": "off"}
    graph = dg.load(str(ROOT / "graphs" / "talos_sway.yaml"), overrides)
    chunks = []
    with graph:
        for _ in range(round(seconds / graph.dt) // 100):
            start = time.perf_counter()
            graph.run(ticks=100, progress=False)
            chunks.append((time.perf_counter() - start) / 100)
        data = graph["recorder"].data()
    truth, estimate = data["device.q"], data["estimator.q"]
    model = load_model("talos")
    pin_data = model.createData()

    def soles(q: np.ndarray) -> np.ndarray:
        pin.framesForwardKinematics(model, pin_data, q)
        return np.array([pin_data.oMf[model.getFrameId(name)].translation for name in SOLES])

    creep = soles(truth[-1]) - soles(truth[0])
    com = []
    for q in truth[::10]:
        pin.centerOfMass(model, pin_data, q)
        com.append(pin_data.com[0].copy())
    com_error = np.array(com) - data["com_reference.output"][::10]
    wrenches = data["solver.contact_wrenches"]
    return {"sole_creep_mm": {name: (1000 * creep[i]).round(2).tolist() for i, name in enumerate(SOLES)},
            "estimator_base_error_mm": float(1000 * np.abs(estimate[:, :3] - truth[:, :3]).max()),
            "com_rms_mm": float(1000 * np.sqrt((com_error**2).sum(axis=1).mean())),
            "mean_lateral_force_N": wrenches[:, :, 1].mean(axis=0).round(2).tolist(),
            "fallen": bool(data["device.fallen"].any()), "tick_us": 1e6 * statistics.median(chunks)}


def print_closed_loop(loops: dict[str, dict[str, object]], seconds: float) -> None:
    print(f"\nclosed loop: {seconds:g} s of the sway in MuJoCo per mode\n")
    print("| mode | left sole creep x, y mm | right sole creep x, y mm | estimator base error mm | CoM RMS mm "
          "| mean lateral force left, right N | fallen | loop µs per tick (one run) |")
    print("|---|---|---|---:|---:|---|---|---:|")
    for mode, run in loops.items():
        left, right = (run["sole_creep_mm"][name] for name in SOLES)
        print(f"| {mode} | {left[0]:.2f}, {left[1]:.2f} | {right[0]:.2f}, {right[1]:.2f} | "
              f"{run['estimator_base_error_mm']:.2f} | {run['com_rms_mm']:.3f} | "
              f"{run['mean_lateral_force_N'][0]:.1f}, {run['mean_lateral_force_N'][1]:.1f} | {run['fallen']} | "
              f"{run['tick_us']:.0f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=1000)
    parser.add_argument("--warmup", type=int, default=1500)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--closed-loop", type=float, default=0.0, metavar="S",
                        help="also run S seconds of the sway in MuJoCo per mode")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    before = calibrate()
    recordings = {mode: record(mode, args.ticks, args.warmup) for mode in MODES}
    rounds: dict[str, list[dict[str, float]]] = {mode: [] for mode in MODES}
    for _ in range(args.rounds):
        for mode in MODES:
            rounds[mode].append(replay(*recordings[mode]))
    loops = {mode: closed_loop(mode, args.closed_loop) for mode in MODES} if args.closed_loop > 0 else {}
    after = calibrate()
    print(f"{args.ticks} recorded sway ticks per mode (after {args.warmup}), {args.rounds} rounds, alternating\n")
    print("| mode | variables | round | solver median µs | p99 µs | ProxQP iterations | active rows | "
          "ticks with active rows |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for mode in MODES:
        for i, run in enumerate(rounds[mode], start=1):
            print(f"| {mode} | {recordings[mode][1]['variables']} | {i} | {run['median_us']:.1f} | "
                  f"{run['p99_us']:.1f} | {run['iterations']:.2f} | {run['active_rows']:.2f} | "
                  f"{100 * run['ticks_with_active_rows']:.0f} % |")
    best = {mode: min(run["median_us"] for run in rounds[mode]) for mode in MODES}
    print(f"\nbest rounds: corners {best['corners']:.1f} µs, wrench {best['wrench']:.1f} µs; "
          f"ratio wrench / corners {best['wrench'] / best['corners']:.2f}")
    if loops:
        print_closed_loop(loops, args.closed_loop)
    print(f"\n{calibration_line(before)}\n{calibration_line(after)}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"calibration": [before, after], "rounds": rounds, "best": best,
                                         "closed_loop": loops,
                                         "variables": {m: recordings[m][1]["variables"] for m in MODES}}, indent=1))


if __name__ == "__main__":
    main()
