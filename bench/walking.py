"""TALOS's walks in MuJoCo against the thesis (Ch. 4.4.4, Tables 4.4-4.10) and placo's walk pattern generator.

    .venv/bin/python bench/walking.py [--graphs talos_walk_20cm ... | --terrain] [--out out/walking]
        [--doc docs/walking.md] [--no-placo]

Runs each walking graph (a name in graphs/ or a .yaml path; default: every graph of ``WALKS``: the
flat 20 cm and 60 cm walks, the stairs, the tilted platforms in the three schemes and the 2 cm
obstacles; ``--terrain``: only the last ones) to its end or to the robot's fall, with the graph's
own recorders and views taken out and one Recorder of what the evaluation reads, the control
graph timed per tick as bench/compare_schemes.py does (``timed``). A graph file that does not
exist is reported as such. The robot has fallen when its base is less than ``FALL_HEIGHT`` above
the terrain under it (``footsteps.walked_terrain``; on flat ground the device's ``fallen``).
Evaluated with :mod:`dgraph.evaluation` on the ticks before a fall, against the simulator's ground
truth (the true CoM and soles from ``device.q``):

- ZMP error (Tables 4.4, 4.6, 4.7, from ``ZMP_SETTLING``): the ankle F/T ZMP (``zmp.zmp``, on the
  plane the pattern generator plans in, ``pattern.zmp_plane_height``) against the planned one
  (``pattern.zmp``), horizontal axes, and, where the graph has a DCM stabiliser, against its
  desired ZMP ``p*`` (Eq. 2.30), the reference the thesis used for the position schemes (L4693-4699);
- CoM and feet tracking (Table 4.5): the true CoM against ``pattern.com_position``, the true
  soles against ``left_swing.position`` / ``right_swing.position``; the CoM's height too;
- E_m, E_m+, C_et, C_mt (Table 4.8, Eq. 4.16; D: the plan's horizontal distance from the initial
  to the final midpoint of the soles, the thesis's "traveled distance", L4682), the PGM per gait
  stage (Table 4.9, Eq. 4.17-4.18; stages from ``schedule.double_support`` / ``left_swing`` /
  ``right_swing``), the control tick (Table 4.10) with the calibration figure;
- the final base position against the plan's final midpoint, the fall and the signs before it
  (the QP's or the pattern generator's status, a slipping stance sole, a swinging foot off its
  path, the measured ZMP at the support polygon's edge, the CoM off its plan);
- the largest foot slip: per stance interval of a foot (``schedule.<side>_contact`` and not
  ``<side>_swing``), the largest horizontal distance of its true sole from where it stood
  ``SLIP_SETTLING`` into the interval;
- the largest per-tick change of each foot's normal force (``solver.contact_wrenches``) within
  the scheduler's ``transition`` of a contact switch, against 5 % of the robot's weight.

One figure per walk (docs/walking_<graph>.png): the top view of the CoM, planned and measured
ZMP and DCM over the footprints and double-support polygons (and the terrain's surfaces), their x
and y over time, and on a terrain a side view (x-z): the surfaces, the terrain under each foot's
line, the planned and true CoM, the true soles' and their references' paths.

The peer (unless ``--no-placo``; bench/setup_placo.sh makes .venv-placo when it is missing):
bench/peer_placo.py plans each flat walk's own footstep plan (``FootstepPlan.to_plain()``, the
same CoM height, margin and initial CoM), and our ZmpPatternGenerator, with the walk graph's
parameters and ``feedback = 0``, plans it open loop in the same run (placo's output is open loop
too: each re-plan starts from its own trajectory). Compared: plan and re-plan times (with the
calibration), the ZMP's distance to the plan's support polygon edge (min, share of samples
outside), the CoM jerk (RMS, peak) and the DCM at the plan's end against the final support.
placo's LIPM walks on one plane: the plans over a terrain are left out.

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
from collections.abc import Callable  # noqa: E402
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
from dgraph.entities.walking.terrain import Terrain  # noqa: E402
from dgraph.errors import DGraphError  # noqa: E402
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
FLAT_WALKS = ("20 cm", "60 cm")
WALKS = {  # graph -> (the thesis's scheme, walk), in the order of the document's tables
    "talos_walk_20cm": ("TSID torque", "20 cm"),
    "talos_walk_60cm": ("TSID torque", "60 cm"),
    "talos_walk_20cm_ik": ("IK", "20 cm"),
    "talos_walk_20cm_tsid_position": ("TSID position", "20 cm"),
    "talos_stairs_ik": ("IK", "Stairs"),
    "talos_stairs_tsid_position": ("TSID position", "Stairs"),
    "talos_stairs": ("TSID torque", "Stairs"),
    "talos_platforms_ik": ("IK", "Platforms"),
    "talos_platforms_tsid_position": ("TSID position", "Platforms"),
    "talos_platforms": ("TSID torque", "Platforms"),
    "talos_obstacles": ("TSID torque", "Obstacles 2 cm"),
}
TERRAIN_GRAPHS = [name for name, (_, walk) in WALKS.items() if walk not in FLAT_WALKS]
FLAT_REFERENCE = "talos_walk_20cm"  # the flat walk whose gains talos_obstacles must keep
REQUIRED = ["device.q", "device.joint_torque", "device.v", "device.fallen", "zmp.zmp", "pattern.zmp",
            "pattern.com_position", "pattern.dcm", "left_swing.position", "right_swing.position",
            "schedule.double_support", "schedule.left_swing", "schedule.right_swing", "schedule.left_contact",
            "schedule.right_contact"]
OPTIONAL = ["solver.contact_wrenches", "stabilizer.desired_zmp", "solver.status", "pattern.status"]
FORCE_JUMP_LIMIT = 0.05  # of the robot's weight per tick: the acceptance of issue 13
ZMP_SETTLING = 0.05  # s left out of the ZMP errors: the F/T start-up transient of MuJoCo's initial contact state
FALL_HEIGHT = 0.6  # m of the base above the terrain under it: TALOS's fall_height (sim/robots.py) above z = 0
SLIP_SETTLING = 0.150  # s into a stance interval at which the sole's position becomes the slip's origin
SLIP_LIMIT = 0.02  # m: the largest slip issue 14 accepts
SWING_OFF_PATH = 0.03  # m of a swinging sole from its reference: a sign before a fall
COM_OFF_PLAN = 0.05  # m of the true CoM from its plan, horizontally: a sign before a fall
LOW_RELIEF = 0.05  # m: a terrain lower than this is drawn from the side zoomed on the feet
SIDE_COLOURS = {"left": "tab:blue", "right": "tab:red"}
PLACO_PYTHON = ROOT / ".venv-placo" / "bin" / "python"

# The thesis (Gazebo), /work/shared/reference/walking_mptc_actuators_drilling.md §1.7, keyed by (scheme, walk).
THESIS_ZMP = {  # m: (average, std, peak) per axis x, y
    # Table 4.4 [L4659-4668], the 20 cm walk
    ("IK", "20 cm"): ((0.019, 0.022, 0.131), (0.022, 0.026, 0.150)),
    ("TSID position", "20 cm"): ((0.028, 0.025, 0.142), (0.025, 0.027, 0.138)),
    ("TSID torque", "20 cm"): ((0.026, 0.021, 0.078), (0.011, 0.014, 0.078)),
    # Table 4.6 [L4826-4835], the tilted platforms
    ("IK", "Platforms"): ((0.021, 0.024, 0.278), (0.016, 0.018, 0.118)),
    ("TSID position", "Platforms"): ((0.012, 0.017, 0.197), (0.015, 0.019, 0.127)),
    ("TSID torque", "Platforms"): ((0.013, 0.021, 0.107), (0.005, 0.006, 0.058)),
    # Table 4.7 [L4857-4866], the stairs
    ("IK", "Stairs"): ((0.022, 0.026, 0.257), (0.015, 0.017, 0.151)),
    ("TSID position", "Stairs"): ((0.009, 0.013, 0.151), (0.012, 0.015, 0.119)),
    ("TSID torque", "Stairs"): ((0.008, 0.006, 0.049), (0.006, 0.005, 0.047)),
}
THESIS_TRACKING = {  # Table 4.5 [L4743-4754], m: body -> (average, std, peak) per axis x, y; 60 cm, torque
    ("TSID torque", "60 cm"): {"CoM": ((0.018, 0.013, 0.050), (0.004, 0.003, 0.015)),
                               "left foot": ((0.014, 0.013, 0.063), (0.001, 0.001, 0.005)),
                               "right foot": ((0.016, 0.016, 0.063), (0.001, 0.001, 0.006))},
}
THESIS_COT = {  # Table 4.8 [L4888-4910]: E_m J, E_m+ J, C_et, C_mt
    ("IK", "20 cm"): (1983.9, 1359.3, 1.68, 1.15), ("TSID position", "20 cm"): (2324.5, 764.1, 1.97, 0.65),
    ("TSID torque", "20 cm"): (521.8, 259.3, 0.44, 0.22), ("TSID torque", "60 cm"): (3147.2, 1583.8, 0.89, 0.45),
    ("IK", "Platforms"): (5418.7, 3769.2, 3.7, 2.6), ("TSID position", "Platforms"): (5377.5, 1413.6, 3.6, 2.0),
    ("TSID torque", "Platforms"): (1378.6, 668.5, 0.93, 0.45),
    ("IK", "Stairs"): (7249.5, 2145.3, 4.1, 1.2), ("TSID position", "Stairs"): (6812.6, 2059.6, 3.8, 1.2),
    ("TSID torque", "Stairs"): (1861.1, 1205.5, 1.1, 0.68),
}
THESIS_COT_ERRATUM = ("TSID position", "Platforms")  # its C_mt 2.0 does not follow from its E_m+ (walking notes §1.7)
THESIS_PGM = {  # Table 4.9 [L4912-4930]: double support, single support, flying foot
    ("IK", "20 cm"): (0.35, 0.89, 0.24), ("TSID position", "20 cm"): (0.37, 0.74, 0.37),
    ("TSID torque", "20 cm"): (0.93, 0.87, 1.0), ("TSID torque", "60 cm"): (0.87, 0.79, 1.0),
    ("IK", "Platforms"): (0.27, 0.85, 0.31), ("TSID position", "Platforms"): (0.27, 0.86, 0.30),
    ("TSID torque", "Platforms"): (0.87, 0.8, 0.91),
    ("IK", "Stairs"): (0.46, 0.86, 0.36), ("TSID position", "Stairs"): (0.55, 0.86, 0.34),
    ("TSID torque", "Stairs"): (0.97, 0.89, 1.0),
}
THESIS_TICK = {  # Table 4.10 [L4932-4940], ms: average, peak
    ("IK", "20 cm"): (0.5, 2.0), ("TSID position", "20 cm"): (1.2, 4.5),
    ("TSID torque", "20 cm"): (1.0, 2.8), ("TSID torque", "60 cm"): (1.4, 6.0),
    ("IK", "Platforms"): (0.7, 4.0), ("TSID position", "Platforms"): (1.2, 4.3),
    ("TSID torque", "Platforms"): (1.2, 5.0),
    ("IK", "Stairs"): (0.6, 4.0), ("TSID position", "Stairs"): (1.2, 4.2), ("TSID torque", "Stairs"): (1.1, 5.5),
}


@dataclass
class Walk:
    """One walking graph and its run: the recording, the control ticks' durations (s, the first
    tick left out), the wall time, whether the robot had fallen at each recorded tick (see
    :func:`has_fallen`), and what the evaluation reads from the graph; ``problem`` says why it did
    not run (the rest then stays empty)."""

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
    terrain: Terrain | None = None
    fallen: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def thesis(self) -> tuple[str, str] | None:
        """The thesis's (scheme, walk) this graph stands for, if any."""
        return WALKS.get(self.name)

    @property
    def on_terrain(self) -> bool:
        """Whether the walk is over a terrain (the thesis's platforms or stairs, or surfaces in its
        ``footsteps.walked_terrain``) rather than on flat ground."""
        if self.thesis is not None:
            return self.thesis[1] not in FLAT_WALKS
        return self.terrain is not None and bool(self.terrain.surfaces)


