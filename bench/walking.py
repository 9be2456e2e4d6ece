"""TALOS's walks in MuJoCo against the thesis (Ch. 4.4.4, Tables 4.4-4.10) and placo's walk pattern generator.

    .venv/bin/python bench/walking.py [--graphs talos_walk_20cm ...] [--out out/walking] [--doc docs/walking.md]
        [--no-placo]

Runs each walking graph (a name in graphs/ or a .yaml path; default: the 20 cm and 60 cm walks in
torque, the 20 cm walk in the IK and TSID-position schemes) to its end or to the robot's fall, with
the graph's own recorders and views taken out and one Recorder of what the evaluation reads, the
control graph timed per tick as bench/compare_schemes.py does (``timed``). A graph file that does
not exist is reported as such. Evaluated with :mod:`dgraph.evaluation` on the ticks before a fall,
against the simulator's ground truth (the true CoM and soles from ``device.q``):

- ZMP error (Table 4.4, from ``ZMP_SETTLING``): the ankle F/T ZMP (``zmp.zmp``) against the planned one
  (``pattern.zmp``), and, where the graph has a DCM stabiliser, against its desired ZMP ``p*``
  (Eq. 2.30), the reference the thesis used for the position schemes (L4693-4699);
- CoM and feet tracking (Table 4.5): the true CoM against ``pattern.com_position``, the true
  soles against ``left_swing.position`` / ``right_swing.position``;
- E_m, E_m+, C_et, C_mt (Table 4.8, Eq. 4.16; D: the plan's distance from the initial to the final
  midpoint of the soles, the thesis's "traveled distance", L4682), the PGM per gait stage
  (Table 4.9, Eq. 4.17-4.18; stages from ``schedule.double_support`` / ``left_swing`` /
  ``right_swing``), the control tick (Table 4.10) with the calibration figure;
- the final base position against the plan's final midpoint, the fall;
- the largest per-tick change of each foot's normal force (``solver.contact_wrenches``) within
  the scheduler's ``transition`` of a contact switch, against 5 % of the robot's weight.

One figure per walk (docs/walking_<graph>.png): the top view of the CoM, planned and measured
ZMP and DCM over the footprints and double-support polygons, and their x and y over time.

The peer (unless ``--no-placo``; bench/setup_placo.sh makes .venv-placo when it is missing):
bench/peer_placo.py plans each walk's own footstep plan (``FootstepPlan.to_plain()``, the same
CoM height, margin and initial CoM), and our ZmpPatternGenerator, with the walk graph's
parameters and ``feedback = 0``, plans it open loop in the same run (placo's output is open loop
too: each re-plan starts from its own trajectory). Compared: plan and re-plan times (with the
calibration), the ZMP's distance to the plan's support polygon edge (min, share of samples
outside), the CoM jerk (RMS, peak) and the DCM at the plan's end against the final support.

Writes the recordings and the peer's files under ``--out`` and the whole of ``--doc``.
"""

from __future__ import annotations

import calibration

calibration.single_threaded()  # before numpy: one BLAS/OpenMP thread, as the other benchmarks

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from calibration import BusyMeter, calibrate, calibration_line, in_loops, single_threaded_env  # noqa: E402
from compare_schemes import timed  # noqa: E402  (bench/, the script's folder)
from tqdm import tqdm  # noqa: E402

import dgraph as dg  # noqa: E402
from dgraph.entities.recording import Recorder  # noqa: E402
from dgraph.entities.robot import load_model  # noqa: E402
from dgraph.entities.stabilizers import divergent_component, natural_frequency  # noqa: E402
from dgraph.entities.stabilizers.lipm import GRAVITY  # noqa: E402
from dgraph.entities.walking import FootstepPlan, ZmpPatternGenerator  # noqa: E402
from dgraph.entities.walking.footsteps import SIDES, convex_hull  # noqa: E402
from dgraph.entities.walking.pattern_generator import SupportPolygons  # noqa: E402
from dgraph.evaluation import (  # noqa: E402
    before_fall,
    contact_switch_force_jumps,
    cost_of_transport,
    first_fall,
    jerk_statistics,
    mechanical_energy,
    phase_passivity,
    polygon_margin,
    tick_statistics,
    tracking_error,
)
from dgraph_sim.truth import robot_mass, true_com_and_frames  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
WALKS = {  # graph -> (the thesis's scheme, walk)
    "talos_walk_20cm": ("TSID torque", "20 cm"),
    "talos_walk_60cm": ("TSID torque", "60 cm"),
    "talos_walk_20cm_ik": ("IK", "20 cm"),
    "talos_walk_20cm_tsid_position": ("TSID position", "20 cm"),
}
REQUIRED = ["device.q", "device.joint_torque", "device.v", "device.fallen", "zmp.zmp", "pattern.zmp",
            "pattern.com_position", "pattern.dcm", "left_swing.position", "right_swing.position",
            "schedule.double_support", "schedule.left_swing", "schedule.right_swing"]
OPTIONAL = ["solver.contact_wrenches", "stabilizer.desired_zmp"]
FORCE_JUMP_LIMIT = 0.05  # of the robot's weight per tick: the acceptance of issue 13
ZMP_SETTLING = 0.05  # s left out of the ZMP errors: the F/T start-up transient of MuJoCo's initial contact state
PLACO_PYTHON = ROOT / ".venv-placo" / "bin" / "python"

