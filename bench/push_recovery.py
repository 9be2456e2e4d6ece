"""The largest push each controller survives on TALOS in MuJoCo: MPTC, the ID solver and the energy-tank passive ID.

    .venv/bin/python bench/push_recovery.py [--controllers mptc id tank mptc_sensed] [--pushes swing_foot ...]
        [--high 1500] [--tolerance 0.05] [--workers N | --ray [ADDRESS]] [--out out/push] [--fresh]
        [--plots docs] [--no-timing]

Every (controller, push) pair is a file of ``graphs/push/`` (the controller's graph plus one push
layer: a ``Pulse`` wrench on a body, its magnitude ``push.magnitude`` the one scalar bisected;
``mptc_sensed``, MPTC with each foot's contact flag from the plan and its ankle F/T sensor, has the
walking pushes only: it has no standing graph). One
:mod:`dgraph.sweep` bisects that magnitude in every file at once, from 0 N (must survive) to
``--high`` (must fall), to the relative ``--tolerance``; a run survives when ``device.fallen``
never turns true before its end (walking pushes: the end of the walk, 11 s, 6.555 s after the
push; standing: 8 s, 6.7 s after it). Each run is a fresh process; the table
(``--out``/push_sweep.csv) is written as runs end, so a second call reuses every run already made
(``--fresh`` starts over) and ``--ray`` sends the runs to a Ray cluster.

Prints, as markdown: the thresholds (largest surviving force and its impulse over the 0.3 s push,
the smallest failing force and its fall time; "falls unpushed" when 0 N already falls), the
MPTC / ID ratio per push against the report's 1.4-2x, the tasks, weights and gains of each
controller (read from its graph, so the doc states what ran), and, unless ``--no-timing``, the
median solver time and control tick of each walk over its first 2 s in this process, with the
calibration figure beside them (bench/calibration.py). With ``--plots`` it draws
``push_recovery_thresholds.png`` (the thresholds as bars) and ``push_recovery_torso_x.png`` (the
true base path of MPTC and the ID solver under the smallest torso push that fells the ID solver).
"""

from __future__ import annotations

import calibration

if __name__ == "__main__":  # not in the sweep's process server, which imports this file again (and numpy first)
    calibration.single_threaded()  # before numpy: one BLAS/OpenMP thread, as the other benchmarks

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import dgraph as dg
import dgraph.loop
from dgraph.sweep import Bisection, Sweep, Threshold, run_sweep

ROOT = Path(__file__).resolve().parents[1]
CONTROLLERS = {"mptc": "MPTC", "id": "ID solver", "tank": "energy-tank passive ID",
               "mptc_sensed": "MPTC, sensed contact flags"}
WALKS = {"mptc": "talos_walk_20cm_mptc", "id": "talos_walk_20cm", "tank": "talos_walk_20cm_tank",
         "mptc_sensed": "talos_walk_20cm_mptc_sensed"}
PUSHES = {"swing_foot": "(a) right swing foot, -x", "torso_x": "(b) torso, x", "torso_y": "(b) torso, y",
          "torso_xy": "(b) torso, [F, F, 0]", "pelvis_standing": "(c) pelvis, x, standing"}
PUSH_DURATION = 0.3  # s, every push layer's
KEY = "push.magnitude"
MEASURES = ("device.q[0]", "device.q[1]")
TIMING_TICKS = 2000


def push_file(controller: str, push: str) -> str:
    """The graph file of a (controller, push) pair, relative to the repository (the sweep's run identity)."""
    return f"graphs/push/{controller}_{push}.yaml"


def sweep(args: argparse.Namespace) -> list[Threshold]:
    """Every (controller, push) pair that has a file (the sensed contact flags have no standing graph)."""
    files = [push_file(c, p) for c in args.controllers for p in args.pushes if (ROOT / push_file(c, p)).exists()]
    spec = Sweep(files, bisection=Bisection(KEY, 0.0, args.high, args.tolerance), measures=list(MEASURES))
    result = run_sweep(spec, Path(args.out) / "push_sweep.csv", ray=args.ray or False, workers=args.workers,
                       fresh=args.fresh, plot=Path(args.out) / "push_sweep.png")
    print(result.summary())
    return result.thresholds


