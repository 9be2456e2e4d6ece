"""Scenario 1 of thesis Ch. 6: the Panda drills ten holes, one breaks through (docs/force_control.md).

    .venv/bin/python bench/drilling.py [--plots docs]

Runs ``graphs/panda_drill.yaml`` (passive QP, energy tank) and ``graphs/panda_drill_no_tank.yaml``
to their end, and the tank graph with the breakthrough moved into hole 5's force ramp, and prints,
for each: the normal-force error per hole in the second half of its hold (mean and max of
``|f_n - F*|``), the peak force at contact and its overshoot over the reference, the largest
measured force in the holds (against f_clamp), the breakthrough (the tool's 3-D displacement over
the 50 ms after it, its peak speed, the time to retract), the position task's largest lag in the
moves, the smallest tank scale gamma, the tank's energy range and the largest
``H_dot - (-v_j^T tau)``. ``--plots DIR`` writes PNGs.
``initial_configuration()`` is how the graph's ``q0`` was computed.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.entities.references.drilling import APPROACH, HOLD, MOVE, RAMP, RETRACT
from dgraph_sim.scenes import DRILL_BREAKTHROUGH

if TYPE_CHECKING:
    from matplotlib.figure import Figure

ROOT = Path(__file__).resolve().parents[1]
GRAPHS = ROOT / "graphs"
TARGET = 20.0
CLAMP = 40.0
LUNGE_WINDOW = 50  # ticks after the breakthrough
RAMP_BREAK = {"sequence.break_phase": "ramp", "sequence.break_delay": 0.15}


def initial_configuration(target: tuple[float, float, float] = (0.62, -0.18, 0.45)) -> np.ndarray:
    """The Panda configuration putting the drill tool's tip at ``target`` with the hand pointing
    down (the tool along +x): bounded least squares on the pose error from the SRDF's default
    posture (joints 0.1 rad inside their limits)."""
    import pinocchio as pin
    from scipy.optimize import least_squares

    from dgraph_sim.robots import robot_spec
    from dgraph_sim.scenes import DRILL_TOOL_TIP

    info = robot_spec("panda")[1]
    model = info.pin_model.copy()
    hand = model.getFrameId("panda_hand")
    tip = model.addFrame(pin.Frame("tip", model.frames[hand].parentJoint, hand, model.frames[hand].placement
                                   * pin.SE3(np.eye(3), np.array(DRILL_TOOL_TIP)), pin.FrameType.OP_FRAME))
    data = model.createData()
    goal = pin.SE3(pin.utils.rpyToMatrix(np.pi, 0.0, 0.0), np.array(target))
    lower, upper = model.lowerPositionLimit[:7] + 0.1, model.upperPositionLimit[:7] - 0.1
    q0 = info.q0.copy()

    def residual(x: np.ndarray) -> np.ndarray:
        q = q0.copy()
        q[:7] = x
        pin.framesForwardKinematics(model, data, q)
        return np.r_[pin.log6(data.oMf[tip].actInv(goal)).vector, 1e-4 * (x - q0[:7])]

    result = least_squares(residual, q0[:7], bounds=(lower, upper), xtol=1e-14, ftol=1e-14, gtol=1e-14)
    q = q0.copy()
    q[:7] = result.x
    return np.round(q, 5)


def scenario(name: str, overrides: dict[str, object] | None = None) -> dict[str, np.ndarray]:
    """Run a graph file to its end; the Recorder's data."""
    graph = dg.load(str(GRAPHS / f"{name}.yaml"), {"recorder.rerun": "off", **(overrides or {})})
    with graph:
        graph.run(duration=graph.duration, progress=False)
        return graph["recorder"].data()


def removal(data: dict[str, np.ndarray]) -> int:
    """The tick of the sequence's breakthrough event (the plate goes in the step from it)."""
    return int(np.argmax(data["sequence.breakthrough"]))