# The thesis (Gazebo), /work/shared/reference/walking_mptc_actuators_drilling.md §1.7, keyed by (scheme, walk).
THESIS_ZMP = {  # Table 4.4 [L4659-4668], m: (average, std, peak) per axis x, y; 20 cm walk only
    ("IK", "20 cm"): ((0.019, 0.022, 0.131), (0.022, 0.026, 0.150)),
    ("TSID position", "20 cm"): ((0.028, 0.025, 0.142), (0.025, 0.027, 0.138)),
    ("TSID torque", "20 cm"): ((0.026, 0.021, 0.078), (0.011, 0.014, 0.078)),
}
THESIS_TRACKING = {  # Table 4.5 [L4743-4754], m: body -> (average, std, peak) per axis x, y; 60 cm, torque
    ("TSID torque", "60 cm"): {"CoM": ((0.018, 0.013, 0.050), (0.004, 0.003, 0.015)),
                               "left foot": ((0.014, 0.013, 0.063), (0.001, 0.001, 0.005)),
                               "right foot": ((0.016, 0.016, 0.063), (0.001, 0.001, 0.006))},
}
THESIS_COT = {  # Table 4.8 [L4888-4910]: E_m J, E_m+ J, C_et, C_mt
    ("IK", "20 cm"): (1983.9, 1359.3, 1.68, 1.15), ("TSID position", "20 cm"): (2324.5, 764.1, 1.97, 0.65),
    ("TSID torque", "20 cm"): (521.8, 259.3, 0.44, 0.22), ("TSID torque", "60 cm"): (3147.2, 1583.8, 0.89, 0.45),
}
THESIS_PGM = {  # Table 4.9 [L4912-4930]: double support, single support, flying foot
    ("IK", "20 cm"): (0.35, 0.89, 0.24), ("TSID position", "20 cm"): (0.37, 0.74, 0.37),
    ("TSID torque", "20 cm"): (0.93, 0.87, 1.0), ("TSID torque", "60 cm"): (0.87, 0.79, 1.0),
}
THESIS_TICK = {  # Table 4.10 [L4932-4940], ms: average, peak
    ("IK", "20 cm"): (0.5, 2.0), ("TSID position", "20 cm"): (1.2, 4.5),
    ("TSID torque", "20 cm"): (1.0, 2.8), ("TSID torque", "60 cm"): (1.4, 6.0),
}


@dataclass
class Walk:
    """One walking graph and its run: the recording, the control ticks' durations (s, the first
    tick left out), the wall time, and what the evaluation reads from the graph; ``problem`` says
    why it did not run (the rest then stays empty)."""

    name: str
    path: Path
    problem: str | None = None
    data: dict[str, np.ndarray] = field(default_factory=dict)
    durations: np.ndarray = field(default_factory=lambda: np.zeros(0))
    wall: float = 0.0
    dt: float = 0.001
    plan: FootstepPlan | None = None
    transition: float = 0.0
    pattern_params: dict[str, object] = field(default_factory=dict)
    contacts: list[str] = field(default_factory=list)

    @property
    def thesis(self) -> tuple[str, str] | None:
        """The thesis's (scheme, walk) this graph stands for, if any."""
        return WALKS.get(self.name)


# -- running ----------------------------------------------------------------------------------------
def graph_path(graph: str) -> Path:
    """A graph's file: a .yaml path as given, else graphs/<name>.yaml."""
    return Path(graph) if graph.endswith(".yaml") else ROOT / "graphs" / f"{graph}.yaml"


def has_signal(graph: dg.Graph, name: str) -> bool:
    """Whether ``graph`` has the signal ``entity.signal``."""
    entity, _, signal = name.partition(".")
    return entity in graph and signal in graph[entity].ports


def prepared(walk: Walk, out: Path) -> dg.Graph | None:
    """The graph with its observers replaced by the evaluation's Recorder, or None (``walk.problem`` set)."""
    if not walk.path.is_file():
        shown = walk.path.relative_to(ROOT) if walk.path.is_relative_to(ROOT) else walk.path
        walk.problem = f"not run: {shown} does not exist"
        return None
    graph = dg.load(str(walk.path))
    for name in [name for name, entity in graph.entities.items() if entity.observes]:
        graph.remove(name)
    missing = [name for name in REQUIRED if not has_signal(graph, name)]
    if missing:
        walk.problem = f"not evaluated: the graph has no {', '.join(missing)}"
        return None
    recorded = REQUIRED + [name for name in OPTIONAL if has_signal(graph, name)]
    graph.add(Recorder("evaluation", signals=recorded, rerun="off", npz_path=str(out / f"{walk.name}.npz")))
    return graph


def run(walk: Walk, out: Path) -> None:
    """Run the walk's graph to its duration or to the fall, filling ``walk``."""
    graph = prepared(walk, out)
    if graph is None:
        return
    durations: list[float] = []
    timed(graph, durations)
    device, ticks = graph["device"], round(graph.duration / graph.dt)
    start = time.perf_counter()
    with graph, tqdm(total=ticks, unit="tick", desc=walk.name, mininterval=0.5) as bar:
        for tick in range(ticks):
            fallen = device.fallen(tick)  # this tick's state, recorded by the step
            graph.step()
            bar.update()
            if fallen:
                break
    walk.wall = time.perf_counter() - start
    walk.data, walk.durations, walk.dt = graph["evaluation"].data(), np.array(durations[1:]), graph.dt
    walk.plan, walk.transition = graph["footsteps"].plan(0), graph["schedule"].transition
    walk.pattern_params = dict(graph["pattern"].given_params)
    walk.contacts = list(getattr(graph["solver"], "contacts", None) or [])