def how_it_failed(threshold: Threshold, value: float | None) -> str:
    """How the cell's run at ``value`` failed: its fall time, or its status (an error, a timeout...)."""
    for outcome in threshold.outcomes:
        if value is not None and float(outcome.run.settings[KEY]) == value:
            return f"{outcome.fall_time:.2f} s" if outcome.fall_time is not None else outcome.status
    return "not run"


def cell_text(threshold: Threshold) -> str:
    """One table cell: the largest surviving force (its impulse), the smallest failing force (fall time)."""
    if threshold.verdict == "fails low":
        return f"falls unpushed ({how_it_failed(threshold, 0.0)})"
    if threshold.verdict == "survives high":
        return f"survives {threshold.largest_surviving:.0f} N (the bracket's top)"
    survived, failed = threshold.largest_surviving, threshold.smallest_failing
    return (f"{survived:.0f} N ({survived * PUSH_DURATION:.0f} N s); falls at {failed:.0f} N "
            f"({how_it_failed(threshold, failed)})")


def threshold_table(thresholds: list[Threshold], controllers: list[str], pushes: list[str]) -> str:
    by_file = {t.cell.file: t for t in thresholds}
    lines = ["| push | " + " | ".join(CONTROLLERS[c] for c in controllers) + " | MPTC / ID |",
             "|---|" + "---|" * (len(controllers) + 1)]
    for push in pushes:
        cells = [cell_text(by_file[push_file(c, push)]) if push_file(c, push) in by_file else "not run"
                 for c in controllers]
        lines.append(f"| {PUSHES[push]} | " + " | ".join(cells) + f" | {ratio_text(by_file, push)} |")
    return "\n".join(lines)


def ratio_text(by_file: dict[str, Threshold], push: str) -> str:
    """MPTC's largest surviving force over the ID solver's, with the bracket the 5 % leaves."""
    mptc, reference = by_file.get(push_file("mptc", push)), by_file.get(push_file("id", push))
    if mptc is None or reference is None or "found" not in (mptc.verdict, reference.verdict):
        return "-"
    if not reference.largest_surviving:
        return "-"
    low = mptc.largest_surviving / reference.smallest_failing
    high = (mptc.smallest_failing or mptc.largest_surviving) / reference.largest_surviving
    return f"{mptc.largest_surviving / reference.largest_surviving:.2f} ({low:.2f}-{high:.2f})"


def gains_table(controllers: list[str]) -> str:
    """Each controller's solver, and its tasks' weights and gains as its walking graph sets them."""
    lines = ["| controller | solver | task: weight, kp, kd | swing weight; contacts kp, kd |", "|---|---|---|---|"]
    for controller in controllers:
        graph = dg.load(ROOT / "graphs" / f"{WALKS[controller]}.yaml", {"recorder.rerun": "off"})
        solver = graph["solver"]
        tasks = [task_gains(graph, name) for name in solver.tasks]
        feet = f"{graph['schedule'].swing_weight:g}; {_constant(graph['left_foot'], 'kp')}, " \
               f"{_constant(graph['left_foot'], 'kd')}"
        lines.append(f"| {CONTROLLERS[controller]} | {solver.type_name} | {'; '.join(tasks)} | {feet} |")
    return "\n".join(lines)


def task_gains(graph: dg.Graph, name: str) -> str:
    task = graph[name]
    values = {port: _constant(task, port) for port in ("weight", "kp", "kd") if port in task.inputs}
    kd = "2 sqrt(kp)" if task.params.get("critical_damping") else values.get("kd")
    return f"{name}: {values['weight']}, {values['kp']}, {kd}"


def _constant(entity: dg.Entity, port: str) -> str:
    signal = entity.inputs[port]
    if signal.source is not None:
        return f"from {signal.source.full_name}"
    value = np.asarray(signal(0), dtype=float)
    if value.ndim == 0 or np.all(value == value.flat[0]):
        return f"{float(value.flat[0]):g}"
    return f"per joint {value.min():g}-{value.max():g}"


def timing(controllers: list[str]) -> str:
    """Median solver time and whole-tick time over the first ``TIMING_TICKS`` of each walk."""
    cal = calibration.calibrate()
    lines = [calibration.calibration_line(cal), "",
             "| controller | solver (median) | tick with MuJoCo (median) |", "|---|---|---|"]
    for controller in controllers:
        graph = dg.load(ROOT / "graphs" / f"{WALKS[controller]}.yaml", {"recorder.rerun": "off"})
        solver, ticks, solves = graph["solver"], [], []
        with graph:
            for _ in range(TIMING_TICKS):
                start = time.perf_counter()
                dgraph.loop.step(graph)
                ticks.append(time.perf_counter() - start)
                solves.append(solver.solve_time(graph.t - 1))
        lines.append(f"| {CONTROLLERS[controller]} | {1e3 * statistics.median(solves):.3f} ms | "
                     f"{1e3 * statistics.median(ticks):.3f} ms |")
    return "\n".join(lines)