def outcomes(data: dict[str, np.ndarray]) -> dict[str, object]:
    """Per-hole force errors, overshoots, breakthrough, lag and tank figures of one run."""
    time, phase, hole = data["time"], data["sequence.phase"], data["sequence.hole"]
    force = -data["device.contact_force_total"][:, 0]
    reference = data["sequence.normal_force_reference"]
    tip = data["tool_contact.position"]
    k_break = removal(data)
    mean_error, max_error, contact_peak, overshoot = [], [], [], []
    for k in np.unique(hole[phase == HOLD]):
        held = np.flatnonzero((phase == HOLD) & (hole == k))
        if k == DRILL_BREAKTHROUGH:  # the part before the breakthrough
            held = held[held <= k_break]
        steady = held[len(held) // 2:]
        mean_error.append(float(np.abs(force[steady] - TARGET).mean()))
        max_error.append(float(np.abs(force[steady] - TARGET).max()))
        pressing = np.flatnonzero((phase >= APPROACH) & (phase <= HOLD) & (hole == k))
        contact_peak.append(float(force[pressing].max()))
        ramp_hold = np.flatnonzero(((phase == RAMP) | (phase == HOLD)) & (hole == k))
        overshoot.append(float((force[ramp_hold] - reference[ramp_hold]).max()))
    after = slice(k_break, k_break + LUNGE_WINDOW + 1)
    speed = np.linalg.norm(np.gradient(tip[after], time[after], axis=0), axis=1)
    retract = k_break + int(np.argmax(phase[k_break:] == RETRACT))
    moving = phase == MOVE
    return {
        "mean |f_n - F*| per hole (N)": mean_error, "max |f_n - F*| per hole (N)": max_error,
        "peak f_n approach-hold per hole (N)": contact_peak, "max f_n - f_n* ramp-hold per hole (N)": overshoot,
        "max measured f_n in the holds (N)": float(force[phase == HOLD].max()),
        "breakthrough at (s), hole, phase": (float(time[k_break]), int(hole[k_break]), int(phase[k_break])),
        "breakthrough 3-D displacement, 50 ms (mm)":
            1000 * float(np.linalg.norm(tip[after] - tip[k_break], axis=1).max()),
        "breakthrough peak tool speed, 50 ms (m/s)": float(speed.max()),
        "loss seen after (ms)": 1000 * float(time[retract] - time[k_break]),
        "max position-task lag in the moves (mm)": 1000 * float(np.linalg.norm(data["tool.error"][moving][:, :3],
                                                                                axis=1).max()),
        "min tank gamma": float(data["tank.gamma"].min()),
        "E_tank min / max (J)": (float(data["tank.energy"].min()), float(data["tank.energy"].max())),
        "max H_dot - (-v_j^T tau) (W)": float((data["tank.power_bound"] - data["tank.delivered_power"]).max()),
        "QP failures": int((data["solver.status"] != 0).sum()),
        "missed holes": int(data["sequence.missed"][-1]), "breakthroughs": int(data["sequence.breakthroughs"][-1]),
    }


def plot(tank: dict[str, np.ndarray], plain: dict[str, np.ndarray], ramp: dict[str, np.ndarray],
         folder: Path) -> list[Path]:
    """Force tracking over the ten holes, a zoom on one hole and on the breakthrough, tank energy."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    fig, axes = plt.subplots(2, 1, figsize=(10, 5.5), sharex=True)
    t = tank["time"]
    axes[0].plot(t, -tank["device.contact_force_total"][:, 0], label="measured f_n (tank)")
    axes[0].plot(t, tank["sequence.normal_force_reference"], "k--", lw=0.8, label="reference f_n*")
    axes[0].axvline(tank["time"][removal(tank)], color="r", lw=0.8, label=f"hole {DRILL_BREAKTHROUGH} breaks through")
    axes[0].set_ylabel("normal force (N)")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[1].plot(t, tank["tank.energy"], label="E_tank (tank)")
    axes[1].plot(plain["time"], plain["tank.energy"], label="E_tank, bookkeeping only (no tank)")
    axes[1].set_ylabel("energy (J)")
    axes[1].set_xlabel("time (s)")
    axes[1].legend(loc="lower left", fontsize=8)
    fig.suptitle("Panda drills ten holes (graphs/panda_drill.yaml)")
    paths.append(_save(fig, folder / "force_control_holes.png"))

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    hole = (tank["sequence.hole"] == 2) & (tank["sequence.phase"] >= APPROACH) & (tank["sequence.phase"] <= RETRACT)
    axes[0].plot(t[hole], -tank["device.contact_force_total"][hole, 0], label="measured f_n")
    axes[0].plot(t[hole], tank["sequence.normal_force_reference"][hole], "k--", lw=0.8, label="reference")
    axes[0].plot(t[hole], -tank["force_task.force"][hole, 0], ":", label="force task F_F (PI + feed-forward)")
    axes[0].set_title("hole 2: approach, ramp, hold, release")
    axes[0].set_xlabel("time (s)")
    axes[0].set_ylabel("N")
    axes[0].legend(fontsize=8)
    for data, label in ((tank, "tank, in the hold"), (plain, "no tank, in the hold"), (ramp, "tank, in the ramp")):
        k = removal(data)
        since = data["time"] - data["time"][k]
        window = (since > -0.05) & (since < 0.4)
        tip = data["tool_contact.position"]
        axes[1].plot(1000 * since[window], 1000 * np.linalg.norm(tip[window] - tip[k], axis=1), label=label)
    axes[1].axvline(0.0, color="r", lw=0.8)
    axes[1].axvspan(0.0, LUNGE_WINDOW, color="r", alpha=0.08)
    axes[1].set_title("breakthrough: tool displacement (3-D)")
    axes[1].set_xlabel("time since the breakthrough (ms)")
    axes[1].set_ylabel("mm")
    axes[1].legend(fontsize=8)
    paths.append(_save(fig, folder / "force_control_breakthrough.png"))
    return paths


def _save(fig: Figure, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plots", type=Path, default=None, help="folder for the PNG plots")
    args = parser.parse_args()
    runs = {"tank": scenario("panda_drill"), "no tank": scenario("panda_drill_no_tank"),
            "tank, breakthrough in the ramp": scenario("panda_drill", RAMP_BREAK)}
    for label, data in runs.items():
        print(f"== {label}")
        for key, value in outcomes(data).items():
            text = " ".join(f"{v:.3f}" for v in value) if isinstance(value, list) or isinstance(value, tuple) \
                else f"{value:.4g}" if isinstance(value, float) else str(value)
            print(f"  {key}: {text}")
    if args.plots is not None:
        for path in plot(runs["tank"], runs["no tank"], runs["tank, breakthrough in the ramp"], args.plots):
            print("wrote", path)


if __name__ == "__main__":
    main()