# -- evaluation -------------------------------------------------------------------------------------
def ankle_columns(model: object, side: str) -> list[int]:
    """The columns of ``side``'s ankle pitch and roll (leg_<side>_5, _6) in the actuated torques."""
    return [model.joints[model.getJointId(f"leg_{side}_{k}_joint")].idx_v - 6 for k in (5, 6)]


def evaluate(walk: Walk) -> dict[str, object]:
    """Every metric of one walk, on the ticks before a fall."""
    data = walk.data
    mask, fall = before_fall(data["device.fallen"]), first_fall(data["device.fallen"])
    com, soles = true_com_and_frames(data["device.q"], [f"{side}_sole_link" for side in SIDES])
    result = {"fall": None if fall is None else fall * walk.dt, "mask": mask, "weight": robot_mass() * GRAVITY,
              "com": com, "dcm": measured_dcm(walk, com)}
    result.update(tracking(walk, com, soles, mask))
    result.update(gait(walk, mask))
    return result


def measured_dcm(walk: Walk, com: np.ndarray) -> np.ndarray:
    """The true DCM ``c + c_dot / omega`` (Eq. 2.27), ``c_dot`` by central differences of the true
    CoM, ``omega`` from the planned CoM height above the ground."""
    omega = natural_frequency(walk.data["pattern.com_position"][:, 2] - walk.plan.ground_height())
    return divergent_component(com, np.gradient(com, walk.dt, axis=0), omega)


def tracking(walk: Walk, com: np.ndarray, soles: np.ndarray, mask: np.ndarray) -> dict[str, object]:
    """The ZMP errors (Table 4.4) and the CoM and feet tracking errors (Table 4.5), horizontal axes."""
    data = walk.data
    settled = mask & (data["time"] >= ZMP_SETTLING)
    result = {"zmp": tracking_error(data["zmp.zmp"][:, :2], data["pattern.zmp"][:, :2], settled),
              "tracking": {"CoM": tracking_error(com[:, :2], data["pattern.com_position"][:, :2], mask)}}
    for i, side in enumerate(SIDES):
        result["tracking"][f"{side} foot"] = tracking_error(soles[:, i, :2], data[f"{side}_swing.position"][:, :2],
                                                            mask)
    if "stabilizer.desired_zmp" in data:
        result["zmp_desired"] = tracking_error(data["zmp.zmp"][:, :2], data["stabilizer.desired_zmp"][:, :2],
                                               settled)
    return result


def gait(walk: Walk, mask: np.ndarray) -> dict[str, object]:
    """Energy and costs of transport (Table 4.8), PGM per stage (Table 4.9), force jumps, ticks
    (Table 4.10), the final base position."""
    data, dt, plan = walk.data, walk.dt, walk.plan
    swings = {side: data[f"schedule.{side}_swing"].astype(bool)[mask] for side in SIDES}
    model = load_model("talos")
    work, positive = mechanical_energy(data["device.joint_torque"][mask], data["device.v"][mask, 6:], dt)
    distance = float(np.linalg.norm(plan.final_midpoint()[:2] - plan.phases[0].zmp_from[:2]))
    return {
        "energy": (work, positive), "distance": distance,
        "cot": tuple(cost_of_transport(energy, robot_mass(), distance) for energy in (work, positive)),
        "pgm": phase_passivity(data["device.joint_torque"][mask], ankle_columns(model, "left"),
                               ankle_columns(model, "right"), data["schedule.double_support"][mask].astype(bool),
                               swings["left"], swings["right"]),
        "force_jumps": force_jumps(walk, swings, mask),
        "tick": tick_statistics(walk.durations[:int(mask.sum()) - 1], dt),  # ticks 1 to the last before a fall
        "real_time_factor": len(mask) * dt / walk.wall,
        "final_base": data["device.q"][mask][-1, :2], "final_midpoint": plan.final_midpoint()[:2],
    }


def force_jumps(walk: Walk, swings: dict[str, np.ndarray], mask: np.ndarray) -> list[object] | None:
    """Per foot, the largest per-tick normal-force change near a contact switch (None without the
    solver's contact wrenches of the two feet)."""
    if "solver.contact_wrenches" not in walk.data or walk.contacts[:2] != ["left_foot", "right_foot"]:
        return None
    normal = walk.data["solver.contact_wrenches"][mask][:, :2, 2]
    in_contact = np.column_stack([~swings[side] for side in SIDES])
    return contact_switch_force_jumps(normal, in_contact, round(walk.transition / walk.dt))


# -- plots ------------------------------------------------------------------------------------------
def draw_plan(axes: plt.Axes, plan: FootstepPlan) -> None:
    """The double-support polygons (grey) and every footprint (one colour per foot), seen from above."""
    for phase in plan.phases:
        if phase.kind == "double":
            stance = plan.stance_placements(0.5 * (phase.start + phase.end))
            hull = convex_hull(np.vstack([plan.sole.corners(p)[:, :2] for p in stance.values()]))
            axes.fill(hull[:, 0], hull[:, 1], color="0.85", alpha=0.5, zorder=0)
    placements = [("left", plan.initial_left), ("right", plan.initial_right)]
    placements += [(step.side, step.placement) for step in plan.steps]
    for side, placement in placements:
        corners = plan.sole.corners(placement)[:, :2]
        axes.fill(corners[:, 0], corners[:, 1], fill=False, color="tab:blue" if side == "left" else "tab:red",
                  linewidth=0.8, zorder=1)


