"""TALOS control tick: dgraph's inverse-dynamics graph against TSID 1.10, in the same run.

    bash bench/setup_tsid.sh            # once: the TSID peer's own venv (.venv-tsid, pin 4.0.0, mujoco)
    .venv/bin/python bench/talos_tick.py [--ticks 3000] [--rounds 3] [--sets bench demo demo+4]
                                         [--json out/talos_tick.json] [--base ddec0a5]

Task sets, the same on both sides (two Contact6d on the soles, 4 corners, mu 0.3, Kp 30, Kd 11,
minimum normal force 1 N, force regularisation 1e-5, in every set):

- ``bench`` (2 tasks, TSID's standing benchmark): CoM (weight 1e3, Kp 20, Kd 3, swaying 5 cm at
  0.5 Hz) and joint posture (weight 0.1, Table 4.3 gains, Kd = 2 sqrt(Kp));
- ``demo`` (4 tasks, those of ``graphs/talos_sway.yaml``): + waist orientation (``base_link``,
  weight 1, Kp 100, Kd 20; TSID: TaskSE3Equality with the orientation mask) and angular
  momentum (weight 0.02, Kp 10, Kd 0; TSID: TaskAMEquality);
- ``demo+4`` (8 tasks): + full poses of both grippers' base frames and orientations of
  ``torso_2_link`` and ``head_2_link`` (weight 0.1, Kp 10, Kd 2 sqrt(10), held at their initial
  pose; ours: FramePose + Task entities added here, TSID: TaskSE3Equality).

Ticks:

- **dgraph tick**: TALOS in MuJoCo (``graphs/talos_sway.py`` with the set's tasks, no recorder).
  A ``before`` hook of the device pulls ``solver.tau(t)`` and times it: the whole control graph
  (FloatingBaseEstimator + RobotModel + features + tasks + contacts + QP assembly and solve,
  plus dgraph's signal overhead), without the simulator (torque limits in the QP when one binds).
- **TSID tick**: ``bench/peer_tsid.py`` in ``.venv-tsid``: ``computeProblemData`` + ``solve``;
  eiquadprog (HQuadProgFast). Measured in the same MuJoCo closed loop as ours (the same model
  of TALOS in the flat scene, saved by ``dgraph_sim.model`` for the peer: its torques drive MuJoCo, its
  state is read back from it), the ratio of the acceptance; and, for information, in TSID's own
  loop (semi-implicit Euler, no simulator between its ticks), where it runs a few per cent
  faster (the simulator's step between two ticks leaves the caches colder for the next one).
- **real-time factor**: simulated time / wall time of the closed loop of the ``bench`` graph
  (control graph + MuJoCo step, no recording), and of the full demo (``graphs/talos_sway.yaml``
  with its recorder and 3D view writing an .rrd into a temporary directory, timed after 200
  warm-up ticks, closing included: bench/compare_commits.py's run), once per round.

Rounds: one warm-up round of both sides (not counted), then ``--rounds`` rounds, each running
every set on our side then on TSID's. Per set and side: each round's median and p99, and the
*best round* (lowest median). A round whose median exceeds 1.5 times the best round of the same
side and set is **anomalous**; it is listed, with ``others busy``, the CPUs that other processes
kept busy during it (calibration.BusyMeter). The headline figures are ratios against TSID in
the same run; absolute times come with the calibration figure (bench/calibration.py) measured
at the start and the end of the run, and in calibration loops.

**Threads, and the first-round anomaly.** libtsid.so and Pinocchio's bindings (and proxsuite on
our side) link libgomp. With the OpenMP defaults, TSID's tick runs parallel regions with a second
thread that spins between them (30-50 % of a vCPU in ``top -H``). On 2 vCPUs, as soon as
another process holds the other vCPU, each parallel region waits for that thread to be scheduled
again: TSID's p99 goes from ~0.3 ms to 10-50 ms and its median, in some rounds, from ~0.2 ms to
several ms (docs/benchmarks.md has the measurements). What was busy was
other jobs on the shared machine (another engineer's tests or a busy loop), not this script: it
sleeps in ``subprocess.run`` while the peer runs. A first round is simply the likeliest to
overlap a job started at the same time. So both sides run with ``OMP_NUM_THREADS``,
``OPENBLAS_NUM_THREADS`` and ``MKL_NUM_THREADS`` set to 1: in this process before numpy is
imported, and in the peer's environment (``--unpinned-peer`` runs the peer with the defaults,
to reproduce the anomaly).

Acceptance (one PASS/FAIL/SKIP line each, at the end): no anomalous round in any set on either
side; our best-round median over TSID's at most 2.0 for ``bench`` and for ``demo``; our p99 at
most 2x our median (best round of ``bench`` and ``demo``); the cost of one more task (slope of
our best-round median over the number of tasks, least squares over the sets run) at most 40 us;
with ``--base COMMIT``, the full demo's real-time factor at least doubles against that commit
(bench/compare_commits.py, base against this working tree, in the same run).
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "graphs"))

import calibration  # noqa: E402
import compare_commits  # noqa: E402

calibration.single_threaded()  # before numpy, Pinocchio and proxsuite read the thread variables

import argparse  # noqa: E402
import copy  # noqa: E402
import importlib.metadata as md  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
import talos_sway  # noqa: E402

import dgraph as dg  # noqa: E402
from dgraph.entities.features import FramePose  # noqa: E402
from dgraph.entities.robot import load_model  # noqa: E402
from dgraph.entities.solvers import InverseDynamicsSolver  # noqa: E402
from dgraph.entities.tasks import Task  # noqa: E402

ANOMALY_FACTOR = 1.5
MAX_RATIO, MAX_P99_OVER_MEDIAN, MAX_TASK_COST_US, MIN_SPEEDUP = 2.0, 2.0, 40.0, 2.0


@dataclass(frozen=True)
class FrameTask:
    """An extra pose task of the 8-task set: frame, mask (x y z rx ry rz), weight and gains."""

    frame: str
    mask: str
    weight: float = 0.1
    kp: float = 10.0
    kd: float = 2.0 * math.sqrt(10.0)


EXTRA_TASKS = {
    "left_hand_task": FrameTask("gripper_left_base_link", "111111"),
    "right_hand_task": FrameTask("gripper_right_base_link", "111111"),
    "torso_task": FrameTask("torso_2_link", "000111"),
    "head_task": FrameTask("head_2_link", "000111"),
}
SETS = {"bench": ("com_task", "posture_task"), "demo": talos_sway.TASKS,
        "demo+4": (*talos_sway.TASKS, *EXTRA_TASKS)}
TSID_BASE = {
    "contacts": {"mu": 0.3, "fMin": 1.0, "fMax": 1000.0, "kp": 30.0, "kd": 11.0, "w_force_reg": 1e-5},
    "com": {"weight": 1000.0, "kp": 20.0, "kd": 3.0, "sway_amplitude": [0.0, 0.05, 0.0], "sway_frequency": 0.5},
    "posture": {"weight": 0.1, "kp": {"legs": [10, 5, 5, 1, 10, 10], "torso": [100, 100],
                                      "arms": [50, 10, 10, 10, 50, 10, 10, 10], "head": [100, 100]}, "kd": None},
    "waist": None,
    "momentum": {"enabled": False},
    "frames": [],
}
PEER_LOOPS = {"tsid": "mujoco", "tsid_euler": "euler"}
"""The peer's runs: in our closed loop (the ratio of the acceptance) and in its own loop."""
TSID_WAIST = {"frame": "base_link", "weight": 1.0, "kp": 100.0, "kd": 20.0, "mask": [0, 0, 0, 1, 1, 1],
              "local_frame": False}
