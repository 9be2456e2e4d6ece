"""Run the lifting scenario (graphs/talos_lift_load.yaml) and draw its story.

    .venv/bin/python bench/lift_load.py --plots docs

writes ``lift_load_current.png``, ``lift_load_temperature.png``, ``lift_load_torque.png`` and
``lift_load_elbow.png`` into the folder given, and prints the numbers quoted in
docs/actuators.md. ``--bypass`` also runs the graph with ``chain.selection: 1`` (the elbow driven
by ActuatorModel: the same demand i*, with the same compensation, clipped at i_max, no barrier)
and prints its numbers.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

import dgraph as dg
from dgraph.entities.actuators.chain import load_chain_file

ROOT = Path(__file__).resolve().parents[1]
GRAPH = ROOT / "graphs" / "talos_lift_load.yaml"
ELBOW = 17  # index of arm_left_4_joint among the 32 actuated joints
CHAIN = load_chain_file(ROOT / "graphs" / "data" / "talos_actuators.yaml")["arm_left_4_joint"]
I_MAX = CHAIN.i_max


def run(overrides: dict[str, object] | None = None) -> dict[str, np.ndarray]:
    """The recorded signals of one run of the scenario."""
    settings: dict[str, object] = {"view.rerun": "off", "recorder.rrd_path": "/dev/null"}
    settings.update(overrides or {})
    graph = dg.load(str(GRAPH), settings)
    with graph:
        graph.run(duration=graph.duration, progress=False)
    return graph["recorder"].data()


def summary(data: dict[str, np.ndarray]) -> dict[str, float]:
    """Peak current, plateau, first tick with the demand over the limit, temperature rise."""
    i = np.abs(data["protection.current"][:, 0])
    demand = np.abs(data["protection.reference_current"][:, 0])
    load = data["load.position"][:, 0]
    hold = slice(7_000, 7_999)
    over = np.flatnonzero((demand > I_MAX) & (load > 0.0))
    temperature = data["thermal.temperature"][:, 0]
    return {"peak |i| (A)": float(i.max()),
            "ticks saturated (clip acted)": float(np.count_nonzero(data["protection.saturated"][:, 0])),
            "plateau at 34 kg, mean |i| (A)": float(i[hold].mean()),
            "peak |i*| (A)": float(demand.max()), "|i*| at 34 kg, mean (A)": float(demand[hold].mean()),
            "first loaded tick with |i*| > 6 A (s)": float(over[0] * 1e-3) if over.size else float("nan"),
            "load then (kg)": float(load[over[0]]) if over.size else float("nan"),
            "ticks with |i*| > 6 A unloaded (lift)": float(np.count_nonzero((demand > I_MAX) & (load == 0.0))),
            "temperature rise (K)": float(temperature[-1] - temperature[0]),
            "lowest base height (m)": float(data["device.q"][:, 2].min()),
            "elbow error at the end (rad)": float(data["elbow_q.output"][-1, 0]
                                                  - data["elbow_reference.position"][-1, 0])}


def plots(data: dict[str, np.ndarray], folder: Path) -> list[Path]:
    """The four figures."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(len(data["protection.current"])) * 1e-3
    load = data["load.position"][:, 0]
    out = []

    def figure(title: str) -> tuple[Any, Any]:
        fig, ax = plt.subplots(figsize=(8, 3.6))
        ax.set_title(title)
        ax.set_xlabel("time (s)")
        twin = ax.twinx()
        twin.plot(t, load, color="0.6", lw=1, ls=":", label="load (kg at 5 cm)")
        twin.set_ylabel("load (kg at 5 cm)", color="0.4")
        return fig, ax

    def save(fig: Any, name: str) -> None:
        path = folder / name
        fig.tight_layout()
        fig.savefig(path, dpi=100)
        plt.close(fig)
        out.append(path)

    fig, ax = figure("Elbow motor current (magnitude)")
    ax.plot(t, np.abs(data["protection.reference_current"][:, 0]), color="tab:red", lw=1,
            label="demand |i*| (QP torque, unfiltered)")
    ax.plot(t, np.abs(data["protection.current"][:, 0]), color="tab:blue", lw=1.5, label="|i| after TorqueProtection")
    ax.axhline(I_MAX, color="k", ls="--", lw=1, label=f"i_max = {I_MAX:g} A")
    ax.set_ylabel("current (A)")
    ax.legend(loc="upper left", fontsize=8)
    save(fig, "lift_load_current.png")

    fig, ax = figure("Elbow motor temperature (ThermalModel)")
    ax.plot(t, data["thermal.temperature"][:, 0], color="tab:orange", label="T (T_max = 100 °C)")
    ax.set_ylabel("temperature (°C)")
    ax.legend(loc="upper left", fontsize=8)
    save(fig, "lift_load_temperature.png")

    fig, ax = figure("Elbow joint torque: commanded vs delivered")
    ax.plot(t, data["elbow_tau.output"][:, 0], color="tab:red", lw=1, label="commanded (QP tau_j*)")
    delivered = np.append(data["device.joint_torque"][1:, ELBOW], np.nan)  # stamped t + 1
    ax.plot(t, delivered, color="tab:blue", lw=1.5, label="motor torque applied (R K_m i)")
    ax.axhline(-CHAIN.R_Km * I_MAX, color="k", ls="--", lw=1, label="-R K_m i_max")
    ax.set_ylabel("torque (N m)")
    ax.legend(loc="lower left", fontsize=8)
    save(fig, "lift_load_torque.png")

    fig, ax = figure("Elbow angle vs reference")
    ax.plot(t, data["elbow_reference.position"][:, 0], color="k", ls="--", lw=1, label="reference (minimum jerk)")
    ax.plot(t, data["elbow_q.output"][:, 0], color="tab:green", lw=1.5, label="q (encoder)")
    ax.set_ylabel("arm_left_4_joint (rad)")
    ax.legend(loc="upper right", fontsize=8)
    save(fig, "lift_load_elbow.png")
    return out


