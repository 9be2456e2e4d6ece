"""The energy tank's cost and effect on the pushing scenario (thesis §5.4.1).

    .venv/bin/pip install -e ".[plots]"        # matplotlib, for --plots
    .venv/bin/python bench/energy_tank.py [--ticks 20000] [--rounds 2] [--plots docs]

- **Tick cost**: ``graphs/talos_push_tank.yaml`` in MuJoCo, as a *plain* controller (no tank
  entity, ``solver.passive: false``) and as the *passive* one (tank enabled). A ``before`` hook
  of the device pulls ``solver.tau(t)`` and times it: the whole control graph (estimator,
  model, features, tasks, contacts, force task, tank stage 1, QP) without the simulator. The
  tank's stage 1 and the QP solve are also timed on their own. Variants alternate round by
  round; medians and p99 are per round.
- **Scenario** (``--plots DIR``): both graph files run to the end; a table of outcomes is
  printed and PNG plots are written to DIR (energy and valves; H_dot and its bound; force;
  hand height).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import calibration

calibration.single_threaded()  # before numpy: one BLAS/OpenMP thread, as the other benchmarks

import numpy as np  # noqa: E402
import yaml  # noqa: E402
from calibration import calibrate, calibration_line  # noqa: E402

import dgraph as dg  # noqa: E402
from dgraph.files import loads, parse  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
GRAPHS = ROOT / "graphs"


def percentiles(samples: np.ndarray) -> str:
    """``median / p99`` in µs."""
    return f"{np.median(samples):.0f} / {np.percentile(samples, 99):.0f}"


def timed_graph(passive: bool) -> dg.Graph:
    """The pushing graph, passive (tank) or plain (no tank entity, no passivity input), without
    recording."""
    path = GRAPHS / "talos_push_tank.yaml"
    data = parse(path.read_text(), str(path))
    del data["entities"]["view"], data["record"]
    data["plugs"] = [p for p in data["plugs"] if not p.strip().startswith("device.q ->")]
    if not passive:
        del data["entities"]["tank"]
        data["entities"]["solver"]["params"]["passive"] = False
        data["plugs"] = [p for p in data["plugs"] if "tank." not in p]
    return loads(yaml.safe_dump(data), str(path))


def tick_cost(passive: bool, ticks: int) -> dict[str, np.ndarray]:
    """Per-tick times (µs): control graph, tank stage 1 (passive only), QP assembly and solve."""
    graph = timed_graph(passive)
    control, stage = [], []
    tau, solve_time = graph["solver"].tau, graph["solver"].solve_time
    tank_budget = graph["tank"].budget if passive else None

    def pull(t: int) -> None:
        start = time.perf_counter_ns()
        if tank_budget is not None:
            tank_budget(t)
            stage.append(time.perf_counter_ns() - start)
        tau(t)
        control.append(time.perf_counter_ns() - start)

    solves = []
    graph["device"].before.add(pull)
    graph["device"].before.add(lambda t: solves.append(solve_time(t) * 1e9))
    with graph:
        graph.run(ticks=ticks, progress=False)
        fallen = bool(graph["device"].fallen.value)
    return {"control": np.array(control) / 1e3, "stage": np.array(stage) / 1e3, "solve": np.array(solves) / 1e3,
            "fallen": fallen}


def scenario(name: str) -> dict[str, np.ndarray]:
    """Run a graph file to its end and return the Recorder's data."""
    graph = dg.load(str(GRAPHS / f"{name}.yaml"), {"recorder.rerun": "off", "view.rerun": "off"})
    with graph:
        graph.run(duration=graph.duration, progress=True)
    return graph["recorder"].data()


def outcomes(data: dict[str, np.ndarray], removal: float = 13.0) -> dict[str, float]:
    """What the table reports for one run."""
    time_s, after = data["time"], data["time"] >= removal
    before = np.argmax(after) - 10
    tip, com = data["tool_contact.position"], data["robot.com_position"]
    return {
        "fallen": float(data["device.fallen"].any()),
        "hand drop (cm)": 100 * float(tip[before, 2] - tip[after, 2].min()),
        "hand travel (cm)": 100 * float(np.linalg.norm(tip[after] - tip[before], axis=1).max()),
        "CoM excursion (cm)": 100 * float(np.linalg.norm(com[after] - com[before], axis=1).max()),
        "peak |-v_j^T tau| after removal (W)": float(np.abs(data["tank.delivered_power"][after]).max()),
        "E_tank min (J)": float(data["tank.energy"].min()),
        "E_tank max (J)": float(data["tank.energy"].max()),
        "clamp correction (J)": float(data["tank.correction"][-1]),
        "max H_dot - (-v_j^T tau) (W)": float((data["tank.power_bound"] - data["tank.delivered_power"]).max()),
        "force task removed at (s)": float(time_s[np.argmax(data["detector.phase"] == 2)]),
        "QP failures": float((data["solver.status"] != 0).sum()),
    }