def stretch_across(axes: plt.Axes) -> int:
    """The whole factor y is stretched by in a top view so that it is at least a quarter as tall as wide."""
    (x_low, x_high), (y_low, y_high) = axes.get_xlim(), axes.get_ylim()
    return max(1, round(0.25 * (x_high - x_low) / (y_high - y_low)))


def plot_walk(path: Path, walk: Walk, result: dict[str, object]) -> None:
    """The walk's figure: the top view above, x and y over time below."""
    mask, data = result["mask"], walk.data
    t = data["time"][mask]
    series = [("CoM (true)", result["com"][mask], dict(color="k", linewidth=1.4)),
              ("CoM plan", data["pattern.com_position"][mask], dict(color="k", linewidth=1.0, linestyle="--")),
              ("ZMP plan", data["pattern.zmp"][mask], dict(color="tab:green", linewidth=1.4)),
              ("ZMP measured (ankle F/T)", data["zmp.zmp"][mask], dict(color="tab:olive", linewidth=0.6)),
              ("DCM plan", data["pattern.dcm"][mask], dict(color="tab:purple", linewidth=1.4)),
              ("DCM measured", result["dcm"][mask], dict(color="tab:orange", linewidth=0.8, linestyle=":"))]
    figure = plt.figure(figsize=(14, 9), constrained_layout=True)
    grid = figure.add_gridspec(2, 2, height_ratios=(1.0, 1.0))
    top, along, across = figure.add_subplot(grid[0, :]), figure.add_subplot(grid[1, 0]), figure.add_subplot(grid[1, 1])
    draw_plan(top, walk.plan)
    for label, xy, style in series:
        top.plot(xy[:, 0], xy[:, 1], label=label, **style)
        along.plot(t, xy[:, 0], **style)
        across.plot(t, xy[:, 1], **style)
    stretch = stretch_across(top)
    top.set(aspect=stretch, xlabel="x (m)", ylabel="y (m)", title=f"{walk.name}: top view" + (
        f", y stretched ×{stretch}" if stretch > 1 else "") + (
        f" (fell at {result['fall']:.2f} s)" if result["fall"] is not None else ""))
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9)
    along.set(xlabel="time (s)", ylabel="x (m)", title="along the walk")
    across.set(xlabel="time (s)", ylabel="y (m)", title="across the walk")
    for axes in (top, along, across):
        axes.grid(alpha=0.3)
    figure.savefig(path, dpi=80)
    plt.close(figure)


# -- the peer -----------------------------------------------------------------------------------------
def open_loop_pattern(plan: FootstepPlan, initial_com: np.ndarray, params: dict[str, object],
                      dt: float) -> dict[str, object]:
    """Our ZmpPatternGenerator with the walk's ``params`` and ``feedback = 0`` on ``plan`` from
    ``initial_com`` at rest, sampled at every tick from the plan's start to its end (``time``: plan
    time); its solve times and settings."""
    graph = dg.Graph(dt=dt)
    pattern = graph.add(ZmpPatternGenerator("pattern", **{**params, "feedback": 0.0}))
    pattern.plan.set(plan)
    pattern.estimated_com_position.set(initial_com)
    pattern.estimated_com_velocity.set(np.zeros(3))
    names = ("com_position", "com_acceleration", "zmp", "dcm")
    samples: dict[str, list] = {name: [] for name in names}
    solve_times = []
    first = round(plan.start / dt)  # before it, the generator plans standing: stepped, not sampled
    for t in range(first + round(plan.duration / dt) + 1):
        com_plan = pattern.com_plan(t)
        if com_plan.replan_tick == t:
            solve_times.append(com_plan.solve_time)
        if t >= first:
            for name in names:
                samples[name].append(getattr(pattern, name)(t).copy())
        graph.step()
    return {"time": np.arange(len(samples["zmp"])) * dt, **{name: np.array(values) for name, values in samples.items()},
            "plan_time": solve_times[0], "replan_times": np.array(solve_times[1:]),
            **{name: getattr(pattern, name) for name in ("margin", "period", "sampling", "horizon")}}


def placo_plan(plan: FootstepPlan, initial_com: np.ndarray, margin: float, out: Path,
               tag: str) -> dict[str, np.ndarray]:
    """placo's plan of ``plan`` (bench/peer_placo.py in .venv-placo) from ``initial_com`` at rest,
    its LIPM at that CoM's height above the ground, the support polygons shrunk by ``margin``."""
    ground = 0.5 * (plan.initial_left[2, 3] + plan.initial_right[2, 3])
    request = {**plan.to_plain(), "com_height": float(initial_com[2] - ground), "margin": margin,
               "initial_com": initial_com.tolist()}
    plan_path, result_path = out / f"placo_{tag}.json", out / f"placo_{tag}.npz"
    plan_path.write_text(json.dumps(request, indent=1))
    subprocess.run([str(PLACO_PYTHON), str(ROOT / "bench" / "peer_placo.py"), str(plan_path), str(result_path)],
                   check=True, env=single_threaded_env(), stdout=subprocess.DEVNULL)
    with np.load(result_path) as result:
        return dict(result)


