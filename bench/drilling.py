"""Scenario 1 of thesis Ch. 6: the Panda drills ten holes, one breaks through (docs/force_control.md).

    .venv/bin/python bench/drilling.py [--plots docs]

Runs ``graphs/panda_drill.yaml`` (passive QP, energy tank) and ``graphs/panda_drill_no_tank.yaml``
to their end and prints, for each: the normal-force error per hole in the second half of its hold
(mean and max of ``|f_n - F*|``), the peak force at contact and its overshoot over the reference,
the breakthrough (how far the tool advanced into the hole, its peak speed, the time to retract),
the tank's energy range and the largest ``H_dot - (-v_j^T tau)``. ``--plots DIR`` writes PNGs.
``initial_configuration()`` is how the graph's ``q0`` was computed.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import dgraph as dg
from dgraph.entities.references.drilling import APPROACH, HOLD, RAMP, RETRACT

ROOT = Path(__file__).resolve().parents[1]
GRAPHS = ROOT / "graphs"
TARGET = 20.0
REMOVAL = 12.25


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


def scenario(name: str) -> dict[str, np.ndarray]:
    """Run a graph file to its end; the Recorder's data."""
    graph = dg.load(str(GRAPHS / f"{name}.yaml"), {"recorder.rerun": "off"})
    with graph:
        graph.run(duration=graph.duration, progress=False)
        return graph["recorder"].data()


def outcomes(data: dict[str, np.ndarray]) -> dict[str, object]:
    """Per-hole force errors, overshoots, breakthrough and tank figures of one run."""
    time, phase, hole = data["time"], data["sequence.phase"], data["sequence.hole"]
    force = -data["device.contact_force_total"][:, 0]
    reference = data["sequence.normal_force_reference"]
    x = data["tool_contact.position"][:, 0]
    mean_error, max_error, contact_peak, overshoot = [], [], [], []
    for k in np.unique(hole[phase == HOLD]):
        held = np.flatnonzero((phase == HOLD) & (hole == k) & (time < REMOVAL if k == 5 else True))
        steady = held[len(held) // 2:]
        mean_error.append(float(np.abs(force[steady] - TARGET).mean()))
        max_error.append(float(np.abs(force[steady] - TARGET).max()))
        pressing = np.flatnonzero((phase >= APPROACH) & (phase <= HOLD) & (hole == k))
        contact_peak.append(float(force[pressing].max()))
        ramp_hold = np.flatnonzero(((phase == RAMP) | (phase == HOLD)) & (hole == k))
        overshoot.append(float((force[ramp_hold] - reference[ramp_hold]).max()))
    removal = int(np.argmax(time >= REMOVAL))
    after = slice(removal, removal + 1000)
    speed = np.abs(np.gradient(x[after], time[after]))
    retract = removal + int(np.argmax(phase[removal:] == RETRACT))
    return {
        "mean |f_n - F*| per hole (N)": mean_error, "max |f_n - F*| per hole (N)": max_error,
        "peak f_n approach-hold per hole (N)": contact_peak, "max f_n - f_n* ramp-hold per hole (N)": overshoot,
        "breakthrough advance (mm)": 1000 * float(x[after].max() - x[removal - 1]),
        "breakthrough peak tool speed (m/s)": float(speed.max()),
        "loss seen after (ms)": 1000 * float(time[retract] - REMOVAL),
        "E_tank min / max (J)": (float(data["tank.energy"].min()), float(data["tank.energy"].max())),
        "max H_dot - (-v_j^T tau) (W)": float((data["tank.power_bound"] - data["tank.delivered_power"]).max()),
        "QP failures": int((data["solver.status"] != 0).sum()),
        "missed holes": int(data["sequence.missed"][-1]), "breakthroughs": int(data["sequence.breakthroughs"][-1]),
    }


def plot(tank: dict[str, np.ndarray], plain: dict[str, np.ndarray], folder: Path) -> list[Path]:
    """Force tracking over the ten holes, a zoom on one hole and on the breakthrough, tank energy."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    fig, axes = plt.subplots(2, 1, figsize=(10, 5.5), sharex=True)
    t = tank["time"]
    axes[0].plot(t, -tank["device.contact_force_total"][:, 0], label="measured f_n (tank)")
    axes[0].plot(t, tank["sequence.normal_force_reference"], "k--", lw=0.8, label="reference f_n*")
    axes[0].axvline(REMOVAL, color="r", lw=0.8, label="hole 5 breaks through")
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
    for data, label in ((tank, "tank"), (plain, "no tank")):
        window = (data["time"] > REMOVAL - 0.05) & (data["time"] < REMOVAL + 0.4)
        removal = int(np.argmax(data["time"] >= REMOVAL))
        x = data["tool_contact.position"][:, 0]
        axes[1].plot(data["time"][window], 1000 * (x[window] - x[removal - 1]), label=label)
    axes[1].axvline(REMOVAL, color="r", lw=0.8)
    axes[1].set_title("breakthrough: tool advance into the hole")
    axes[1].set_xlabel("time (s)")
    axes[1].set_ylabel("mm (+: into the wall)")
    axes[1].legend(fontsize=8)
    paths.append(_save(fig, folder / "force_control_breakthrough.png"))
    return paths


def _save(fig: object, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plots", type=Path, default=None, help="folder for the PNG plots")
    args = parser.parse_args()
    runs = {"tank": scenario("panda_drill"), "no tank": scenario("panda_drill_no_tank")}
    for label, data in runs.items():
        print(f"== {label}")
        for key, value in outcomes(data).items():
            text = " ".join(f"{v:.3f}" for v in value) if isinstance(value, list) or isinstance(value, tuple) \
                else f"{value:.4g}" if isinstance(value, float) else str(value)
            print(f"  {key}: {text}")
    if args.plots is not None:
        for path in plot(runs["tank"], runs["no tank"], args.plots):
            print("wrote", path)


if __name__ == "__main__":
    main()