def main() -> None:
    """Parse the arguments, run, print, plot."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--plots", type=Path, help="folder for the PNGs (e.g. docs)")
    parser.add_argument("--bypass", action="store_true", help="also run with the protection bypassed")
    args = parser.parse_args()
    data = run()
    for key, value in summary(data).items():
        print(f"{key}: {value:.3f}")
    if args.plots:
        args.plots.mkdir(parents=True, exist_ok=True)
        for path in plots(data, args.plots):
            print("wrote", path)
    if args.bypass:
        free = run({"chain.selection": 1})
        demand = np.abs(free["bypass_chain.current_desired"][:, 0])
        current = np.abs(free["bypass_chain.current"][:, 0])
        load = free["load.position"][:, 0]
        over = demand > I_MAX
        first = np.flatnonzero(over)
        applied = np.abs(free["device.joint_torque"][:, ELBOW])
        same = np.abs(demand - np.abs(free["protection.reference_current"][:, 0])).max()  # one helper, one i*
        error = free["elbow_q.output"][-1, 0] - free["elbow_reference.position"][-1, 0]
        print(f"bypassed: peak |i*| {demand.max():.3f} A, ticks over {I_MAX:g} A {np.count_nonzero(over)} "
              f"({np.count_nonzero(over & (load == 0.0))} unloaded), first at "
              f"{first[0] * 1e-3 if first.size else float('nan'):.3f} s, |i*| at 34 kg mean "
              f"{demand[7_000:7_999].mean():.3f} A, |i| at 34 kg mean {current[7_000:7_999].mean():.3f} A, "
              f"saturated ticks {np.count_nonzero(free['bypass_chain.saturated'][:, 0])}, "
              f"max |i* - protection i*| {same:.2e} A, "
              f"peak motor torque {applied.max():.3f} N m (R K_m i_max {CHAIN.R_Km * I_MAX:.2f}), "
              f"elbow error at the end {error:.3f} rad, "
              f"fallen {bool(free['device.fallen'].any())}")


if __name__ == "__main__":
    main()