# -- running ----------------------------------------------------------------------------------------
def graph_path(graph: str) -> Path:
    """A graph's file: a .yaml path as given, else graphs/<name>.yaml."""
    return Path(graph) if graph.endswith(".yaml") else ROOT / "graphs" / f"{graph}.yaml"


def has_signal(graph: dg.Graph, name: str) -> bool:
    """Whether ``graph`` has the signal ``entity.signal``."""
    entity, _, signal = name.partition(".")
    return entity in graph and signal in graph[entity].ports


def one_line(error: Exception) -> str:
    """An error's message on one line."""
    return " ".join(str(error).split())


def prepared(walk: Walk, out: Path) -> dg.Graph | None:
    """The graph with its observers replaced by the evaluation's Recorder, or None (``walk.problem`` set)."""
    if not walk.path.is_file():
        shown = walk.path.relative_to(ROOT) if walk.path.is_relative_to(ROOT) else walk.path
        walk.problem = f"not run: {shown} does not exist"
        return None
    try:
        graph = dg.load(str(walk.path))
    except DGraphError as error:
        walk.problem = f"not run: the graph does not load: {one_line(error)}"
        return None
    for name in [name for name, entity in graph.entities.items() if entity.observes]:
        graph.remove(name)
    missing = [name for name in REQUIRED if not has_signal(graph, name)]
    if missing:
        walk.problem = f"not evaluated: the graph has no {', '.join(missing)}"
        return None
    recorded = REQUIRED + [name for name in OPTIONAL if has_signal(graph, name)]
    graph.add(Recorder("evaluation", signals=recorded, rerun="off", npz_path=str(out / f"{walk.name}.npz")))
    return graph