TSID_MOMENTUM = {"enabled": True, "weight": 0.02, "kp": 10.0, "kd": 0.0}


# -- our side ------------------------------------------------------------------------------------
def build(tasks: tuple[str, ...]) -> dg.Graph:
    """The sway graph without recording, with ``tasks`` (of talos_sway.TASKS and EXTRA_TASKS)."""
    graph = talos_sway.build(tasks=tuple(t for t in tasks if t in talos_sway.TASKS), record=False)
    extra = [t for t in tasks if t in EXTRA_TASKS]
    if extra:
        add_frame_tasks(graph, extra)
    return graph


def add_frame_tasks(graph: dg.Graph, names: list[str]) -> None:
    """Add FramePose + Task pairs held at the frames' initial pose, and a solver that has them too."""
    model = load_model("talos")
    data = model.createData()
    pin.framesForwardKinematics(model, data, graph["device"].sim.q0)
    old = graph.remove("solver")
    for name in names:
        spec = EXTRA_TASKS[name]
        feature = graph.add(FramePose(f"{name}_pose", frame=spec.frame, mask=spec.mask))
        placement = data.oMf[model.getFrameId(spec.frame)]
        feature.reference_position.set(placement.translation.copy())
        feature.reference_orientation.set(pin.Quaternion(placement.rotation).coeffs().copy())  # xyzw
        task = graph.add(Task(name))
        task.weight.set(spec.weight)
        task.kp.set(spec.kp)
        task.kd.set(spec.kd)
        graph.plug("robot.state", f"{name}_pose.robot")
        graph.plug(f"{name}_pose.feature", f"{name}.feature")
    graph.add(InverseDynamicsSolver("solver", model="talos", tasks=[*old.tasks, *names], contacts=list(old.contacts)))
    graph.plug("robot.state", "solver.robot")
    for name in (*old.tasks, *names):
        graph.plug(f"{name}.equation", f"solver.{name}")
    for name in old.contacts:
        graph.plug(f"{name}.contact", f"solver.{name}")
    graph.plug("solver.tau", "device.control")