def plan_quality(samples: dict[str, np.ndarray], plan: FootstepPlan) -> dict[str, float]:
    """ZMP margin to the plan's support polygon (min, share outside), CoM jerk (RMS, peak), the
    DCM at the plan's end against the final support (distance to its midpoint, margin to its edge)."""
    times = samples["time"]
    polygons = SupportPolygons(plan, 0.0)
    margin = polygon_margin(samples["zmp"][:, :2], *polygons.at(times))
    jerk_rms, jerk_peak = jerk_statistics(samples["com_acceleration"][:, :2], float(times[1] - times[0]))
    end_dcm = samples["dcm"][-1:, :2]
    return {"margin_min": float(margin.min()), "outside": float(np.mean(margin < 0.0)), "jerk_rms": jerk_rms,
            "jerk_peak": jerk_peak, "dcm_to_midpoint": float(np.linalg.norm(end_dcm[0] - plan.final_midpoint()[:2])),
            "dcm_margin": float(polygon_margin(end_dcm, *polygons.at(times[-1:]))[0])}


def compare_planners(walks: list[Walk], results: dict[str, dict], out: Path) -> list[dict[str, object]]:
    """Ours and placo's plans of each distinct footstep plan of the walks that ran."""
    comparisons: dict[str, dict[str, object]] = {}
    for walk in walks:
        if walk.plan is None:
            continue
        key = json.dumps(walk.plan.to_plain())
        if key in comparisons:
            comparisons[key]["walks"].append(walk.name)
            continue
        initial_com = results[walk.name]["com"][round(walk.plan.start / walk.dt)]
        ours = open_loop_pattern(walk.plan, initial_com, walk.pattern_params, walk.dt)
        lipm_com = np.r_[initial_com[:2], ours["com_position"][-1, 2]]  # at our LIPM's height (com_height)
        placo = placo_plan(walk.plan, lipm_com, ours["margin"], out, walk.name)
        comparisons[key] = {"walks": [walk.name], "ours": ours, "placo": placo,
                            "quality": {"ours": plan_quality(ours, walk.plan), "placo": plan_quality(placo, walk.plan)}}
        print(f"planners on the plan of {walk.name}: done", flush=True)
    return list(comparisons.values())


# -- the document -------------------------------------------------------------------------------------
def table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


def triple(values: tuple[float, ...] | np.ndarray, scale: float = 1e3, digits: int = 1) -> str:
    """``a / b / c`` scaled (default: m to mm)."""
    return " / ".join(f"{scale * v:.{digits}f}" for v in values)


def statistics(error: object, axis: int) -> tuple[float, float, float]:
    """A TrackingError's average / std / peak on one axis."""
    return error.mean[axis], error.std[axis], error.peak[axis]


def fell(result: dict[str, object]) -> str | None:
    """``fell at X s`` if the robot fell, None otherwise."""
    return None if result["fall"] is None else f"fell at {result['fall']:.2f} s"


def labelled(walk: Walk, result: dict[str, object]) -> str:
    """The graph's name, with its fall if it fell (for the tables that still give numbers)."""
    return walk.name if result["fall"] is None else f"{walk.name} ({fell(result)}: until then)"


def thesis_label(walk: Walk) -> str:
    """The thesis's scheme and walk this graph stands for."""
    return "—" if walk.thesis is None else f"{walk.thesis[0]}, {walk.thesis[1]}"


def summary_table(walks: list[Walk], results: dict[str, dict]) -> str:
    """Outcome of every walk: fall, final base against the plan's final midpoint, wall time."""
    rows = []
    for walk in walks:
        if walk.problem is not None:
            rows.append([walk.name, thesis_label(walk), walk.problem, "—", "—", "—", "—"])
            continue
        result = results[walk.name]
        base, midpoint = result["final_base"], result["final_midpoint"]
        outcome = fell(result) or f"walked to the end ({len(result['mask']) * walk.dt:.1f} s)"
        rows.append([walk.name, thesis_label(walk), outcome, f"{base[0]:.3f}, {base[1]:.3f}",
                     f"{midpoint[0]:.3f}, {midpoint[1]:.3f}",
                     "—" if result["fall"] is not None else f"{1e3 * np.linalg.norm(base - midpoint):.0f}",
                     f"{walk.wall:.0f} s ({result['real_time_factor']:.2f})"])
    return table(["graph", "thesis", "outcome", "base x, y at the end (m)", "plan's final midpoint x, y (m)",
                  "distance (mm)", "wall time (real-time factor)"], rows)


def zmp_rows(walk: Walk, result: dict[str, object]) -> list[list[str]]:
    """The ZMP error rows of one walk: against the plan, and against p* where there is a stabiliser;
    the thesis's numbers on the row of its reference (p* for the position schemes when we have it)."""
    references = [("planned ZMP (`pattern.zmp`)", "zmp")]
    if "zmp_desired" in result:
        references.append(("stabiliser's p* (Eq. 2.30)", "zmp_desired"))
    thesis = THESIS_ZMP.get(walk.thesis)
    position_scheme = walk.thesis is not None and walk.thesis[0] != "TSID torque"
    thesis_key = "zmp_desired" if position_scheme and "zmp_desired" in result else "zmp"
    rows = []
    for label, key in references:
        ours = [fell(result)] * 2 if fell(result) else [triple(statistics(result[key], axis)) for axis in (0, 1)]
        theirs = [triple(thesis[axis]) if thesis is not None and key == thesis_key else "—" for axis in (0, 1)]
        rows.append([walk.name, label, ours[0], theirs[0], ours[1], theirs[1]])
    return rows