def plot(tank: dict[str, np.ndarray], plain: dict[str, np.ndarray], folder: Path) -> list[Path]:
    """Energy and valves; H_dot against its bound; force; hand height (PNG files)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    files = []
    t = tank["time"]
    fig, (energy, valves) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    energy.plot(t, tank["tank.energy"], label="with tank")
    energy.plot(plain["time"], plain["tank.energy"], "--", label="without (bookkeeping only)")
    energy.axhline(5.0, color="grey", lw=0.8)
    energy.axhline(0.1, color="grey", lw=0.8)
    energy.set_ylabel("E_tank (J)")
    energy.legend()
    for name in ("alpha", "beta", "gamma"):
        valves.plot(t, tank[f"tank.{name}"], label=name)
    valves.set_ylabel("valves (with tank)")
    valves.set_xlabel("time (s)")
    valves.legend()
    for ax in (energy, valves):
        ax.axvline(13.0, color="red", lw=0.8)
    files.append(_save(fig, folder / "energy_tank_valves.png"))

    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    window = (t > 12.5) & (t < 15.0)
    for ax, data, title in ((axes[0], tank, "with tank"), (axes[1], plain, "without tank")):
        ax.plot(data["time"][window], data["tank.delivered_power"][window], label="-v_j^T tau (bound)")
        ax.plot(data["time"][window], data["tank.power_bound"][window], "--", label="H_dot")
        ax.set_ylabel(f"W ({title})")
        ax.legend()
    axes[1].set_xlabel("time (s)")
    files.append(_save(fig, folder / "energy_tank_power.png"))

    fig, (force, hand) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    force.plot(t, tank["force_reference.position"][:, 2], "k", lw=0.8, label="F* (reference)")
    force.plot(t, tank["wrist_force.force"][:, 2], label="measured, with tank")
    force.plot(plain["time"], plain["wrist_force.force"][:, 2], "--", label="measured, without")
    force.set_ylabel("F_z on the tool (N)")
    force.legend()
    hand.plot(t, tank["tool_contact.position"][:, 2], label="with tank")
    hand.plot(plain["time"], plain["tool_contact.position"][:, 2], "--", label="without")
    hand.set_ylabel("tool tip z (m)")
    hand.set_xlabel("time (s)")
    hand.legend()
    for ax in (force, hand):
        ax.axvline(13.0, color="red", lw=0.8)
    files.append(_save(fig, folder / "energy_tank_force.png"))
    return files


def _save(fig: object, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    return path


def main() -> None:
    """Tick cost rounds, then (with --plots) the scenario table and plots."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=20_000, help="ticks per timed run (20000: the whole scenario)")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--plots", type=Path, default=None, help="run both scenarios and write PNG plots here")
    args = parser.parse_args()
    print(f"# {calibration_line(calibrate())}")
    print("| round | variant | control tick median / p99 (µs) | tank stage 1 | QP assembly + solve | fell |")
    print("|---|---|---|---|---|---|")
    for round_ in range(1, args.rounds + 1):
        medians = {}
        for passive in (False, True):
            cost = tick_cost(passive, args.ticks)
            name = "passive" if passive else "plain"
            medians[name] = np.median(cost["control"])
            stage = percentiles(cost["stage"]) if passive else "-"
            print(f"| {round_} | {name} | {percentiles(cost['control'])} | {stage} | {percentiles(cost['solve'])} "
                  f"| {cost['fallen']} |")
        print(f"| {round_} | ratio passive / plain | {medians['passive'] / medians['plain']:.2f} | | | |")
    if args.plots is not None:
        tank, plain = scenario("talos_push_tank"), scenario("talos_push_no_tank")
        rows = {"with tank": outcomes(tank), "without tank": outcomes(plain)}
        print("\n| | with tank | without tank |\n|---|---|---|")
        for key in rows["with tank"]:
            print(f"| {key} | {rows['with tank'][key]:.3g} | {rows['without tank'][key]:.3g} |")
        for path in plot(tank, plain, args.plots):
            print(f"wrote {path}")


if __name__ == "__main__":
    main()