def has_fallen(terrain: Terrain, base: np.ndarray) -> bool:
    """Whether the base at ``base`` (x, y, z) is less than ``FALL_HEIGHT`` above the terrain under
    it: the device's ``fallen`` (base below 0.6 m) counted from the ground the robot is over, so
    that a robot lying on a tread or on the landing has fallen too."""
    return bool(base[2] - terrain.height_at(base[0], base[1]) < FALL_HEIGHT)


def run(walk: Walk, out: Path) -> None:
    """Run the walk's graph to its duration or to the fall, filling ``walk``."""
    graph = prepared(walk, out)
    if graph is None:
        return
    durations: list[float] = []
    timed(graph, durations)
    device, ticks = graph["device"], round(graph.duration / graph.dt)
    walk.terrain = graph["footsteps"].walked_terrain(0)
    fallen: list[bool] = []
    start = time.perf_counter()
    try:
        with graph, tqdm(total=ticks, unit="tick", desc=walk.name, mininterval=0.5) as bar:
            for tick in range(ticks):
                # this tick's state, recorded by the step
                fallen.append(bool(device.fallen(tick)) or has_fallen(walk.terrain, device.q(tick)[:3]))
                graph.step()
                bar.update()
                if fallen[-1]:
                    break
    except DGraphError as error:
        walk.problem = f"stopped at {(len(fallen) - 1) * graph.dt:.3f} s by an error: {one_line(error)}"
        return
    walk.wall, walk.fallen = time.perf_counter() - start, np.array(fallen)
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
    mask, fall = before_fall(walk.fallen), first_fall(walk.fallen)
    com, soles = true_com_and_frames(data["device.q"], [f"{side}_sole_link" for side in SIDES])
    result = {"fall": None if fall is None else fall * walk.dt, "mask": mask, "weight": robot_mass() * GRAVITY,
              "com": com, "soles": soles, "dcm": measured_dcm(walk, com)}
    result.update(tracking(walk, com, soles, mask))
    result.update(gait(walk, mask))
    result["slips"] = {side: largest_slip(drift) for side, drift in stance_drifts(walk, soles, mask).items()}
    result["fall_signs"] = None if fall is None else fall_signs(walk, result, fall)
    return result


def support_heights(walk: Walk) -> np.ndarray:
    """The height of the support the pattern generator carries the CoM over at each recorded tick
    (``FootstepPlan.support_height``: constant on flat ground, rising tread by tread on stairs)."""
    return np.array([walk.plan.support_height(walk.plan.time(t))[0] for t in walk.data["time"]])


def measured_dcm(walk: Walk, com: np.ndarray) -> np.ndarray:
    """The true DCM ``c + c_dot / omega`` (Eq. 2.27), ``c_dot`` by central differences of the true
    CoM, ``omega`` from the planned CoM height above the support (``support_heights``)."""
    omega = natural_frequency(walk.data["pattern.com_position"][:, 2] - support_heights(walk))
    return divergent_component(com, np.gradient(com, walk.dt, axis=0), omega)


def tracking(walk: Walk, com: np.ndarray, soles: np.ndarray, mask: np.ndarray) -> dict[str, object]:
    """The ZMP errors (Tables 4.4, 4.6, 4.7) and the CoM and feet tracking errors (Table 4.5), horizontal
    axes; the CoM's height against its plan."""
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
    result["com_height"] = tracking_error(com[:, 2:], data["pattern.com_position"][:, 2:], mask)
    return result


def gait(walk: Walk, mask: np.ndarray) -> dict[str, object]:
    """Energy and costs of transport (Table 4.8), PGM per stage (Table 4.9), force jumps, ticks
    (Table 4.10), the final base position."""
    data, dt, plan = walk.data, walk.dt, walk.plan
    swings = {side: data[f"schedule.{side}_swing"].astype(bool)[mask] for side in SIDES}
    model = load_model("talos")
    work, positive = mechanical_energy(data["device.joint_torque"][mask], data["device.v"][mask, 6:], dt)
    distance = float(np.linalg.norm(plan.final_midpoint()[:2] - plan.phases[0].zmp_from[:2]))
    com_height = walk.data["pattern.com_position"][mask, 2]
    return {
        "energy": (work, positive), "distance": distance,
        "climb": robot_mass() * GRAVITY * float(com_height[-1] - com_height[0]),
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


@dataclass(frozen=True)
class Slip:
    """A sole's largest slip (m, horizontal) and the tick it is reached."""

    largest: float
    tick: int


def stance_intervals(stance: np.ndarray) -> list[tuple[int, int]]:
    """The ``[start, end)`` tick ranges where ``stance`` is true."""
    edges = np.diff(np.r_[0, np.asarray(stance, dtype=int), 0])
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(), strict=True))


def stance_drift(sole_xy: np.ndarray, stance: np.ndarray, settle: int) -> np.ndarray:
    """Per tick, the horizontal distance (m) of a sole (``sole_xy``, ticks x 2) from where it stood
    ``settle`` ticks into its current stance interval (0 before then and outside stance)."""
    drift = np.zeros(len(stance))
    for start, end in stance_intervals(stance):
        anchor = start + settle
        if anchor < end:
            drift[anchor:end] = np.linalg.norm(sole_xy[anchor:end] - sole_xy[anchor], axis=1)
    return drift