def stats(samples_us: np.ndarray) -> dict[str, float]:
    """Median, p90, p99 and mean of a sample in µs."""
    return {"median": float(np.median(samples_us)), "p90": float(np.percentile(samples_us, 90)),
            "p99": float(np.percentile(samples_us, 99)), "mean": float(samples_us.mean())}


def dgraph_tick(tasks: tuple[str, ...], ticks: int, warmup: int = 200) -> dict[str, object]:
    """Control-graph time per tick in the MuJoCo closed loop, the loop's real-time factor, the load."""
    graph = build(tasks)
    times: list[int] = []
    failures = [0]
    solver = graph["solver"]

    def control(t: int) -> None:
        start = time.perf_counter_ns()
        solver.tau(t)
        times.append(time.perf_counter_ns() - start)
        failures[0] += solver.status(t) != 0

    graph["device"].before.add(control)
    graph.run(ticks=warmup, progress=False)
    times.clear()
    failures[0] = 0
    meter = calibration.BusyMeter().start()
    start = time.perf_counter()
    graph.run(ticks=ticks, progress=False)
    wall = time.perf_counter() - start
    others = meter.stop()
    like_tsid = like_tsid_tick(graph, control, ticks // 2)
    graph.close()
    return {"tasks": list(tasks), "tick_us": stats(np.array(times) / 1e3), "real_time_factor": ticks * graph.dt / wall,
            "loop_us": wall / ticks * 1e6, "qp_failures": failures[0], "fallen": bool(graph["device"].fallen.value),
            "others_busy": others, "like_tsid_tick_us": like_tsid}


def like_tsid_tick(graph: dg.Graph, control: object, ticks: int) -> dict[str, float]:
    """The part of our tick that TSID's timed part covers (computeProblemData + solve: the model,
    tasks, contacts and QP): the same loop continued for ``ticks`` ticks with the estimator's
    outputs and the CoM reference pulled first, untimed. For information only: the acceptance is
    on the whole control graph."""
    graph["device"].before.remove(control)
    solver, upstream = graph["solver"], [graph["estimator.q"], graph["estimator.v"], *(
        graph[f"com_reference.{name}"] for name in ("output", "velocity", "acceleration"))]
    times: list[int] = []

    def timed(t: int) -> None:
        for signal in upstream:
            signal(t)
        start = time.perf_counter_ns()
        solver.tau(t)
        times.append(time.perf_counter_ns() - start)

    graph["device"].before.add(timed)
    graph.run(ticks=ticks, progress=False)
    return stats(np.array(times) / 1e3)


def demo_real_time_factor(ticks: int) -> float:
    """Real-time factor of the full demo (bench/compare_commits.py's run of this tree: recorder, 3D view, .rrd)."""
    return float(compare_commits.run_demo(ROOT, ticks, warmup=200)["real_time_factor"])


# -- TSID ----------------------------------------------------------------------------------------
def simulator_spec(directory: Path) -> dict[str, object]:
    """The MuJoCo closed loop for the peer: our sim's TALOS in the flat scene saved into
    ``directory`` as a binary model, its start configuration and the joint maps."""
    import mujoco

    from dgraph_sim.model import load

    sim = load("talos")
    path = directory / "talos.mjb"
    mujoco.mj_saveModel(sim.mj_model, str(path), None)
    joints = sim.joint_map
    return {"model": str(path), "q0": sim.q0.tolist(), "qpos_index": joints.qpos_index.tolist(),
            "qvel_index": joints.qvel_index.tolist(), "ctrl_index": joints.ctrl_index.tolist(),
            "free_qpos": int(joints.qpos_index[0]), "free_dof": int(joints.qvel_index[0])}


def tsid_config(tasks: tuple[str, ...], simulator: dict[str, object] | None = None) -> dict[str, object]:
    """The peer's config (peer_tsid.py) for the same task set, in ``simulator`` (None: its own loop)."""
    cfg = copy.deepcopy(TSID_BASE)
    cfg["simulator"] = simulator
    if "posture_task" not in tasks:
        cfg["posture"] = None
    if "waist_task" in tasks:
        cfg["waist"] = TSID_WAIST
    if "momentum_task" in tasks:
        cfg["momentum"] = TSID_MOMENTUM
    cfg["frames"] = [{"name": name, "frame": spec.frame, "mask": [int(c) for c in spec.mask], "weight": spec.weight,
                      "kp": spec.kp, "kd": spec.kd, "local_frame": False}
                     for name, spec in EXTRA_TASKS.items() if name in tasks]
    return cfg


def peer_env(unpinned: bool) -> dict[str, str]:
    """The peer's environment: BLAS/OpenMP on one thread, or (``unpinned``) without those variables."""
    if not unpinned:
        return calibration.single_threaded_env()
    return {k: v for k, v in os.environ.items() if k not in calibration.THREAD_VARIABLES}


def tsid_tick(python: str, tasks: tuple[str, ...], ticks: int, unpinned: bool = False,
              loop: str = "mujoco") -> dict[str, object]:
    """Run the TSID peer in its venv on the same task set, in our MuJoCo closed loop (``loop``
    "mujoco") or its own ("euler"); its JSON report, and the load meanwhile."""
    with tempfile.TemporaryDirectory() as tmp:
        config = Path(tmp) / "tsid_config.json"
        simulator = simulator_spec(Path(tmp)) if loop == "mujoco" else None
        config.write_text(json.dumps(tsid_config(tasks, simulator)))
        meter = calibration.BusyMeter().start()
        out = subprocess.run([python, str(ROOT / "bench" / "peer_tsid.py"), "--ticks", str(ticks),
                              "--config", str(config)], check=True, capture_output=True, text=True,
                             env=peer_env(unpinned))
        others = meter.stop()
    return {**json.loads(out.stdout.strip().splitlines()[-1]), "others_busy": others}


# -- summary -------------------------------------------------------------------------------------
def summarise_side(runs: list[dict[str, object]]) -> dict[str, object]:
    """Best round, anomalous rounds and p99 / median of one side of one set."""
    medians = [r["tick_us"]["median"] for r in runs]
    best = int(np.argmin(medians))
    return {"medians_us": medians, "p99_us": [r["tick_us"]["p99"] for r in runs], "best_round": best + 1,
            "best_median_us": medians[best], "best_p99_over_median": runs[best]["tick_us"]["p99"] / medians[best],
            "anomalous_rounds": [i + 1 for i, m in enumerate(medians) if m > ANOMALY_FACTOR * medians[best]]}


def slope(points: dict[int, float]) -> float | None:
    """Least-squares slope of y over x (None with fewer than two x values)."""
    if len(points) < 2:
        return None
    return float(np.polyfit(list(points), list(points.values()), 1)[0])


def summarise(results: dict[str, dict[str, list]], has_peer: bool) -> dict[str, object]:
    """Per set: both sides' summaries and the best-round ratio; the cost of one more task per side."""
    sets = {}
    for name, sides in results.items():
        entry = {"tasks": len(SETS[name]), "dgraph": summarise_side(sides["dgraph"])}
        if has_peer:
            entry["tsid"] = summarise_side(sides["tsid"])
            entry["ratio"] = entry["dgraph"]["best_median_us"] / entry["tsid"]["best_median_us"]
            entry["tsid_euler"] = summarise_side(sides["tsid_euler"])
            entry["ratio_euler"] = entry["dgraph"]["best_median_us"] / entry["tsid_euler"]["best_median_us"]
        sets[name] = entry
    cost = {side: slope({len(SETS[n]): s[side]["best_median_us"] for n, s in sets.items()})
            for side in ("dgraph", *PEER_LOOPS) if side == "dgraph" or has_peer}
    return {"sets": sets, "task_cost_us": cost}


# -- report --------------------------------------------------------------------------------------
def print_set(name: str, sides: dict[str, list], entry: dict[str, object], cal: dict[str, object]) -> None:
    """One markdown table for a set, and its summary lines."""
    print(f"\n### {name} ({entry['tasks']} tasks: {', '.join(SETS[name])})\n")
    print("| round | dgraph tick median µs | p99 | p99 / median | others busy | closed-loop RTF "
          "| TSID tick median µs (MuJoCo loop) | p99 | others busy | TSID, own loop |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    peers = sides.get("tsid") or [None] * len(sides["dgraph"])
    own = sides.get("tsid_euler") or [None] * len(sides["dgraph"])
    for i, (ours, peer, alone) in enumerate(zip(sides["dgraph"], peers, own, strict=True), 1):
        t = ours["tick_us"]
        peer_cols = (f"{peer['tick_us']['median']:.0f} | {peer['tick_us']['p99']:.0f} | {peer['others_busy']:.2f} "
                     f"| {alone['tick_us']['median']:.0f}" if peer else "- | - | - | -")
        print(f"| {i} | {t['median']:.0f} | {t['p99']:.0f} | {t['p99'] / t['median']:.2f} | {ours['others_busy']:.2f} "
              f"| {ours['real_time_factor']:.2f} | {peer_cols} |")
    ours = entry["dgraph"]
    line = (f"best rounds: dgraph {ours['best_median_us']:.0f} µs "
            f"({calibration.in_loops(ours['best_median_us'] * 1e3, cal):.0f} calibration loops)")
    if "tsid" in entry:
        line += (f", TSID {entry['tsid']['best_median_us']:.0f} µs in the MuJoCo loop; ratio {entry['ratio']:.2f} "
                 f"(TSID in its own loop {entry['tsid_euler']['best_median_us']:.0f} µs: "
                 f"{entry['ratio_euler']:.2f})")
    print(f"\n{line}; our p99 / median {ours['best_p99_over_median']:.2f}")
    best = sides["dgraph"][ours["best_round"] - 1]
    if "tsid" in entry and best.get("like_tsid_tick_us"):
        like = best["like_tsid_tick_us"]["median"]
        print(f"(for information: our tick without the estimator and the CoM reference, the part TSID's timed "
              f"computeProblemData + solve covers, {like:.0f} µs in that round: "
              f"{like / entry['tsid']['best_median_us']:.2f} x TSID)")
    for side in ("dgraph", *PEER_LOOPS):
        if side in entry and entry[side]["anomalous_rounds"]:
            print(f"ANOMALOUS {side} rounds (median > {ANOMALY_FACTOR}x the best): {entry[side]['anomalous_rounds']}")
    failures = [r["qp_failures"] for r in sides["dgraph"]]
    if any(failures) or any(r["fallen"] for r in sides["dgraph"]):
        print(f"warning: our QP failed {failures} times per round, fallen {[r['fallen'] for r in sides['dgraph']]}")
    for peer in sides.get("tsid", []):
        if peer["failures"] or peer["base_height_min_m"] < 0.5:
            print(f"warning: TSID in MuJoCo: {peer['failures']} failed solves, lowest base height "
                  f"{peer['base_height_min_m']:.2f} m")


def print_scaling(summary: dict[str, object]) -> None:
    """Tick against the number of tasks, and the slope, per side."""
    sets = summary["sets"]
    print("\n### Tick against the number of tasks (best rounds)\n")
    print("| tasks | set | dgraph µs | TSID µs (MuJoCo loop) | TSID µs (own loop) |\n|---:|---|---:|---:|---:|")
    for name, entry in sorted(sets.items(), key=lambda item: item[1]["tasks"]):
        peer = (f"{entry['tsid']['best_median_us']:.0f} | {entry['tsid_euler']['best_median_us']:.0f}"
                if "tsid" in entry else "- | -")
        print(f"| {entry['tasks']} | {name} | {entry['dgraph']['best_median_us']:.0f} | {peer} |")
    cost = ", ".join(f"{side} {value:.1f} µs" if value is not None else f"{side} - (needs two sets)"
                     for side, value in summary["task_cost_us"].items())
    print(f"\ncost of one more task (least-squares slope): {cost}")


def verdict(ok: bool | None, text: str) -> tuple[str, str]:
    """A (PASS|FAIL|SKIP, text) pair."""
    return ("SKIP" if ok is None else "PASS" if ok else "FAIL", text)


def acceptance(summary: dict[str, object], speedup: float | None) -> list[tuple[str, str]]:
    """The issue's criteria, one verdict each."""
    sets = summary["sets"]
    anomalies = {f"{n} {side}": e[side]["anomalous_rounds"] for n, e in sets.items()
                 for side in ("dgraph", *PEER_LOOPS) if side in e and e[side]["anomalous_rounds"]}
    lines = [verdict(not anomalies, f"no anomalous round (median > {ANOMALY_FACTOR}x the side's best): "
                     + (", ".join(f"{k} rounds {v}" for k, v in anomalies.items()) or "none"))]
    for name in ("bench", "demo"):
        ratio = sets.get(name, {}).get("ratio")
        lines.append(verdict(None if ratio is None else ratio <= MAX_RATIO,
                             f"{name}: best-round tick median dgraph / TSID (in the same MuJoCo loop) "
                             f"{'-' if ratio is None else f'{ratio:.2f}'} <= {MAX_RATIO}"))
    spread = {n: sets[n]["dgraph"]["best_p99_over_median"] for n in ("bench", "demo") if n in sets}
    lines.append(verdict(all(v <= MAX_P99_OVER_MEDIAN for v in spread.values()) if spread else None,
                         f"our p99 / median <= {MAX_P99_OVER_MEDIAN} (best rounds): "
                         + (", ".join(f"{n} {v:.2f}" for n, v in spread.items()) or "-")))
    cost = summary["task_cost_us"]["dgraph"]
    lines.append(verdict(None if cost is None else cost <= MAX_TASK_COST_US,
                         f"cost of one more task {'-' if cost is None else f'{cost:.1f}'} µs <= {MAX_TASK_COST_US} µs"))
    lines.append(verdict(None if speedup is None else speedup >= MIN_SPEEDUP,
                         f"full demo real-time factor, this tree / base: "
                         f"{'- (use --base COMMIT)' if speedup is None else f'{speedup:.2f}'} >= {MIN_SPEEDUP}"))
    return lines


def versions() -> dict[str, str]:
    """Our side's package versions."""
    return {name: md.version(name) for name in ("numpy", "pin", "proxsuite", "mujoco", "scipy")}


# -- main ----------------------------------------------------------------------------------------
def parse_args() -> argparse.Namespace:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=3000, help="timed ticks per round and side")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--sets", nargs="+", choices=list(SETS), default=list(SETS))
    parser.add_argument("--peer", default=str(ROOT / ".venv-tsid" / "bin" / "python"), help="TSID venv python")
    parser.add_argument("--unpinned-peer", action="store_true",
                        help="run TSID with the OpenMP/BLAS thread defaults (reproduces the anomaly)")
    parser.add_argument("--base", help="also compare the full demo's real-time factor with this commit")
    parser.add_argument("--json", type=Path, default=None, help="write the numbers to this file")
    return parser.parse_args()


def measure(args: argparse.Namespace, has_peer: bool) -> tuple[dict[str, dict[str, list]], list[float]]:
    """Warm-up round, then the interleaved rounds; per set and side the runs, and the demo RTFs."""
    dgraph_tick(SETS["bench"], min(args.ticks, 500))
    if has_peer:
        for loop in PEER_LOOPS.values():
            tsid_tick(args.peer, SETS["bench"], min(args.ticks, 500), args.unpinned_peer, loop)
    sides = ("dgraph", *PEER_LOOPS) if has_peer else ("dgraph",)
    results = {name: {side: [] for side in sides} for name in args.sets}
    demo_rtf = []
    for round_index in range(1, args.rounds + 1):
        for name in args.sets:
            results[name]["dgraph"].append(dgraph_tick(SETS[name], args.ticks))
            if has_peer:
                for side, loop in PEER_LOOPS.items():
                    results[name][side].append(tsid_tick(args.peer, SETS[name], args.ticks, args.unpinned_peer, loop))
        demo_rtf.append(demo_real_time_factor(min(args.ticks, 3000)))
        print(f"round {round_index} done", file=sys.stderr, flush=True)
    return results, demo_rtf


def main() -> None:
    """Calibrate, measure, summarise, print tables and the acceptance lines, write the JSON."""
    args = parse_args()
    has_peer = Path(args.peer).exists()
    cal_start = calibration.calibrate()
    results, demo_rtf = measure(args, has_peer)
    speedup = None
    if args.base:
        comparison = compare_commits.compare(args.base, compare_commits.WORKTREE, min(args.ticks, 3000), args.rounds)
        speedup = comparison["ratio_head_over_base"]
    cal_end = calibration.calibrate()
    summary = summarise(results, has_peer)
    print(calibration.calibration_line(cal_start))
    print(calibration.calibration_line(cal_end))
    print(f"{args.ticks} ticks per round and side, {args.rounds} rounds after a warm-up round; "
          f"BLAS/OpenMP threads: ours 1, TSID {'defaults' if args.unpinned_peer else 1}")
    for name in args.sets:
        print_set(name, results[name], summary["sets"][name], cal_start)
    print_scaling(summary)
    bench_rtf = [round(r["real_time_factor"], 2) for r in results.get("bench", {}).get("dgraph", [])]
    print(f"\nclosed-loop real-time factor of the bench graph (control graph + MuJoCo) per round: {bench_rtf}")
    print(f"full demo graph (4 tasks, recorder + 3D view to .rrd): real-time factor per round "
          f"{[round(r, 2) for r in demo_rtf]}, median {float(np.median(demo_rtf)):.2f}")
    peer_versions = next(iter(results.values()))["tsid"][0]["versions"] if has_peer else None
    if peer_versions:
        print(f"TSID: tsid {peer_versions['tsid']}, pinocchio {peer_versions['pinocchio']}, solver HQuadProgFast")
    else:
        print(f"TSID: not run ({args.peer} not found: bash bench/setup_tsid.sh)")
    criteria = acceptance(summary, speedup)
    print("\n## Acceptance\n")
    for status, text in criteria:
        print(f"{status}  {text}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({
            "calibration": {"start": cal_start, "end": cal_end}, "versions": versions(), "tsid_versions": peer_versions,
            "ticks": args.ticks, "rounds": args.rounds, "unpinned_peer": args.unpinned_peer,
            "sets": {name: list(SETS[name]) for name in args.sets}, "results": results, "summary": summary,
            "demo_real_time_factor": demo_rtf, "speedup_vs_base": speedup, "base": args.base,
            "acceptance": [{"status": s, "criterion": t} for s, t in criteria]}, indent=1))


if __name__ == "__main__":
    main()