def zmp_table(walks: list[Walk], results: dict[str, dict]) -> str:
    rows = [row for walk in walks if walk.problem is None for row in zmp_rows(walk, results[walk.name])]
    return table(["graph", "measured ZMP against", "x ours", "x thesis", "y ours", "y thesis"], rows)


def tracking_table(walks: list[Walk], results: dict[str, dict]) -> str:
    rows = []
    for walk in (w for w in walks if w.problem is None):
        result, thesis = results[walk.name], THESIS_TRACKING.get(walk.thesis, {})
        for body, error in result["tracking"].items():
            ours = [fell(result)] * 2 if fell(result) else [triple(statistics(error, axis)) for axis in (0, 1)]
            theirs = [triple(thesis[body][axis]) if body in thesis else "—" for axis in (0, 1)]
            rows.append([walk.name, body, ours[0], theirs[0], ours[1], theirs[1]])
    return table(["graph", "body", "x ours", "x thesis (Table 4.5)", "y ours", "y thesis (Table 4.5)"], rows)


def energy_table(walks: list[Walk], results: dict[str, dict]) -> str:
    rows = []
    for walk in (w for w in walks if w.problem is None):
        result, thesis = results[walk.name], THESIS_COT.get(walk.thesis)
        if fell(result):
            ours = [fell(result)] * 3
        else:
            ours = [f"{result['energy'][0]:.1f} / {result['energy'][1]:.1f}",
                    f"{result['cot'][0]:.2f} / {result['cot'][1]:.2f}", f"{result['distance']:.3f}"]
        theirs = ["—", "—"] if thesis is None else [f"{thesis[0]} / {thesis[1]}", f"{thesis[2]} / {thesis[3]}"]
        rows.append([walk.name, ours[0], theirs[0], ours[1], theirs[1], ours[2]])
    return table(["graph", "E_m / E_m⁺ (J) ours", "thesis", "C_et / C_mt ours", "thesis", "D (m)"], rows)


def pgm_table(walks: list[Walk], results: dict[str, dict]) -> str:
    rows = []
    for walk in (w for w in walks if w.problem is None):
        result, thesis = results[walk.name], THESIS_PGM.get(walk.thesis)
        pgm = result["pgm"]
        ours = fell(result) or " / ".join(
            f"{v:.2f}" for v in (pgm.double_support, pgm.single_support, pgm.flying_foot))
        rows.append([walk.name, ours, "—" if thesis is None else " / ".join(f"{v:.2f}" for v in thesis)])
    return table(["graph", "double support / single support / flying foot, ours", "thesis"], rows)


def tick_table(walks: list[Walk], results: dict[str, dict], cal: dict[str, object]) -> str:
    rows = []
    for walk in (w for w in walks if w.problem is None):
        tick, thesis = results[walk.name]["tick"], THESIS_TICK.get(walk.thesis)
        statistics_ms = triple((tick.mean, tick.median, tick.p99, tick.peak), digits=2)
        rows.append([labelled(walk, results[walk.name]), statistics_ms,
                     f"{in_loops(tick.mean * 1e9, cal):.0f} / {in_loops(tick.peak * 1e9, cal):.0f}",
                     f"{100 * tick.overruns:.1f}", "—" if thesis is None else f"{thesis[0]} / {thesis[1]}"])
    return table(["graph", "mean / median / p99 / peak (ms)", "mean / peak (calibration loops)",
                  "ticks over 1 ms (%)", "thesis average / peak (ms)"], rows)


def force_table(walks: list[Walk], results: dict[str, dict]) -> str:
    rows = []
    for walk in (w for w in walks if w.problem is None):
        result = results[walk.name]
        limit = FORCE_JUMP_LIMIT * result["weight"]
        jumps = result["force_jumps"]
        if jumps is None:
            rows.append([labelled(walk, result), "no `solver.contact_wrenches`", "—", f"{limit:.1f}", "—"])
            continue
        cells = ["no contact switch" if jump is None else
                 f"{jump.largest:.1f} ({100 * jump.largest / result['weight']:.2f} %) at {jump.tick * walk.dt:.3f} s"
                 for jump in jumps]
        ok = all(jump is not None and jump.largest < limit for jump in jumps)
        rows.append([labelled(walk, result), *cells, f"{limit:.1f}", "yes" if ok else "no"])
    return table(["graph", "left foot: N per tick (% of weight), at", "right foot", "5 % of the weight (N)",
                  "below"], rows)


def planner_table(comparison: dict[str, object], cal: dict[str, object]) -> str:
    """Ours against placo on one plan."""
    ours, placo, quality = comparison["ours"], comparison["placo"], comparison["quality"]

    def times(samples: dict[str, object]) -> list[str]:
        plan, replans = float(samples["plan_time"]), np.asarray(samples["replan_times"], dtype=float)
        median = float(np.median(replans)) if replans.size else float("nan")
        return [f"{1e6 * plan:.0f} µs ({in_loops(plan * 1e9, cal):.0f})",
                f"{1e6 * median:.0f} µs ({in_loops(median * 1e9, cal):.0f}), {replans.size} re-plans"]

    settings = [f"LIPM MPC, N {ours['horizon']} × T {ours['sampling']:g} s, re-plan every {1e3 * ours['period']:g} ms, "
                f"open loop (feedback 0)",
                f"placo {placo['placo_version']}, horizon {int(placo['horizon'])} LIPM steps, re-plan every "
                f"≥ {float(placo['replan_period']):g} s"]
    rows = [["planner", *settings], ["initial plan (calibration loops)", *[times(s)[0] for s in (ours, placo)]],
            ["re-plan median (calibration loops)", *[times(s)[1] for s in (ours, placo)]]]
    metrics = [("ZMP distance to the support polygon edge, min (mm)", "margin_min", 1e3, 1),
               ("samples with the ZMP outside (%)", "outside", 100, 2),
               ("CoM jerk RMS (m/s³)", "jerk_rms", 1, 2), ("CoM jerk peak (m/s³)", "jerk_peak", 1, 1),
               ("DCM at the plan's end: distance to the final midpoint (mm)", "dcm_to_midpoint", 1e3, 2),
               ("DCM at the plan's end: distance to the final polygon edge, > 0 inside (mm)", "dcm_margin", 1e3, 1)]
    rows += [[label, *[f"{scale * quality[who][key]:.{digits}f}" for who in ("ours", "placo")]]
             for label, key, scale, digits in metrics]
    return table(["", "ours (ZmpPatternGenerator)", "placo"], rows)


