"""ProxQP's absolute tolerance for the ID QP, chosen from recorded ticks: time, iterations, torque error.

    python bench/qp_tolerance.py [--ticks 2000] [--warmup 500] [--closed-loop 5] [--json PATH]

1. Record ``--ticks`` problems of the TALOS sway closed loop (graphs/talos_sway.py, the demo's
   four tasks and two feet; ``bench/id_formulations.py``'s recorder) after ``--warmup`` ticks.
2. Replay them through the library's :class:`InverseDynamicsQP` at each (tolerance, proximal
   parameter ``rho``) of ``VARIANTS``, one solver per variant, tick after tick (warm-started as in the loop), the
   tolerances interleaved (the order rotates each tick) to spread the machine's noise. Reported
   per tolerance: median and p99 of the solve (assembly included, ``solution.solve_time``),
   mean and max ProxQP iterations, how many ticks needed the torque limits, and the largest
   difference of ``tau`` and of ``a`` from the exact optimum (daqp, an exact dual active-set
   solver, on the same assembled problem). Every 100th problem is also solved cold (a fresh
   solver: what happens when the set of contacts changes) for the worst case.
3. With ``--closed-loop S``: S seconds of the sway in MuJoCo at each tolerance; the CoM
   tracking RMS (estimated CoM against its reference) and the largest torque.

Prints a markdown table, the calibration line and the machine; ``--json`` keeps everything.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "graphs"))

from calibration import calibrate, calibration_line, single_threaded  # noqa: E402

single_threaded()

import numpy as np  # noqa: E402
from id_formulations import exact_reference, record  # noqa: E402

from dgraph.control import SOLVED  # noqa: E402
from dgraph.control.inverse_dynamics import PROXIMAL_RHO, InverseDynamicsQP  # noqa: E402

PROXQP_DEFAULT_RHO = 1e-6

VARIANTS = ((1e-9, PROXIMAL_RHO), (1e-8, PROXIMAL_RHO), (1e-7, PROXIMAL_RHO), (1e-6, PROXIMAL_RHO),
            (1e-5, PROXIMAL_RHO), (1e-9, PROXQP_DEFAULT_RHO), (1e-6, PROXQP_DEFAULT_RHO))
"""(eps_abs, rho): the library's proximal parameter at five tolerances, then ProxQP's default."""
COLD_EVERY = 100


def _solver(info: dict, eps_abs: float, rho: float) -> InverseDynamicsQP:
    return InverseDynamicsQP(info["nv"], info["n_unactuated"], info["effort_limit"], eps_abs=eps_abs, rho=rho,
                             acceleration_weight=info["acceleration_weight"])


def replay(problems: list, info: dict, exact: dict) -> dict[tuple[float, float], dict[str, float]]:
    """Every tolerance on every problem, interleaved; statistics per tolerance."""
    solvers = {v: _solver(info, *v) for v in VARIANTS}
    runs = {v: {"time": [], "iterations": [], "dtau": [], "da": [], "limited": 0, "failed": 0, "cold_dtau": []}
            for v in VARIANTS}
    for k, p in enumerate(problems):
        order = VARIANTS[k % len(VARIANTS):] + VARIANTS[:k % len(VARIANTS)]
        for variant in order:
            run = runs[variant]
            solution = solvers[variant].solve(p.mass_matrix, p.bias_forces, p.tasks, p.contacts, k)
            if solution.status != SOLVED:
                run["failed"] += 1
                continue
            run["time"].append(solution.solve_time * 1e6)
            run["iterations"].append(solution.iterations)
            run["limited"] += solution.torque_limited
            run["dtau"].append(float(np.abs(solution.tau - exact["tau"][k]).max()))
            run["da"].append(float(np.abs(solution.acceleration - exact["a"][k]).max()))
            if k % COLD_EVERY == 0:
                first = _solver(info, *variant).solve(p.mass_matrix, p.bias_forces, p.tasks, p.contacts, k)
                if first.status == SOLVED:
                    run["cold_dtau"].append(float(np.abs(first.tau - exact["tau"][k]).max()))
    return {variant: summary(run) for variant, run in runs.items()}


def summary(run: dict) -> dict[str, float]:
    """Medians, p99 and maxima of one tolerance's replay."""
    times = np.array(run["time"])
    return {"solve_us_median": float(np.median(times)), "solve_us_p99": float(np.percentile(times, 99)),
            "iterations_mean": float(np.mean(run["iterations"])), "iterations_max": int(max(run["iterations"])),
            "torque_limited_ticks": int(run["limited"]), "failed": int(run["failed"]),
            "max_dtau_Nm": max(run["dtau"]), "max_da": max(run["da"]),
            "cold_max_dtau_Nm": max(run["cold_dtau"]) if run["cold_dtau"] else float("nan")}