def stance_drifts(walk: Walk, soles: np.ndarray, mask: np.ndarray) -> dict[str, np.ndarray]:
    """Each foot's :func:`stance_drift` on the ticks before the fall, a stance being the ticks where
    the foot is a contact of the controller and does not swing (``schedule.<side>_contact`` and not
    ``<side>_swing``), anchored ``SLIP_SETTLING`` into it."""
    settle = round(SLIP_SETTLING / walk.dt)
    drifts = {}
    for i, side in enumerate(SIDES):
        stance = walk.data[f"schedule.{side}_contact"].astype(bool) & ~walk.data[f"schedule.{side}_swing"].astype(bool)
        drifts[side] = stance_drift(soles[mask, i, :2], stance[mask], settle)
    return drifts


def largest_slip(drift: np.ndarray) -> Slip:
    """The largest value of a :func:`stance_drift` and its tick."""
    tick = int(np.argmax(drift))
    return Slip(float(drift[tick]), tick)


def fall_signs(walk: Walk, result: dict[str, object], fall: int) -> list[tuple[int, str]]:
    """What went wrong before the fall, each sign at the first tick it shows, in time order (none of
    them shows in the walks that do not fall): a status of the QP (``solver.status``) or of the
    pattern generator's re-plan (``pattern.status``) other than 0, a stance sole slipping more
    than ``SLIP_LIMIT``, a swinging sole more than ``SWING_OFF_PATH`` from its reference, the
    measured ZMP on or past the edge of the planned support polygon (a sole rolling over its edge,
    or the feet off their planned footprints), the true CoM more than ``COM_OFF_PLAN`` off its plan horizontally."""
    data, before = walk.data, slice(fall)
    conditions = [(f"`{name}` {int(data[name][before][np.argmax(data[name][before] != 0)])}",
                   data[name][before] != 0) for name in ("solver.status", "pattern.status") if name in data]
    drifts = stance_drifts(walk, result["soles"], result["mask"])
    for i, side in enumerate(SIDES):
        conditions.append((f"{side} sole slipping > {1e2 * SLIP_LIMIT:g} cm", drifts[side][before] > SLIP_LIMIT))
        off_path = np.linalg.norm(result["soles"][before, i] - data[f"{side}_swing.position"][before], axis=1)
        swinging = data[f"schedule.{side}_swing"][before].astype(bool)
        conditions.append((f"{side} foot {1e2 * SWING_OFF_PATH:g} cm off its swing path",
                           swinging & (off_path > SWING_OFF_PATH)))
    polygons = SupportPolygons(walk.plan, 0.0).at(walk.plan.time(data["time"][before]))
    conditions.append(("measured ZMP on or past the planned support polygon's edge",
                       polygon_margin(data["zmp.zmp"][before, :2], *polygons) <= 0.0))
    com_off = np.linalg.norm(result["com"][before, :2] - data["pattern.com_position"][before, :2], axis=1)
    conditions.append((f"CoM {1e2 * COM_OFF_PLAN:g} cm off its plan", com_off > COM_OFF_PLAN))
    return sorted((int(np.argmax(shown)), label) for label, shown in conditions if shown.any())


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
        axes.fill(corners[:, 0], corners[:, 1], fill=False, color=SIDE_COLOURS[side],
                  linewidth=0.8, zorder=1)


def stretch_across(axes: plt.Axes) -> int:
    """The whole factor y is stretched by in a top view so that it is at least a quarter as tall as wide."""
    (x_low, x_high), (y_low, y_high) = axes.get_xlim(), axes.get_ylim()
    return max(1, round(0.25 * (x_high - x_low) / (y_high - y_low)))


def draw_surfaces_from_above(axes: plt.Axes, terrain: Terrain) -> None:
    """The terrain's surfaces (light grey rectangles, seen from above) within the axes' present limits."""
    axes.autoscale_view()
    axes.set_autoscale_on(False)
    for surface in terrain.surfaces:
        corners = surface.corners()
        axes.fill(corners[:, 0], corners[:, 1], color="0.93", edgecolor="0.7", linewidth=0.6, zorder=-1)


def side_line(plan: FootstepPlan, side: str) -> float:
    """The median y of ``side``'s footprints in the plan: the line along which it walks."""
    placements = [plan.initial_left if side == "left" else plan.initial_right]
    placements += [step.placement for step in plan.steps if step.side == side]
    return float(np.median([plan.sole.center(placement)[1] for placement in placements]))


def draw_terrain_side(axes: plt.Axes, walk: Walk, x: np.ndarray) -> None:
    """The terrain seen from the right: each surface as the box under it (grey), and its height
    along each foot's line (``side_line``) at ``x``."""
    for surface in walk.terrain.surfaces:
        corners = surface.corners()[:, [0, 2]]
        box = convex_hull(np.vstack([corners, np.column_stack([corners[:, 0], np.zeros(4)])]))
        axes.fill(box[:, 0], box[:, 1], color="0.9", edgecolor="0.6", linewidth=0.6, zorder=0)
    for side in SIDES:
        y = side_line(walk.plan, side)
        axes.plot(x, [walk.terrain.height_at(xi, y) for xi in x], color=SIDE_COLOURS[side], linewidth=0.8,
                  alpha=0.5, label=f"terrain under the {side} foot (y {y:+.3f} m)")


def draw_side_view(axes: plt.Axes, walk: Walk, result: dict[str, object]) -> None:
    """The walk seen from its right (x-z): the terrain (:func:`draw_terrain_side`), the true soles'
    paths and their references (``<side>_swing.position``), the planned and true CoM; on a terrain
    lower than ``LOW_RELIEF``, z zoomed on the feet, without the CoM."""
    mask, data = result["mask"], walk.data
    soles = result["soles"][mask]
    draw_terrain_side(axes, walk, np.linspace(soles[:, :, 0].min() - 0.2, soles[:, :, 0].max() + 0.2, 1200))
    for i, side in enumerate(SIDES):
        axes.plot(soles[:, i, 0], soles[:, i, 2], color=SIDE_COLOURS[side], linewidth=2.4 if side == "left" else 1.0,
                  alpha=0.8, label=f"{side} sole (true)")  # the left one wider: under the right one when they meet
        reference = data[f"{side}_swing.position"][mask]
        axes.plot(reference[:, 0], reference[:, 2], color=SIDE_COLOURS[side], linewidth=0.8, linestyle="--",
                  label=f"{side} sole reference")
    if max(surface.corners()[:, 2].max() for surface in walk.terrain.surfaces) < LOW_RELIEF:
        axes.set(xlabel="x (m)", ylabel="z (m)", title="side view (seen from the right), z zoomed on the feet")
    else:
        axes.plot(result["com"][mask, 0], result["com"][mask, 2], color="k", linewidth=1.4, label="CoM (true)")
        planned = data["pattern.com_position"][mask]
        axes.plot(planned[:, 0], planned[:, 2], color="k", linewidth=1.0, linestyle="--", label="CoM plan")
        axes.set(aspect="equal", xlabel="x (m)", ylabel="z (m)", title="side view (seen from the right)")
    axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9)


