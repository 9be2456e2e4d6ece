"""Scenario 2 of thesis Ch. 6: the largest normal force TALOS holds on a wall, standing, with and
without the energy tank.

    python bench/wall_push.py [--plots DIR] [--start 20] [--step 10] [--max 150] [--hold 1.0]

For each of ``graphs/talos_wall_push.yaml`` (tank) and ``talos_wall_push_no_tank.yaml``: one run
whose force reference (the wall's normal force on the tool) is 10 N from the contact, then a
staircase ``--start``, ``--start + --step``, ... up to ``--max`` N, one level per ``--hold`` s
(0.2 s linear ramps). The run stops at the end of the first level that fails a criterion not in
``--ignore`` (default: slip, which MuJoCo's creep trips first; it is still reported). A level is **held**
when, over its hold (after the ramp):

- the robot has not fallen;
- **slip**: neither sole moved more than 2 mm on the floor during the level (ramp and hold; MuJoCo's
  state, the sole frames placed by Pinocchio, as bench/contact_forces.py); the total creep since
  tick 0 is reported too (MuJoCo's soft contacts creep under a tangential load);
- **tipping**: each foot's centre of pressure, from MuJoCo's contact forces on that foot, stays at
  least 5 mm inside its sole rectangle (front 0.10 m, back 0.11 m, half width 0.069 m: the
  Contact6d's) and each foot's normal force stays above 5 % of its share ``m g / 2``;
- **tracking**: the mean measured normal force (wrist F/T) over the second half of the hold is
  within 10 % of the reference.

The largest held level is the answer (to ``--step``). Also reported per level, from the QP's
contact wrenches: each foot's friction usage ``max(|f_x|, |f_y|) / (mu' f_z)`` (1: every corner on
its pyramid, ``mu' = mu / sqrt 2``) and its CoP margin (distance to the nearest sole edge), the
share of ticks where a torque limit binds; and the static estimates (friction ``mu' m g`` and
``mu m g``, tipping ``m g d / h`` about the heels, the arm's torque limits ``J^T f``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.entities.robot import load_model

ROOT = Path(__file__).resolve().parent.parent
GRAPHS = ROOT / "graphs"
SOLES = ("left_sole_link", "right_sole_link")
ANKLES = ("leg_left_6_link", "leg_right_6_link")
FRONT, BACK, HALF_WIDTH = 0.10, 0.11, 0.069   # the feet's Contact6d sole (graphs/base/talos.yaml defaults)
MU = 0.3                                       # the feet's friction coefficient in the QP
SLIP_LIMIT = 0.002                             # m
COP_MARGIN = 0.005                             # m
SHARE = 0.05                                   # of m g / 2
FORCE_TOLERANCE = 0.10                         # of the reference
CONTACT_TIME = 1.0                             # s: the staircase starts here (10 N before)
RAMP = 0.2                                     # s
SAMPLE = 10                                    # ticks between MuJoCo samples


def initial_configuration(tip: tuple[float, float, float] = (0.45, 0.35, 1.10)) -> np.ndarray:
    """Half-sitting with the left arm moved so that the push tool (20 cm along
    ``gripper_left_base_link``'s -z) is horizontal along +x with its tip at ``tip``: bounded least
    squares on the tip position and axis, regularised towards half-sitting's arm (joints 0.05 rad
    inside their limits). ``graphs/talos_wall_push.yaml``'s ``device.q0`` is this, rounded."""
    from scipy.optimize import least_squares

    model = load_model("talos").copy()
    gripper = model.getFrameId("gripper_left_base_link")
    frame = model.addFrame(pin.Frame("tip", model.frames[gripper].parentJoint, gripper,
                                     model.frames[gripper].placement * pin.SE3(np.eye(3), np.array([0, 0, -0.2])),
                                     pin.FrameType.OP_FRAME))
    data = model.createData()
    graph = dg.load(str(GRAPHS / "talos_push_tank.yaml"), {"view.rerun": "off", "recorder.rerun": "off"})
    with graph:
        q0 = graph["device"].q.value.copy()
    arm = [model.joints[model.getJointId(f"arm_left_{k}_joint")].idx_q for k in range(1, 8)]
    lower, upper = model.lowerPositionLimit[arm] + 0.05, model.upperPositionLimit[arm] - 0.05

    def residual(x: np.ndarray) -> np.ndarray:
        q = q0.copy()
        q[arm] = x
        pin.framesForwardKinematics(model, data, q)
        placement = data.oMf[frame]
        return np.r_[placement.translation - tip, placement.rotation[:, 2] + [1.0, 0.0, 0.0], 1e-3 * (x - q0[arm])]

    result = least_squares(residual, np.clip(q0[arm], lower, upper), bounds=(lower, upper), xtol=1e-14,
                           ftol=1e-14, gtol=1e-14)
    q = q0.copy()
    q[arm] = result.x
    return np.round(q, 5)