def plots(thresholds: list[Threshold], controllers: list[str], pushes: list[str], folder: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    by_file = {t.cell.file: t for t in thresholds}
    figure, axis = plt.subplots(figsize=(9, 4))
    width = 0.8 / len(controllers)
    for i, controller in enumerate(controllers):
        cells = [by_file.get(push_file(controller, p)) for p in pushes]
        positions = np.arange(len(pushes)) + i * width
        axis.bar(positions, [(cell.largest_surviving or 0.0) if cell else 0.0 for cell in cells], width,
                 label=CONTROLLERS[controller])
        for position, cell in zip(positions, cells, strict=True):
            if cell is None:
                axis.text(position, 2.0, "not run", ha="center", va="bottom", fontsize=6, rotation=90)
            elif cell.verdict == "fails low":
                axis.text(position, 2.0, "falls\nunpushed", ha="center", va="bottom", fontsize=6, rotation=90)
    axis.set_xticks(np.arange(len(pushes)) + 0.4 - width / 2, [PUSHES[p] for p in pushes], fontsize=8)
    axis.set_ylabel("largest push survived (N, 0.3 s)")
    axis.legend()
    figure.tight_layout()
    figure.savefig(folder / "push_recovery_thresholds.png", dpi=110)
    reference = by_file.get(push_file("id", "torso_x"))
    if reference is not None and reference.smallest_failing is not None:
        base_paths(reference.smallest_failing, folder, plt)


def base_paths(force: float, folder: Path, plt) -> None:
    """The true base path of MPTC and the ID solver under the torso push ``force`` (x)."""
    figure, axes = plt.subplots(1, 2, figsize=(9, 3.5))
    for controller in ("mptc", "id"):
        graph = dg.load(ROOT / push_file(controller, "torso_x"), {KEY: force, "recorder.rerun": "off"})
        device, path = graph["device"], []
        with graph:
            for _ in range(round(graph.duration / graph.dt)):
                dgraph.loop.step(graph)
                path.append(device.q(graph.t)[:3].copy())
                if device.fallen(graph.t):
                    break
        path = np.array(path)
        times = np.arange(1, len(path) + 1) * graph.dt
        axes[0].plot(times, path[:, 0], label=CONTROLLERS[controller])
        axes[1].plot(times, path[:, 2], label=CONTROLLERS[controller])
    for axis, label in zip(axes, ("base x (m)", "base z (m)"), strict=True):
        axis.axvspan(4.145, 4.445, color="0.85")
        axis.set_xlabel("t (s)")
        axis.set_ylabel(label)
    axes[0].legend()
    figure.suptitle(f"torso pushed along x with {force:.0f} N for 0.3 s (grey)", fontsize=9)
    figure.tight_layout()
    figure.savefig(folder / "push_recovery_torso_x.png", dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--controllers", nargs="+", choices=list(CONTROLLERS), default=list(CONTROLLERS))
    parser.add_argument("--pushes", nargs="+", choices=list(PUSHES), default=list(PUSHES))
    parser.add_argument("--high", type=float, default=1500.0, help="N, a push every controller falls under")
    parser.add_argument("--tolerance", type=float, default=0.05)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--ray", nargs="?", const=True, default=None, help="a local Ray cluster, or its ADDRESS")
    parser.add_argument("--out", default="out/push")
    parser.add_argument("--fresh", action="store_true")
    parser.add_argument("--plots", default=None, help="folder for the PNGs (docs)")
    parser.add_argument("--no-timing", action="store_true")
    args = parser.parse_args()
    Path(args.out).mkdir(parents=True, exist_ok=True)
    thresholds = sweep(args)
    print("\n" + threshold_table(thresholds, args.controllers, args.pushes) + "\n")
    print(gains_table(args.controllers) + "\n")
    if not args.no_timing:
        print(timing(args.controllers) + "\n")
    if args.plots:
        plots(thresholds, args.controllers, args.pushes, Path(args.plots))


if __name__ == "__main__":
    main()