DIFFERENCES = """\
- **Simulator**: the thesis ran Gazebo (L4672); these walks run MuJoCo (its contact model, soft
  constraints, and ankle F/T sensors read from it), so the numbers are an envelope, not targets.
- **Pattern generator**: the thesis's is the NMPC of Naveau et al. with Kajita's dynamic filter on the
  whole-body ZMP (L1549-1567; in jrl-walkgen's public code: CoM jerk and two footsteps as variables,
  SQP with qpOASES); ours is a linear LIPM MPC on ProxQP over fixed footsteps, without the dynamic
  filter, re-planned every `period` from a blend of the estimated and the planned CoM state
  (`feedback`, per graph below).
- **ZMP reference**: for the torque scheme the thesis compared the estimated ZMP to the planned one,
  for the position schemes to the stabiliser's ZMP reference p* of Eq. 2.30 (L4693-4699); both are
  given above where the graph has them.
- **Timing**: the thesis's control loop is C++ (the SoT and TSID); ours is Python calling Pinocchio
  and ProxQP, timed on the machine above with other processes running (see the load).
- **Actuation**: the torque walks send the QP's torques to MuJoCo's motors; the position walks close
  stiff joint PD servos in the simulated device, where the thesis's Gazebo model had the PID gains
  of a low-level position control (high on the ankles, L4712-4714).
- **Gaps the thesis leaves** (walking notes §1.4): the CoM height (ours: the standing robot's, or the
  graph's `pattern.com_height`), the step width 0.17 m, the swing height 0.05 m and the sole size are
  gap-fillers.
"""


def document(command: str, walks: list[Walk], results: dict[str, dict], comparisons: list[dict[str, object]],
             calibrations: tuple[dict[str, object], dict[str, object]], load: float, images: list[str]) -> str:
    """The whole of docs/walking.md."""
    before, after = calibrations
    parts = [
        "# Walking: TALOS in MuJoCo against the thesis and placo\n",
        f"Written by `{command}` on {time.strftime('%Y-%m-%d %H:%M')}; every number below comes from that run "
        "(thesis numbers: `/work/shared/reference/walking_mptc_actuators_drilling.md` §1.7, cited per table). "
        "Do not edit: run the command again.\n",
        f"Machine: {platform.platform()}, {before['cpu']}, {before['vcpus']} vCPU, {before['python']}; "
        f"other processes kept {load:.2f} CPUs busy on average during the run.\n",
        f"- before: {calibration_line(before)}\n- after: {calibration_line(after)}\n",
        "A time in calibration loops is the time divided by the first figure (bench/calibration.py).\n",
        "## The walks\n",
        "Each graph runs to its duration, or stops at the tick the robot falls (`device.fallen`: the base below "
        "0.6 m); every gait metric is taken on the ticks before the fall, and a walk that fell shows its fall "
        "instead. The base's position is `device.q` (the simulator's), the plan's final midpoint "
        "`FootstepPlan.final_midpoint()`.\n",
        summary_table(walks, results),
        "\n## ZMP error (Table 4.4, 20 cm walk [L4659-4668])\n",
        "Average / std / peak of |p - p_ref| in mm, per axis, p the ZMP of the ankle F/T sensors (`zmp.zmp`, "
        f"the robot's estimate, as the thesis's), on every tick from {1e3 * ZMP_SETTLING:g} ms to the end or the "
        "fall (the initial and final double supports included; the first ticks are left out: MuJoCo's initial "
        "contact state gives the F/T ZMP a start-up transient of a few ticks).\n",
        zmp_table(walks, results),
        "\n## CoM and feet tracking (Table 4.5, 60 cm walk [L4743-4754])\n",
        "Average / std / peak in mm of the true CoM (Pinocchio on `device.q`) against `pattern.com_position` and of "
        "the true sole frames against the swing references (`left_swing.position`, `right_swing.position`, the "
        "placement the foot stands on outside its swings). The thesis gives a table for the 60 cm walk only; for the "
        "20 cm walk it says every scheme tracks the CoM and the feet within 1 cm [L4689-4691].\n",
        tracking_table(walks, results),
        "\n## Cost of transport (Table 4.8 [L4888-4910], Eq. 4.16)\n",
        f"m = {robot_mass():.2f} kg (the model's). "
        "E_m = ∫ Σ|τ_i ω_i| dt, E_m⁺ its positive part (applied torques `device.joint_torque`, joint velocities "
        "`device.v`), C = E / (m g D) with m the model's mass and D the distance the plan travels, from the "
        "midpoint of the initial soles to the final one (the thesis's \"traveled distance of 1.2 m\" [L4682]).\n",
        energy_table(walks, results),
        "\n## Passivity gait measure per gait stage (Table 4.9 [L4912-4930], Eq. 4.17-4.18)\n",
        "PGM = 1 - RMS(τ_ankle) / RMS(τ_all joints) with the ankle pitch and roll joints (leg_*_5, leg_*_6): both "
        "ankles in double support (`schedule.double_support`), the stance ankle in single support and the swinging "
        "foot's ankle for the flying foot (`schedule.left_swing`, `schedule.right_swing`).\n",
        pgm_table(walks, results),
        "\n## Control tick (Table 4.10 [L4932-4940])\n",
        "The control graph's evaluation per tick (`timed` of bench/compare_schemes.py: every plugged input of the "
        "device pulled; the simulator's step and the recorder excluded), first tick left out.\n",
        tick_table(walks, results, before),
        "\n## Normal-force jumps at the contact switches\n",
        "The largest |f_z[k] - f_z[k-1]| of each foot's contact force from the QP (`solver.contact_wrenches`) on "
        "the ticks within the scheduler's `transition` of a lift-off or touch-down of either foot; the acceptance "
        "of issue 13 is below 5 % of the robot's weight per tick.\n",
        force_table(walks, results),
        "\n## Plots\n",
        "Top view: footprints (left blue, right red), double-support polygons (grey), the true CoM, the planned "
        "CoM, ZMP and DCM, the measured ZMP (ankle F/T) and DCM (true CoM + its velocity / ω); right: the same "
        "along and across the walk.\n",
        "\n".join(f"![{image}]({image})" for image in images),
        "\n## The peer: placo's walk pattern generator\n",
        peer_text(comparisons, before),
        "\n## What differs from the thesis\n",
        DIFFERENCES,
        pattern_settings(walks),
    ]
    return "\n".join(parts)