def staircase(levels: list[float], hold: float, path: Path) -> None:
    """Write the force reference CSV: 10 N until :data:`CONTACT_TIME`, then each level for ``hold`` s
    after a :data:`RAMP` s ramp (world force on the tool: ``fx = -F``)."""
    rows = [(0.0, 10.0), (CONTACT_TIME, 10.0)]
    for k, level in enumerate(levels):
        start = CONTACT_TIME + k * hold
        rows += [(start + RAMP, level), (start + hold, level)]
    path.write_text("time, fx, fy, fz\n" + "".join(f"{t:.3f}, {-f:.3f}, 0.0, 0.0\n" for t, f in rows))


@dataclass
class Run:
    """One staircase run: the Recorder's data and the MuJoCo samples (every :data:`SAMPLE` ticks)."""

    name: str
    levels: list[float]
    hold: float
    data: dict[str, np.ndarray] = field(default_factory=dict)
    ticks: list[int] = field(default_factory=list)
    cop: list[np.ndarray] = field(default_factory=list)        # per foot, sole frame (x, y), m
    normal: list[np.ndarray] = field(default_factory=list)     # per foot, N
    slip: list[np.ndarray] = field(default_factory=list)       # per foot, |xy displacement| since tick 0, m
    sole_xy: list[np.ndarray] = field(default_factory=list)    # per foot, xy displacement since tick 0, m
    wall_time: float = 0.0


class FootSampler:
    """The feet's measured contact forces and centre of pressure from MuJoCo's contacts, and the
    soles' displacement on the floor (Pinocchio frames at MuJoCo's configuration)."""

    def __init__(self, device: dg.Entity):
        self.device = device
        m = device.mj_model
        self.m = m
        roots = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name) for name in ANKLES]
        self.foot_of_body = np.full(m.nbody, -1)
        for body in range(m.nbody):
            b = body
            while b > 0:
                if b in roots:
                    self.foot_of_body[body] = roots.index(b)
                    break
                b = m.body_parentid[b]
        self.model = load_model("talos")
        self.pdata = self.model.createData()
        self.sole_ids = [self.model.getFrameId(name) for name in SOLES]
        self.start: list[np.ndarray] | None = None
        self._force = np.zeros(6)

    def soles(self, q: np.ndarray) -> list[pin.SE3]:
        """The sole frames' placements at ``q``."""
        pin.framesForwardKinematics(self.model, self.pdata, q)
        return [self.pdata.oMf[i].copy() for i in self.sole_ids]

    def sample(self, run: Run, tick: int) -> None:
        """Append the feet's CoP (sole frame), normal force and slip at ``tick``."""
        d = self.device.data
        soles = self.soles(np.asarray(self.device.q.value))
        if self.start is None:
            self.start = [s.translation.copy() for s in soles]
        moment, normal = np.zeros((2, 2)), np.zeros(2)
        for i in range(d.ncon):
            contact = d.contact[i]
            feet = self.foot_of_body[self.m.geom_bodyid[[contact.geom1, contact.geom2]]]
            foot = int(feet.max())
            if foot < 0:
                continue
            mujoco.mj_contactForce(self.m, d, i, self._force)
            world = contact.frame.reshape(3, 3).T @ self._force[:3]
            fz = abs(world[2])
            normal[foot] += fz
            moment[foot] += fz * contact.pos[:2]
        cop = np.full((2, 2), np.nan)
        for foot in range(2):
            if normal[foot] > 1e-6:
                point = np.r_[moment[foot] / normal[foot], soles[foot].translation[2]]
                cop[foot] = (soles[foot].rotation.T @ (point - soles[foot].translation))[:2]
        xy = np.array([s.translation[:2] - s0[:2] for s, s0 in zip(soles, self.start, strict=True)])
        run.ticks.append(tick)
        run.cop.append(cop)
        run.normal.append(normal)
        run.sole_xy.append(xy)
        run.slip.append(np.linalg.norm(xy, axis=1))