def plot_walk(path: Path, walk: Walk, result: dict[str, object]) -> None:
    """The walk's figure: the top view above, on a terrain the side view under it, x and y over time below."""
    mask, data = result["mask"], walk.data
    t = data["time"][mask]
    series = [("CoM (true)", result["com"][mask], dict(color="k", linewidth=1.4)),
              ("CoM plan", data["pattern.com_position"][mask], dict(color="k", linewidth=1.0, linestyle="--")),
              ("ZMP plan", data["pattern.zmp"][mask], dict(color="tab:green", linewidth=1.4)),
              ("ZMP measured (ankle F/T)", data["zmp.zmp"][mask], dict(color="tab:olive", linewidth=0.6)),
              ("DCM plan", data["pattern.dcm"][mask], dict(color="tab:purple", linewidth=1.4)),
              ("DCM measured", result["dcm"][mask], dict(color="tab:orange", linewidth=0.8, linestyle=":"))]
    side_view = bool(walk.terrain.surfaces)
    figure = plt.figure(figsize=(14, 14 if side_view else 9), constrained_layout=True)
    grid = figure.add_gridspec(3 if side_view else 2, 2)
    top = figure.add_subplot(grid[0, :])
    along, across = figure.add_subplot(grid[-1, 0]), figure.add_subplot(grid[-1, 1])
    draw_plan(top, walk.plan)
    for label, xy, style in series:
        top.plot(xy[:, 0], xy[:, 1], label=label, **style)
        along.plot(t, xy[:, 0], **style)
        across.plot(t, xy[:, 1], **style)
    draw_surfaces_from_above(top, walk.terrain)
    stretch = stretch_across(top)
    top.set(aspect=stretch, xlabel="x (m)", ylabel="y (m)", title=f"{walk.name}: top view" + (
        f", y stretched ×{stretch}" if stretch > 1 else "") + (
        f" (fell at {result['fall']:.2f} s)" if result["fall"] is not None else ""))
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9)
    along.set(xlabel="time (s)", ylabel="x (m)", title="along the walk")
    across.set(xlabel="time (s)", ylabel="y (m)", title="across the walk")
    panels = [top, along, across]
    if side_view:
        panels.append(figure.add_subplot(grid[1, :]))
        draw_side_view(panels[-1], walk, result)
    for axes in panels:
        axes.grid(alpha=0.3)
    figure.savefig(path, dpi=80, bbox_inches="tight")
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
    """Ours and placo's plans of each distinct footstep plan of the flat walks that ran."""
    comparisons: dict[str, dict[str, object]] = {}
    for walk in walks:
        if walk.plan is None or walk.on_terrain:
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
    """A markdown table (a cell's line breaks and bars, as in an error message, made safe)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    cells = [[cell.replace("\n", " ").replace("|", "\\|") for cell in row] for row in rows]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in cells])


def triple(values: tuple[float, ...] | np.ndarray, scale: float = 1e3, digits: int = 1) -> str:
    """``a / b / c`` scaled (default: m to mm)."""
    return " / ".join(f"{scale * v:.{digits}f}" for v in values)


def statistics(error: object, axis: int) -> tuple[float, float, float]:
    """A TrackingError's average / std / peak on one axis."""
    return error.mean[axis], error.std[axis], error.peak[axis]


def fell(result: dict[str, object]) -> str | None:
    """``fell at X s`` if the robot fell, None otherwise."""
    return None if result["fall"] is None else f"fell at {result['fall']:.2f} s"


def fell_with_signs(walk: Walk, result: dict[str, object]) -> str | None:
    """``fell at X s`` and the first signs before the fall (:func:`fall_signs`) if the robot fell,
    None otherwise."""
    if result["fall"] is None:
        return None
    signs = result["fall_signs"]
    if not signs:
        return f"{fell(result)}; no sign the bench looks for came before it"
    return f"{fell(result)}; first signs: " + ", then ".join(f"{label} at {tick * walk.dt:.2f} s"
                                                            for tick, label in signs[:3])


def labelled(walk: Walk, result: dict[str, object]) -> str:
    """The graph's name, with its fall if it fell (for the tables that still give numbers)."""
    return walk.name if result["fall"] is None else f"{walk.name} ({fell(result)}: until then)"


def thesis_label(walk: Walk) -> str:
    """The thesis's scheme and walk this graph stands for."""
    return "—" if walk.thesis is None else f"{walk.thesis[0]}, {walk.thesis[1]}"


def outcome_table(walks: list[Walk], results: dict[str, dict], outcome: Callable[[Walk, dict], str | None],
                  base_header: str, measure: tuple[str, Callable[[Walk, dict], str]]) -> str:
    """One row per walk: its outcome (``outcome``, or that it walked to the end), the final base
    against the plan's final midpoint, one ``measure`` column (header, cell) and the wall time."""
    header, cell = measure
    rows = []
    for walk in walks:
        if walk.problem is not None:
            rows.append([walk.name, thesis_label(walk), walk.problem, "—", "—", "—", "—"])
            continue
        result = results[walk.name]
        base, midpoint = result["final_base"], result["final_midpoint"]
        ended = outcome(walk, result) or f"walked to the end ({len(result['mask']) * walk.dt:.1f} s)"
        rows.append([walk.name, thesis_label(walk), ended, f"{base[0]:.3f}, {base[1]:.3f}",
                     f"{midpoint[0]:.3f}, {midpoint[1]:.3f}", cell(walk, result),
                     f"{walk.wall:.0f} s ({result['real_time_factor']:.2f})"])
    return table(["graph", "thesis", "outcome", base_header, "plan's final midpoint x, y (m)", header,
                  "wall time (real-time factor)"], rows)


def summary_table(walks: list[Walk], results: dict[str, dict]) -> str:
    """Outcome of every walk: fall, final base against the plan's final midpoint, wall time."""
    def distance(_: Walk, result: dict) -> str:
        if result["fall"] is not None:
            return "—"
        return f"{1e3 * np.linalg.norm(result['final_base'] - result['final_midpoint']):.0f}"
    return outcome_table(walks, results, lambda _, result: fell(result), "base x, y at the end (m)",
                         ("distance (mm)", distance))