def pattern_settings(walks: list[Walk]) -> str:
    """The pattern generator's settings each walk graph gives (the rest are its defaults)."""
    rows = [[walk.name, ", ".join(f"`{name}` {value}" for name, value in walk.pattern_params.items()) or "defaults"]
            for walk in walks if walk.problem is None]
    return "Pattern generator settings per graph (`pattern.*`; the others are ZmpPatternGenerator's defaults):\n\n" \
        + table(["graph", "settings"], rows)


def peer_text(comparisons: list[dict[str, object]], cal: dict[str, object]) -> str:
    """The placo section: how, then one table per plan."""
    if not comparisons:
        return "Not run (`--no-placo`, or no walk ran).\n"
    text = ["Both planners plan the same footstep plan (the walk graph's `footsteps.plan`, given to "
            "bench/peer_placo.py as `FootstepPlan.to_plain()` JSON), from the walk's true CoM (x, y) at the plan's "
            "start, at rest, with our LIPM's CoM height above the ground (the pattern generator's `com_height`, or "
            "the standing CoM's) and the same margin of the support polygons. Ours is "
            "the ZmpPatternGenerator with the walk graph's parameters run open loop (`feedback = 0`, no robot), as "
            "placo's own loop is (each re-plan from its own trajectory), sampled every 1 ms to the plan's end. Plan "
            "times are ours `ComPlan.solve_time` (QP assembly + ProxQP) and placo's `plan` / `replan` calls, "
            "medians in µs and calibration loops. The ZMP's distance is to the plan's support polygon "
            "(`FootstepPlan.support_polygon`, no margin) at each sample; the CoM jerk is the difference of the "
            "sampled CoM acceleration (x, y) over 1 ms; the DCM is the one of the plan's last sample.\n"]
    for comparison in comparisons:
        text += [f"\n**The plan of {', '.join(comparison['walks'])}**\n", planner_table(comparison, cal)]
    return "\n".join(text)


def main() -> None:
    """Run the walks, evaluate them, plan with both planners, write the document."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--graphs", nargs="+", default=list(WALKS), help="graph names (graphs/) or .yaml paths")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "walking")
    parser.add_argument("--doc", type=Path, default=ROOT / "docs" / "walking.md")
    parser.add_argument("--no-placo", action="store_true", help="leave the placo peer out")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    args.doc.parent.mkdir(parents=True, exist_ok=True)
    if not args.no_placo and not PLACO_PYTHON.exists():
        subprocess.run(["bash", str(ROOT / "bench" / "setup_placo.sh")], check=True)
    before = calibrate()
    busy = BusyMeter().start()
    walks = [Walk(Path(graph).stem, graph_path(graph)) for graph in args.graphs]
    for walk in walks:
        run(walk, args.out)
        print(f"{walk.name}: {walk.problem or f'ran ({walk.wall:.0f} s)'}", flush=True)
    results = {walk.name: evaluate(walk) for walk in walks if walk.problem is None}
    images = []
    for name, result in results.items():
        images.append(f"walking_{name}.png")
        plot_walk(args.doc.parent / images[-1], next(w for w in walks if w.name == name), result)
    comparisons = [] if args.no_placo else compare_planners(walks, results, args.out)
    load = busy.stop()
    after = calibrate()
    command = " ".join([".venv/bin/python", "bench/walking.py", *sys.argv[1:]])
    text = document(command, walks, results, comparisons, (before, after), load, images)
    args.doc.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