def level_window(run: Run, k: int, dt: float) -> tuple[int, int]:
    """Ticks ``[start, end)`` of level ``k``'s hold (after its ramp)."""
    start = CONTACT_TIME + k * run.hold
    return round((start + RAMP) / dt), round((start + run.hold) / dt)


def evaluate_level(run: Run, k: int, dt: float, weight: float) -> dict[str, object]:
    """The failure criteria and the QP's saturation over level ``k``'s hold."""
    lo, hi = level_window(run, k, dt)
    data = run.data
    ticks = np.asarray(run.ticks)
    sel = (ticks >= lo) & (ticks < hi)
    level = run.levels[k]
    half = slice((lo + hi) // 2, hi)
    measured = -data["wrist_force.force"][half, 0]
    cop = np.asarray(run.cop)[sel]                       # (n, foot, xy)
    margins = np.minimum.reduce([FRONT - cop[..., 0], cop[..., 0] + BACK, HALF_WIDTH - np.abs(cop[..., 1])])
    normal = np.asarray(run.normal)[sel]
    begin = round((CONTACT_TIME + k * run.hold) / dt)   # the level's ramp starts here
    xy = np.asarray(run.sole_xy)[(ticks >= begin) & (ticks < hi)]
    slip = np.linalg.norm(xy - xy[0], axis=-1) if len(xy) else np.zeros((1, 2))
    creep = np.asarray(run.slip)[ticks < hi]
    wrenches = data["solver.contact_wrenches"][lo:hi, :2]   # the feet: world axes at the sole frames
    fz = np.maximum(wrenches[..., 2], 1e-9)
    usage = np.maximum(np.abs(wrenches[..., 0]), np.abs(wrenches[..., 1])) / (MU / np.sqrt(2.0) * fz)
    qp_cop = np.stack([-wrenches[..., 4] / fz, wrenches[..., 3] / fz], axis=-1)
    qp_margin = np.minimum.reduce([FRONT - qp_cop[..., 0], qp_cop[..., 0] + BACK,
                                   HALF_WIDTH - np.abs(qp_cop[..., 1])])
    fallen = bool(data["device.fallen"][:hi].any())
    result = {
        "level": level, "force": float(measured.mean()), "error": float(abs(measured.mean() - level) / level),
        "slip_mm": 1000 * float(np.nanmax(slip)), "creep_mm": 1000 * float(creep.max()),
        "cop_margin_mm": 1000 * float(np.nanmin(margins)) if len(margins) else float("nan"),
        "cop_x_mm": 1000 * float(np.nanmin(cop[..., 0])) if len(cop) else float("nan"),
        "min_normal": float(normal.min()) if len(normal) else 0.0,
        "qp_friction": float(usage.max()), "qp_cop_margin_mm": 1000 * float(qp_margin.min()),
        "neg_qp_cop": -1000 * float(qp_margin.min()),
        "torque_limited": float(data["solver.torque_limited"][lo:hi].mean()), "fallen": fallen,
        "qp_tool_tangential": float(np.abs(data["solver.contact_wrenches"][lo:hi, 2, 1:]).max()),
    }
    failures = []
    if fallen:
        failures.append("fall")
    if result["slip_mm"] > 1000 * SLIP_LIMIT:
        failures.append("slip")
    if not result["cop_margin_mm"] >= 1000 * COP_MARGIN:
        failures.append("CoP at edge")
    if result["min_normal"] < SHARE * weight / 2.0:
        failures.append("foot unloaded")
    if not result["error"] <= FORCE_TOLERANCE:
        failures.append("force error")
    result["failures"] = failures
    return result


def run_staircase(name: str, levels: list[float], hold: float, weight: float, tmp: Path,
                  ignore: tuple[str, ...] = ()) -> tuple[Run, list[dict]]:
    """Run ``name`` on the staircase ``levels`` until the end of the first level failing a criterion
    not in ``ignore`` (those are still reported)."""
    path = tmp / f"{name}.csv"
    staircase(levels, hold, path)
    duration = CONTACT_TIME + len(levels) * hold
    run = Run(name, levels, hold)
    graph = dg.load(str(GRAPHS / f"{name}.yaml"), {"force_reference.path": str(path), "recorder.rerun": "off",
                                                   "view.rerun": "off"})
    results: list[dict] = []
    start = time.perf_counter()
    with graph:
        sampler = FootSampler(graph["device"])
        dt = graph.dt
        sampler.sample(run, 0)
        k = 0
        while graph.t < round(duration / dt):
            graph.run(ticks=SAMPLE, progress=False)
            sampler.sample(run, graph.t)
            if k < len(levels) and graph.t >= level_window(run, k, dt)[1]:
                run.data = graph["recorder"].data()
                results.append(evaluate_level(run, k, dt, weight))
                r = results[-1]
                print(f"  {name}: {levels[k]:6.1f} N  measured {r['force']:6.1f} N  slip {r['slip_mm']:5.2f} mm  "
                      f"CoP margin {r['cop_margin_mm']:5.1f} mm  QP friction {r['qp_friction']:.2f}  "
                      f"QP CoP margin {r['qp_cop_margin_mm']:5.1f} mm  {', '.join(r['failures']) or 'held'}  "
                      f"[{time.perf_counter() - start:.0f} s]", file=sys.stderr, flush=True)
                k += 1
                if set(r["failures"]) - set(ignore):
                    break
        run.data = graph["recorder"].data()
    run.wall_time = time.perf_counter() - start
    return run, results


def statics(q0: np.ndarray, tip_height: float) -> dict[str, float]:
    """The static estimates at ``q0``: weight, friction limits, tipping about the heels, arm torques."""
    model = load_model("talos")
    data = model.createData()
    weight = pin.computeTotalMass(model) * 9.81
    pin.centerOfMass(model, data, q0)
    pin.framesForwardKinematics(model, data, q0)
    heel = min(data.oMf[model.getFrameId(s)].translation[0] for s in SOLES) - BACK
    return {"weight": weight, "friction_pyramid": MU / np.sqrt(2.0) * weight, "friction_cone": MU * weight,
            "com_x": float(data.com[0][0]), "heel_x": heel, "height": tip_height,
            "tipping": weight * (data.com[0][0] - heel) / tip_height}


def plot(runs: list[tuple[Run, list[dict]]], directory: Path) -> list[Path]:
    """Normal force against its reference, the feet's CoP against the sole edges, the soles' slip."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 3.2 * len(runs)), sharex=True, squeeze=False)
    for ax, (run, _) in zip(axes[:, 0], runs, strict=True):
        t = run.data["time"]
        ax.plot(t, -run.data["force_reference.position"][:, 0], "k--", lw=1, label="reference F*")
        ax.plot(t, -run.data["wrist_force.force"][:, 0], lw=1, label="measured (wrist F/T)")
        ax.plot(t, -run.data["solver.contact_wrenches"][:, 2, 0], lw=0.8, alpha=0.7, label="QP tool force")
        ax.set_ylabel("normal force (N)")
        ax.set_title(run.name)
        ax.legend(loc="upper left", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    fig.tight_layout()
    paths.append(directory / "wall_push_force.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 3.2 * len(runs)), sharex=True, squeeze=False)
    for ax, (run, _) in zip(axes[:, 0], runs, strict=True):
        t = np.asarray(run.ticks) * 1e-3
        cop = 1000 * np.asarray(run.cop)
        wrench = run.data["solver.contact_wrenches"][:, :2]
        qp_x = -1000 * wrench[..., 4] / np.maximum(wrench[..., 2], 1e-9)
        for foot, name in enumerate(("left", "right")):
            ax.plot(t, cop[:, foot, 0], lw=1, label=f"{name} CoP x (MuJoCo)")
            ax.plot(run.data["time"], qp_x[:, foot], lw=0.8, ls=":", label=f"{name} CoP x (QP)")
        ax.axhline(1000 * FRONT, color="r", lw=0.8)
        ax.axhline(-1000 * BACK, color="r", lw=0.8, label="sole edges (toe, heel)")
        ax.axhline(-1000 * (BACK - COP_MARGIN), color="r", lw=0.6, ls="--", label="heel + 5 mm")
        ax.set_ylabel("CoP x in sole frame (mm)")
        ax.set_title(run.name)
        ax.legend(loc="lower left", fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel("time (s)")
    fig.tight_layout()
    paths.append(directory / "wall_push_cop.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(9, 3.5))
    for run, _ in runs:
        t = np.asarray(run.ticks) * 1e-3
        slip = 1000 * np.asarray(run.slip)
        for foot, name in enumerate(("left", "right")):
            ax.plot(t, slip[:, foot], lw=1, label=f"{run.name}: {name} sole")
    ax.axhline(1000 * SLIP_LIMIT, color="r", lw=0.8, ls="--", label="2 mm")
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("sole displacement on the floor (mm)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths.append(directory / "wall_push_slip.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    return paths


def main() -> None:
    """Both runs, the per-level table, the summary and the static estimates; the plots."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plots", type=Path, help="write the PNGs here")
    parser.add_argument("--start", type=float, default=20.0, help="first level (N)")
    parser.add_argument("--step", type=float, default=5.0, help="level step (N)")
    parser.add_argument("--max", type=float, default=120.0, help="last level (N)")
    parser.add_argument("--hold", type=float, default=1.0, help="seconds per level (ramp included)")
    parser.add_argument("--graphs", nargs="+", default=["talos_wall_push", "talos_wall_push_no_tank"])
    parser.add_argument("--ignore", nargs="*", default=["slip"], choices=["slip", "CoP at edge", "foot unloaded",
                                                                      "force error"],
                        help="criteria that do not stop the staircase (still reported; default: slip, so that the QP's "
                             "friction and CoP bounds are reached beyond MuJoCo's creep)")
    args = parser.parse_args()
    levels = list(np.arange(args.start, args.max + 1e-9, args.step))
    graph = dg.load(str(GRAPHS / "talos_wall_push.yaml"), {"view.rerun": "off", "recorder.rerun": "off"})
    with graph:
        q0 = np.asarray(graph["device"].q.value).copy()
    est = statics(q0, 1.10)
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.graphs:
            print(f"{name}: levels {levels[0]:g} to {levels[-1]:g} N by {args.step:g} N, {args.hold:g} s each",
                  file=sys.stderr, flush=True)
            runs.append(run_staircase(name, levels, args.hold, est["weight"], Path(tmp), tuple(args.ignore)))
    print("| graph | F* (N) | measured (N) | error | slip in level (mm) | creep since 0 (mm) | min CoP margin (mm) "
          "| heel-most CoP x (mm) "
          "| min foot f_z (N) | QP friction usage | QP CoP margin (mm) | QP tool tangential (N) | torque-limited ticks "
          "| outcome |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for run, results in runs:
        for r in results:
            print(f"| {run.name} | {r['level']:.0f} | {r['force']:.1f} | {100 * r['error']:.1f} % | "
                  f"{r['slip_mm']:.2f} | {r['creep_mm']:.2f} | {r['cop_margin_mm']:.1f} | {r['cop_x_mm']:.1f} | "
                  f"{r['min_normal']:.0f} | "
                  f"{r['qp_friction']:.2f} | {r['qp_cop_margin_mm']:.1f} | {r['qp_tool_tangential']:.1f} | "
                  f"{100 * r['torque_limited']:.0f} % | {', '.join(r['failures']) or 'held'} |")
    print()
    for run, results in runs:
        for skipped in ((), tuple(args.ignore)):
            held, first = [], None
            for r in results:   # the levels held before the first failure
                if set(r["failures"]) - set(skipped):
                    first = r
                    break
                held.append(r["level"])
            label = f"ignoring {', '.join(skipped)}" if skipped else "all criteria"
            print(f"{run.name} ({label}): largest force held {max(held) if held else 0:.0f} N; "
                  + (f"first failure at {first['level']:.0f} N ({', '.join(first['failures'])})" if first else
                     "no failure up to the last level"))
        binding = [(name, next((r["level"] for r in results if r[key] >= bound), None))
                   for name, key, bound in (("QP friction usage >= 0.99", "qp_friction", 0.99),
                                            ("QP CoP margin <= 1 mm", "neg_qp_cop", -1.0))]
        print(f"{run.name}: first level where " + "; ".join(
            f"{name}: {level:.0f} N" if level is not None else f"{name}: never" for name, level in binding)
              + f"; {run.data['time'][-1]:.2f} s simulated in {run.wall_time:.0f} s")
    print(f"\nstatics: m g = {est['weight']:.1f} N; friction mu' m g = {est['friction_pyramid']:.1f} N (pyramid, "
          f"mu' = {MU / np.sqrt(2):.3f}), mu m g = {est['friction_cone']:.1f} N (cone); tipping about the heels "
          f"m g (x_com - x_heel) / h = {est['weight']:.1f} x ({est['com_x']:.4f} - ({est['heel_x']:.4f})) / "
          f"{est['height']:.2f} = {est['tipping']:.1f} N")
    if args.plots:
        args.plots.mkdir(parents=True, exist_ok=True)
        for path in plot(runs, args.plots):
            print(f"wrote {path}")


if __name__ == "__main__":
    main()