def zmp_rows(walk: Walk, result: dict[str, object], signs: bool = False) -> list[list[str]]:
    """The ZMP error rows of one walk: against the plan, and against p* where there is a stabiliser;
    the thesis's numbers on the row of its reference (p* for the position schemes when we have it).
    A walk that fell has one row, on the thesis's reference: its fall (with its first signs if
    ``signs``) instead of the numbers."""
    references = [("planned ZMP (`pattern.zmp`)", "zmp")]
    if "zmp_desired" in result:
        references.append(("stabiliser's p* (Eq. 2.30)", "zmp_desired"))
    thesis = THESIS_ZMP.get(walk.thesis)
    position_scheme = walk.thesis is not None and walk.thesis[0] != "TSID torque"
    thesis_key = "zmp_desired" if position_scheme and "zmp_desired" in result else "zmp"
    fall = fell_with_signs(walk, result) if signs else fell(result)
    rows = []
    for label, key in references:
        if fall and key != thesis_key:
            continue
        ours = [fall, "—"] if fall else [triple(statistics(result[key], axis)) for axis in (0, 1)]
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


def energy_table(walks: list[Walk], results: dict[str, dict], climb: bool = False) -> str:
    """E_m, E_m+, C_et, C_mt and D, ours and the thesis's; with ``climb``, also ``m g`` times the
    planned CoM's rise and the thesis's D implied by its row, ``E_m / (C_et m g)``."""
    rows = []
    for walk in (w for w in walks if w.problem is None):
        result, thesis = results[walk.name], THESIS_COT.get(walk.thesis)
        if fell(result):
            ours = [fell(result)] * 4
        else:
            ours = [f"{result['energy'][0]:.1f} / {result['energy'][1]:.1f}",
                    f"{result['cot'][0]:.2f} / {result['cot'][1]:.2f}", f"{result['distance']:.3f}",
                    f"{result['climb']:.1f}"]
        theirs = ["—", "—", "—"] if thesis is None else [
            f"{thesis[0]} / {thesis[1]}", f"{thesis[2]} / {thesis[3]}" + (" ⚠" if walk.thesis == THESIS_COT_ERRATUM
                                                                          else ""),
            f"{thesis[0] / (thesis[2] * robot_mass() * GRAVITY):.2f}"]
        rows.append([walk.name, ours[0], theirs[0], ours[1], theirs[1], ours[2]] + ([ours[3], theirs[2]] if climb
                                                                                     else []))
    header = ["graph", "E_m / E_m⁺ (J) ours", "thesis", "C_et / C_mt ours", "thesis", "D (m)"]
    return table(header + (["m g Δz_CoM plan (J)", "thesis D implied (m)"] if climb else []), rows)


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


def terrain_summary_table(walks: list[Walk], results: dict[str, dict]) -> str:
    """Outcome of every terrain walk: the fall and its first signs, the final base against the
    plan's final midpoint, the CoM height against its plan, wall time."""
    def height(_: Walk, result: dict) -> str:
        error = result["com_height"]
        return f"{1e3 * error.mean[0]:.1f} / {1e3 * error.peak[0]:.1f}"
    return outcome_table(walks, results, fell_with_signs, "base x, y at the end or the fall (m)",
                         ("CoM height error average / peak (mm)", height))


def terrain_zmp_table(walks: list[Walk], results: dict[str, dict]) -> str:
    """The ZMP errors of the terrain walks beside the thesis's Tables 4.6 and 4.7, a graph that did
    not run with its reason (and the thesis's row all the same)."""
    rows = []
    for walk in walks:
        scheme = "—" if walk.thesis is None else walk.thesis[0]
        terrain = "—" if walk.thesis is None else walk.thesis[1]
        if walk.problem is not None:
            thesis = THESIS_ZMP.get(walk.thesis)
            theirs = ["—", "—"] if thesis is None else [triple(thesis[axis]) for axis in (0, 1)]
            rows.append([terrain, scheme, walk.name, "—", walk.problem, theirs[0], "—", theirs[1]])
            continue
        rows += [[terrain, scheme, *row] for row in zmp_rows(walk, results[walk.name], signs=True)]
    return table(["walk", "scheme", "graph", "measured ZMP against", "x ours", "x thesis", "y ours", "y thesis"],
                 rows)


def slip_table(walks: list[Walk], results: dict[str, dict]) -> str:
    """Each foot's largest slip (:func:`largest_slip`) and whether both are under ``SLIP_LIMIT``."""
    rows = []
    for walk in (w for w in walks if w.problem is None):
        result = results[walk.name]
        slips = [result["slips"][side] for side in SIDES]
        cells = [f"{1e3 * slip.largest:.1f} at {slip.tick * walk.dt:.2f} s" for slip in slips]
        below = all(slip.largest < SLIP_LIMIT for slip in slips)
        rows.append([labelled(walk, result), *cells, "yes" if below else "no"])
    return table(["graph", "left sole: largest slip (mm), at", "right sole", f"below {1e3 * SLIP_LIMIT:g} mm"],
                 rows)


def zmp_peaks_check(walk: Walk, result: dict[str, object]) -> tuple[str, bool] | None:
    """Whether the ZMP error's peaks (against the plan) are at most the thesis's, per axis (None
    without thesis numbers)."""
    thesis = THESIS_ZMP.get(walk.thesis)
    if thesis is None:
        return None
    if result["fall"] is not None:
        return "ZMP peaks ≤ the thesis's: not measured (it fell)", False
    ours = result["zmp"].peak
    ok = bool(ours[0] <= thesis[0][2] and ours[1] <= thesis[1][2])
    return (f"ZMP peaks ≤ the thesis's: x {1e3 * ours[0]:.1f} mm ≤ {1e3 * thesis[0][2]:.0f}, y {1e3 * ours[1]:.1f} mm "
            f"≤ {1e3 * thesis[1][2]:.0f}: {'holds' if ok else 'does not hold'}"), ok


