"""TALOS control tick: dgraph's inverse-dynamics graph against TSID 1.10, in the same run.

    bash bench/setup_tsid.sh            # once: the TSID peer's own venv (.venv-tsid, pin 4.0.0)
    .venv/bin/python bench/talos_tick.py [--ticks 5000] [--rounds 2] [--json out/talos_tick.json]

Task set of the TSID benchmark, on both sides: Contact6d x2 (soles, 4 corners, mu 0.3), CoM
(weight 1e3, Kp 20, Kd 3, swaying 5 cm at 0.5 Hz), joint posture (weight 0.1, Table 4.3 gains,
Kd = 2 sqrt(Kp)); force regularisation 1e-5, contact Kp 30, Kd 11.

- **dgraph tick**: TALOS in MuJoCo (``graphs/talos_sway.py`` with the CoM and posture tasks,
  no recorder). A ``before`` hook of the device pulls ``solver.tau(t)`` and times it: that is
  the whole control graph (FloatingBaseEstimator + RobotModel + features + tasks + contacts +
  QP assembly and solve, plus dgraph's signal overhead), without the simulator. Our QP also has
  the 32 torque limits (66 inequalities against TSID's 34).
- **TSID tick**: ``bench/peer_tsid.py`` in ``.venv-tsid``: ``computeProblemData`` + ``solve``
  on its own kinematically integrated state (no simulator); eiquadprog (HQuadProgFast).
- **real-time factor**: simulated time / wall time of the whole dgraph closed loop (control
  graph + MuJoCo step), without recording; and with the recorder and 3D view of the demo.

The variants are interleaved round by round (VM noise is +-20-30%); medians and p99 are per
round, the ratio is dgraph's median over TSID's median in the same round.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "graphs"))

import talos_sway  # noqa: E402

TSID_CONFIG = {
    "contacts": {"mu": 0.3, "fMin": 1.0, "fMax": 1000.0, "kp": 30.0, "kd": 11.0, "w_force_reg": 1e-5},
    "com": {"weight": 1000.0, "kp": 20.0, "kd": 3.0, "sway_amplitude": [0.0, 0.05, 0.0], "sway_frequency": 0.5},
    "posture": {"weight": 0.1, "kp": {"legs": [10, 5, 5, 1, 10, 10], "torso": [100, 100],
                                      "arms": [50, 10, 10, 10, 50, 10, 10, 10], "head": [100, 100]}, "kd": None},
    "waist": None,
}


def stats(samples_us: np.ndarray) -> dict[str, float]:
    """Median, p90, p99 and mean of a sample in µs."""
    return {"median": float(np.median(samples_us)), "p90": float(np.percentile(samples_us, 90)),
            "p99": float(np.percentile(samples_us, 99)), "mean": float(samples_us.mean())}


def dgraph_tick(ticks: int, warmup: int = 200) -> dict[str, object]:
    """Control-graph time per tick in the MuJoCo closed loop, and the loop's real-time factor."""
    graph = talos_sway.build(tasks=("com_task", "posture_task"), record=False)
    times: list[float] = []
    tau = graph["solver"].tau

    def control(t: int) -> None:
        start = time.perf_counter_ns()
        tau(t)
        times.append(time.perf_counter_ns() - start)

    graph["device"].before.add(control)
    graph.run(ticks=warmup, progress=False)
    times.clear()
    start = time.perf_counter()
    graph.run(ticks=ticks, progress=False)
    wall = time.perf_counter() - start
    status = graph["solver"].solution.value.status
    graph.close()
    return {"tick_us": stats(np.array(times) / 1e3), "real_time_factor": ticks * graph.dt / wall,
            "loop_us": wall / ticks * 1e6, "last_status": int(status), "fallen": bool(graph["device"].fallen.value)}


def demo_real_time_factor(ticks: int) -> float:
    """Real-time factor of the full demo graph (all tasks, recorder and 3D view, .rrd written)."""
    import dgraph as dg

    graph = dg.load(str(ROOT / "graphs" / "talos_sway.yaml"), {"recorder.rrd_path": "out/bench_talos_sway.rrd",
                                                               "view.rrd_path": "out/bench_talos_sway.rrd"})
    start = time.perf_counter()
    with graph:
        graph.run(ticks=ticks, progress=False)
    return ticks * graph.dt / (time.perf_counter() - start)


def tsid_tick(python: str, ticks: int) -> dict[str, object]:
    """Run the TSID peer in its venv on the same task set; its JSON report."""
    config = ROOT / "out" / "tsid_config.json"
    config.parent.mkdir(exist_ok=True)
    config.write_text(json.dumps(TSID_CONFIG))
    out = subprocess.run([python, str(ROOT / "bench" / "peer_tsid.py"), "--ticks", str(ticks), "--config", str(config)],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def machine() -> str:
    """CPU model, cores and Python version."""
    model = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                  if line.startswith("model name")), platform.processor())
    import os

    return f"{model}, {os.cpu_count()} vCPU, CPython {platform.python_version()}"


def main() -> None:
    """Interleave dgraph and TSID rounds; print a markdown table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=5000)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--peer", default=str(ROOT / ".venv-tsid" / "bin" / "python"), help="TSID venv python")
    parser.add_argument("--json", default=None, help="write the numbers to this file")
    args = parser.parse_args()
    rounds = []
    for _ in range(args.rounds):
        ours = dgraph_tick(args.ticks)
        peer = tsid_tick(args.peer, args.ticks) if Path(args.peer).exists() else None
        rounds.append({"dgraph": ours, "tsid": peer})
    demo_rtf = demo_real_time_factor(min(args.ticks, 3000))
    print(f"machine: {machine()}; {args.ticks} ticks per round, {args.rounds} rounds\n")
    print("| round | dgraph tick median µs | p99 | TSID tick median µs | p99 | ratio (median) | "
          "closed-loop RTF |")
    print("|---|---|---|---|---|---|---|")
    for i, r in enumerate(rounds, 1):
        ours, peer = r["dgraph"], r["tsid"]
        peer_cols = (f"{peer['tick_us']['median']:.0f} | {peer['tick_us']['p99']:.0f} | "
                     f"{ours['tick_us']['median'] / peer['tick_us']['median']:.2f}") if peer else "- | - | -"
        print(f"| {i} | {ours['tick_us']['median']:.0f} | {ours['tick_us']['p99']:.0f} | {peer_cols} | "
              f"{ours['real_time_factor']:.2f} |")
    print(f"\nfull demo graph (4 tasks, recorder + 3D view to .rrd): real-time factor {demo_rtf:.2f}")
    if rounds[0]["tsid"]:
        p = rounds[0]["tsid"]
        print(f"TSID: tsid {p['versions']['tsid']}, pinocchio {p['versions']['pinocchio']}, nVar {p['nVar']}, "
              f"nEq {p['nEq']}, nIn {p['nIn']}, solver {p['solver']}")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"machine": machine(), "rounds": rounds, "demo_rtf": demo_rtf},
                                              indent=1))


if __name__ == "__main__":
    main()