def closed_loop(seconds: float) -> dict[tuple[float, float], dict[str, float]]:
    """graphs/talos_sway.yaml in MuJoCo at each tolerance: CoM tracking RMS and the largest torque."""
    import dgraph as dg

    out = {}
    for eps, rho in VARIANTS:
        graph = dg.load(str(ROOT / "graphs" / "talos_sway.yaml"),
                        {"solver.eps_abs": eps, "recorder.rerun": "off", "view.rerun": "off"})
        graph["solver"]._qp.rho = rho  # read when its ProxQP problems are made, at the first tick
        with graph:
            graph.run(duration=seconds, progress=False)
            data = graph["recorder"].data()
        error = data["com.error"]
        out[eps, rho] = {"com_rms_mm": float(1e3 * np.sqrt(np.mean(np.sum(error**2, axis=1)))),
                    "max_tau_Nm": float(np.abs(data["solver.tau"]).max()), "fallen": bool(data["device.fallen"].any())}
    return out


def main() -> None:
    """Record, replay, report."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=2000, help="problems recorded and replayed")
    parser.add_argument("--warmup", type=int, default=500, help="closed-loop ticks before recording")
    parser.add_argument("--closed-loop", type=float, default=0.0, help="seconds of sway per tolerance (0: none)")
    parser.add_argument("--json", type=Path, help="write the numbers to this file")
    args = parser.parse_args()
    cal = calibrate()
    start = time.perf_counter()
    problems, info = record(args.ticks, args.warmup)
    exact = exact_reference(problems, info["nv"], info["n_unactuated"], info["effort_limit"],
                            info["acceleration_weight"])
    if exact is None:
        raise SystemExit("qp_tolerance: daqp (the test extra) is needed for the exact reference")
    stats = replay(problems, info, exact)
    loops = closed_loop(args.closed_loop) if args.closed_loop > 0 else {}
    print(f"{len(problems)} recorded TALOS sway problems (4 tasks, 2 feet); every {COLD_EVERY}th also solved cold\n")
    print("| eps_abs | rho | solve µs median | p99 | iterations mean / max | ticks with torque limits | "
          "max abs Δtau (N m) | max abs Δa | cold start: max abs Δtau | closed loop: CoM RMS (mm) |")
    print("|---|---|---:|---:|---|---:|---:|---:|---:|---:|")
    for (eps, rho), s in stats.items():
        loop = loops.get((eps, rho))
        com = f"{loop['com_rms_mm']:.4f}" if loop else "-"
        print(f"| {eps:g} | {rho:g} | {s['solve_us_median']:.0f} | {s['solve_us_p99']:.0f} | "
              f"{s['iterations_mean']:.2f} / {s['iterations_max']} | {s['torque_limited_ticks']} | "
              f"{s['max_dtau_Nm']:.1e} | {s['max_da']:.1e} | {s['cold_max_dtau_Nm']:.1e} | {com} |")
    print(f"\n{calibration_line(cal)}")
    print(f"time: {time.perf_counter() - start:.0f} s; command: `.venv/bin/python bench/qp_tolerance.py "
          f"{' '.join(sys.argv[1:])}`")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"calibration": cal, "ticks": len(problems),
                                         "replay": {f"eps {e:g} rho {r:g}": v for (e, r), v in stats.items()},
                                         "closed_loop": {f"eps {e:g} rho {r:g}": v for (e, r), v in loops.items()}},
                                        indent=1, default=str))


if __name__ == "__main__":
    main()