def torque_checks(walk: Walk, result: dict[str, object], obstacle_changes: list[str] | None) -> list[tuple[str, bool]]:
    """The acceptance checks of one TSID-torque terrain walk: no fall, slip, ZMP peaks, and for the
    obstacles the flat walk's gains (``obstacle_changes``: its parameters that differ from
    ``FLAT_REFERENCE``'s)."""
    largest = max(result["slips"][side].largest for side in SIDES)
    checks = [(f"no fall: {'holds' if result['fall'] is None else 'does not hold, ' + fell(result)}",
               result["fall"] is None),
              (f"slip < {1e2 * SLIP_LIMIT:g} cm: largest {1e3 * largest:.1f} mm"
               f"{'' if result['fall'] is None else ' before the fall'}: "
               f"{'holds' if largest < SLIP_LIMIT else 'does not hold'}", largest < SLIP_LIMIT)]
    peaks = zmp_peaks_check(walk, result)
    if peaks is not None:
        checks.append(peaks)
    if walk.thesis is not None and walk.thesis[1] == "Obstacles 2 cm":
        if obstacle_changes is None:
            checks.append((f"the flat walk's gains: not checked (graphs/talos_obstacles.yaml or "
                           f"graphs/{FLAT_REFERENCE}.yaml missing or not loading)", False))
        else:
            gains_kept = all(name.startswith("footsteps.") or name == "device.scene" for name in obstacle_changes)
            checks.append((f"the flat walk's gains: its parameters differ from {FLAT_REFERENCE}'s only in "
                           f"{', '.join(f'`{name}`' for name in obstacle_changes) or 'nothing'}: "
                           f"{'holds' if gains_kept else 'does not hold'}", gains_kept))
    return checks


def acceptance(walks: list[Walk], results: dict[str, dict], obstacle_changes: list[str] | None) -> str:
    """Which of issue 14's acceptance points hold, per TSID-torque terrain walk, and the position
    schemes' outcomes (not part of the acceptance)."""
    lines, failed = [], []
    for walk in (w for w in walks if w.on_terrain):
        if walk.problem is not None:
            lines.append(f"- `{walk.name}`: {walk.problem}: no verdict.")
            failed.append(walk.name)
            continue
        result = results[walk.name]
        if walk.thesis is not None and walk.thesis[0] != "TSID torque":
            lines.append(f"- `{walk.name}` ({walk.thesis[0]}, not part of the acceptance): "
                         f"{fell(result) or 'walked to the end'}.")
            continue
        checks = torque_checks(walk, result, obstacle_changes)
        lines.append(f"- `{walk.name}`: " + "; ".join(label for label, _ in checks) + ".")
        if not all(ok for _, ok in checks):
            failed.append(walk.name)
    verdict = ("Every acceptance point holds." if not failed else
               f"Not every acceptance point holds: see {', '.join(f'`{name}`' for name in failed)}.")
    return "\n".join(lines) + f"\n\n{verdict}\n"


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
- **Stairs and platforms plans**: the thesis's came offline from multicontact-locomotion-planning (SL1M
  contacts, a centroidal optimisation that does not assume L̇ = 0; L1582-1627); ours are `terrain_walk`'s
  straight plans over the same surfaces, step-to, single / double support 1.6 / 0.3 s (mlp's public
  stairs and platforms configs, walking notes §1.3), planned online by the LIPM MPC with the CoM carried
  over the supports' height. The thesis gives neither its gait nor its distance for these walks.
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
             calibrations: tuple[dict[str, object], dict[str, object]], load: float, images: list[str],
             obstacle_changes: list[str] | None) -> str:
    """The whole of docs/walking.md: the flat walks' sections, then the terrain's, if either ran."""
    before, after = calibrations
    flat, terrain = [w for w in walks if not w.on_terrain], [w for w in walks if w.on_terrain]
    parts = [
        "# Walking: TALOS in MuJoCo against the thesis and placo\n",
        f"Written by `{command}` on {time.strftime('%Y-%m-%d %H:%M')}; every number below comes from that run "
        "(thesis numbers: `/work/shared/reference/walking_mptc_actuators_drilling.md` §1.7, cited per table). "
        "Do not edit: run the command again.\n",
        f"Machine: {platform.platform()}, {before['cpu']}, {before['vcpus']} vCPU, {before['python']}; "
        f"other processes kept {load:.2f} CPUs busy on average during the run.\n",
        f"- before: {calibration_line(before)}\n- after: {calibration_line(after)}\n",
        "A time in calibration loops is the time divided by the first figure (bench/calibration.py).\n",
        "Each graph runs to its duration, or stops at the tick the robot falls: its base (`device.q`, the "
        f"simulator's) less than {FALL_HEIGHT:g} m above the terrain under it (`footsteps.walked_terrain`; on flat "
        "ground the device's `fallen`, so that a robot lying on a tread has fallen too); every gait metric is taken "
        "on the ticks before the fall, and a walk that fell shows its fall instead. The plan's final midpoint is "
        "`FootstepPlan.final_midpoint()`.\n",
    ]
    if flat:
        parts += flat_sections(flat, results, before)
    if terrain:
        parts += terrain_sections(walks, results, before, obstacle_changes)
    parts += [
        "\n## Plots\n",
        "Top view: the terrain's surfaces (light grey), footprints (left blue, right red), double-support polygons "
        "(grey), the true CoM, the planned CoM, ZMP and DCM, the measured ZMP (ankle F/T) and DCM (true CoM + its "
        "velocity / ω, ω from the planned CoM height above the support, `FootstepPlan.support_height`). On a "
        "terrain, the side view: each surface as the box under it, the terrain's height along each foot's line "
        "(the median y of its footprints), the true soles' paths and their references, the planned and true CoM. "
        "Below: x and y over time.\n",
        "\n".join(f"![{image}]({image})" for image in images),
        "\n## The peer: placo's walk pattern generator\n",
        peer_text(comparisons, before),
        "\n## What differs from the thesis\n",
        DIFFERENCES,
        pattern_settings(walks),
    ]
    return "\n".join(parts)


def flat_sections(walks: list[Walk], results: dict[str, dict], cal: dict[str, object]) -> list[str]:
    """The flat walks' sections: outcome, Tables 4.4, 4.5, 4.8-4.10, force jumps."""
    return [
        "## The walks on flat ground\n",
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
        "`device.v`), C = E / (m g D) with m the model's mass and D the horizontal distance the plan travels, from "
        "the midpoint of the initial soles to the final one (the thesis's \"traveled distance of 1.2 m\" [L4682]).\n",
        energy_table(walks, results),
        "\n## Passivity gait measure per gait stage (Table 4.9 [L4912-4930], Eq. 4.17-4.18)\n",
        "PGM = 1 - RMS(τ_ankle) / RMS(τ_all joints) with the ankle pitch and roll joints (leg_*_5, leg_*_6): both "
        "ankles in double support (`schedule.double_support`), the stance ankle in single support and the swinging "
        "foot's ankle for the flying foot (`schedule.left_swing`, `schedule.right_swing`).\n",
        pgm_table(walks, results),
        "\n## Control tick (Table 4.10 [L4932-4940])\n",
        "The control graph's evaluation per tick (`timed` of bench/compare_schemes.py: every plugged input of the "
        "device pulled; the simulator's step and the recorder excluded), first tick left out.\n",
        tick_table(walks, results, cal),
        "\n## Normal-force jumps at the contact switches\n",
        "The largest |f_z[k] - f_z[k-1]| of each foot's contact force from the QP (`solver.contact_wrenches`) on "
        "the ticks within the scheduler's `transition` of a lift-off or touch-down of either foot; the acceptance "
        "of issue 13 is below 5 % of the robot's weight per tick.\n",
        force_table(walks, results),
    ]


def terrain_sections(walks: list[Walk], results: dict[str, dict], cal: dict[str, object],
                     obstacle_changes: list[str] | None) -> list[str]:
    """The section "Stairs, tilted platforms, obstacles": outcome, Tables 4.6-4.10 side by side
    with ours, slips, force jumps, the acceptance of issue 14."""
    terrain = [w for w in walks if w.on_terrain]
    erratum = THESIS_COT[THESIS_COT_ERRATUM]
    return [
        "\n## Stairs, tilted platforms, obstacles\n",
        "The walks of issue 14 over the terrains of `dgraph.entities.walking.terrain` (the MuJoCo scenes are built "
        "from the same surfaces): `stairs10`, six 10 cm rises over 30 cm treads [L4837-4838], climbed step-to "
        "(both feet on each tread); `platforms`, two flat pads 0.16 m high and four pads tilted by 15° (walking "
        "notes §1.5), crossed step-to; `obstacles`, boards 1 and 2 cm high under the footsteps of the flat 20 cm "
        "walk (the MPTC report's uneven terrain; the thesis has no numbers for it). The thesis planned its stairs "
        "and platforms with multicontact-locomotion-planning offline [L1582-1627]; ours are `terrain_walk`'s plans "
        "and our LIPM MPC with the CoM carried over the support's height. A graph that is not there yet, or does "
        "not load, is listed as such.\n",
        terrain_summary_table(terrain, results),
        "\n### ZMP error (Table 4.6, tilted platforms [L4826-4835]; Table 4.7, stairs [L4857-4866])\n",
        "Average / std / peak of |p - p_ref| in mm per horizontal axis, as for Table 4.4: p the ankle F/T "
        "ZMP (`zmp.zmp`) on the plane the pattern generator plans the ZMP in (`zmp.plane_height` plugged from "
        "`pattern.zmp_plane_height`: the stance sole's height, linear between the soles' in a double support), "
        "p_ref the planned ZMP (`pattern.zmp`), or the stabiliser's p* for the position schemes, the thesis's "
        "reference for them [L4693-4699]. The thesis's row sits beside the reference it used.\n",
        terrain_zmp_table(terrain, results),
        "\n### Foot slip\n",
        "Per foot, the largest horizontal distance of the true sole (`<side>_sole_link` from `device.q`) from "
        f"where it stood {1e3 * SLIP_SETTLING:g} ms after the start of its stance interval (the foot a contact "
        "of the controller, `schedule.<side>_contact`, and not swinging), over every stance interval before the "
        f"end or the fall; issue 14 accepts less than {1e2 * SLIP_LIMIT:g} cm. A sole that rolls over its edge "
        "moves its frame too, and counts. The flat walks are given for comparison.\n",
        slip_table(walks, results),
        "\n### Cost of transport (Table 4.8 [L4888-4910], Eq. 4.16)\n",
        f"C = E / (m g D), m = {robot_mass():.2f} kg (the model's), D the plan's horizontal distance from the "
        "initial to the final midpoint of the soles. E_m and E_m⁺ are the joints' mechanical work "
        "(`dgraph.evaluation.mechanical_energy`: ∫ Σ|τ_i ω_i| dt and ∫ Σ max(τ_i ω_i, 0) dt), so the work the "
        "joints do to lift the robot is counted in them like any other work; no potential-energy term is added "
        "or removed. The column m g Δz gives that potential energy (m g times the planned CoM's rise from the "
        "first tick to the last) for comparison. The thesis does not "
        "give its D for these walks; its E_m / (C_et m g) is given with our m. ⚠: the thesis's TSID-position "
        f"platforms row gives C_mt {erratum[3]}, but its E_m⁺ {erratum[1]} J with the same m g D as its C_et "
        f"gives {erratum[1] * erratum[2] / erratum[0]:.2f} (walking notes §1.7).\n",
        energy_table(terrain, results, climb=True),
        "\n### Passivity gait measure (Table 4.9 [L4912-4930])\n",
        "PGM = 1 - RMS(τ_ankle) / RMS(τ_all joints), the ankles as for the flat walks: double support / single "
        "support / flying foot.\n",
        pgm_table(terrain, results),
        "\n### Control tick (Table 4.10 [L4932-4940])\n",
        tick_table(terrain, results, cal),
        "\n### Normal-force jumps at the contact switches\n",
        force_table(terrain, results),
        "\n### Acceptance of issue 14\n",
        acceptance(walks, results, obstacle_changes),
    ]


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


def given_parameters(path: Path) -> dict[str, str]:
    """Every parameter a graph file gives its entities, as ``entity.param`` -> its repr."""
    graph = dg.load(str(path))
    return {f"{name}.{param}": repr(value) for name, entity in graph.entities.items()
            for param, value in entity.given_params.items()}


def obstacle_changes() -> list[str] | None:
    """The parameters talos_obstacles gives otherwise than ``FLAT_REFERENCE`` (None if either graph
    file is missing or does not load)."""
    paths = [graph_path("talos_obstacles"), graph_path(FLAT_REFERENCE)]
    try:
        obstacles, flat = map(given_parameters, paths)
    except (OSError, DGraphError):
        return None
    return sorted(name for name in obstacles.keys() | flat.keys() if obstacles.get(name) != flat.get(name))


def main() -> None:
    """Run the walks, evaluate them, plan with both planners, write the document."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    chosen = parser.add_mutually_exclusive_group()
    chosen.add_argument("--graphs", nargs="+", default=list(WALKS),
                        help=f"graph names (graphs/) or .yaml paths (default: {' '.join(WALKS)})")
    chosen.add_argument("--terrain", action="store_const", dest="graphs", const=TERRAIN_GRAPHS,
                        help=f"only the walks over a terrain: {' '.join(TERRAIN_GRAPHS)}")
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
    text = document(command, walks, results, comparisons, (before, after), load, images, obstacle_changes())
    args.doc.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
