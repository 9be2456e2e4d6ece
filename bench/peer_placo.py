"""placo's walk pattern generator as the walking peer (issue 13), run in .venv-placo (bench/setup_placo.sh).

    bash bench/setup_placo.sh
    .venv-placo/bin/python bench/peer_placo.py PLAN.json OUT.npz [--talos-urdf PATH] [--horizon 48]
        [--timesteps 10] [--replan-period 0.1] [--dt 0.001]

It does not import dgraph (other venv: PyPI placo pins pin 3.8.0). The robot is example-robot-data's
``talos_reduced.urdf`` (the one ``example_robot_data.load("talos")`` reads; by default taken from this venv's
example-robot-data wheel) with its visual and collision elements removed and three massless links added on fixed
joints, the frames placo's ``HumanoidRobot`` looks for: ``left_foot`` on ``left_sole_link``, ``right_foot`` on
``right_sole_link``, ``trunk`` on ``torso_2_link``. That URDF is written to ``out/placo/talos_placo.urdf``.

Input, PLAN.json: a footstep plan in plain data, the content of dgraph's ``FootstepPlan``
(``dgraph/entities/walking/footsteps.py``); example: bench/placo/example_plan.json. Lengths in m, times in s.

    initial_left, initial_right    4x4 sole placements (TALOS ``*_sole_link`` frames) at the start
    steps                          [{"side": "left"|"right", "placement": 4x4, "single_support", "double_support"}]:
                                   the foot ``side`` swings to ``placement`` during ``single_support``, then both
                                   feet stand for ``double_support`` (0: none; the last step's is replaced by
                                   ``final_double_support``)
    initial_double_support         before the first lift-off;  final_double_support: after the last touch-down
    com_height                     the LIPM height h (placo's ``walk_com_height``), omega = sqrt(g / h)
    sole                           {"front", "back", "half_width"}: the sole rectangle x in [-back, front],
                                   y in [-half_width, half_width] in the placement frame
    margin                         placo's ``zmp_margin``: the sole shrunk by it bounds the ZMP
    initial_com                    optional, 3: the CoM at rest at time 0; default: the midpoint of the two
                                   initial sole centres at ``com_height``

How the plan becomes placo's supports (``placo.Support``, one per phase): the initial double support
(``start``), then per step a single support on the other foot and a double support on both, the last one being the
final double support (``end``: placo brings the CoM to rest over its centre). A placo ``Footstep`` is centred on its
frame (``foot_length`` x ``foot_width``), so each footstep's frame is the placement moved by (front - back) / 2
along its x axis: the sole centre; placo's polygon is then exactly the plan's sole. placo's timing is per support
kind (``single_support_duration`` with ``--timesteps`` LIPM steps, double and start/end supports as ratios of it);
the plan's own durations, which may differ step by step, are given through each support's ``time_ratio`` (its
duration / placo's default for its kind), which stretches its LIPM steps (their number stays the default). The
defaults are taken from the first step (SS, DS) and the initial double support.

Receding horizon and replans (placo's usual loop, Rhoban/placo-examples ``walk/walk.py``): each plan holds the
supports from the current one until ``--horizon`` LIPM steps are covered; if the plan goes on beyond them, a
virtual end double support (duration: the final double support) on the feet after the last kept support closes it
(placo's walks always end on a stop). The initial plan (``WalkPatternGenerator.plan``) is at t = 0; then, walking
the plan at ``--dt``, a replan (``WalkPatternGenerator.replan``, from the current trajectory's CoM state) is made
whenever more than ``--replan-period`` s passed since the last one and ``can_replan_supports`` allows it: in a
single support that is not followed by the final support. The current support is given with its elapsed part.
Times are ``time.perf_counter`` around the ``plan`` / ``replan`` call alone.

Output, OUT.npz (``np.load``; n samples at ``time[k] = k * dt`` from 0 to the plan's end; each sample is taken
from the trajectory of the last plan or replan made at or before it, as a controller would read it):

    time                 (n,)    s
    com_position         (n, 3)  m, placo's CoM (z = com_height, constant)
    com_velocity         (n, 3)  m/s
    com_acceleration     (n, 3)  m/s^2
    zmp                  (n, 2)  m, c - c_ddot / omega^2 (placo's ``get_p_world_ZMP``)
    dcm                  (n, 2)  m, c + c_dot / omega (placo's ``get_p_world_DCM``)
    left_foot            (n, 3)  m, origin of the left sole placement frame (placo's swing in single support)
    right_foot           (n, 3)  m, same for the right foot
    zmp_support_distance (n,)    m, signed distance from the ZMP to the edge of the support polygon placo uses at
                                 that time (the convex hull of the soles on the ground; > 0 inside)
    plan_time            ()      s, the initial plan
    replan_times         (m,)    s, each replan, in order
    replan_at            (m,)    s, the walk time of each replan
    replan_success       (m,)    bool, placo's ``replan_success`` (false: it kept the trimmed old trajectory)
    omega                ()      1/s;  dt: () s;  horizon: () LIPM steps;  replan_period: () s
    placo_version        ()      str

It prints the medians (plan and replan times), the CoM advance and the least ZMP distance to the polygon edge.
placo bounds the ZMP at its LIPM steps only (each support's steps 1..N, not the instant it begins) and its ZMP is
continuous (jerk input), so for a fraction of a LIPM step after each lift-off the ZMP is still where the double
support left it, outside the new stance sole: ``zmp_support_distance`` shows it. placo's ``HumanoidRobot`` prints
two warnings (no ``left_hip_yaw`` and no head frames): only its kinematic helpers use those, not the WPG.
"""

from __future__ import annotations

import argparse
import bisect
import importlib.metadata as md
import json
import sysconfig
import time
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import placo

ROOT = Path(__file__).resolve().parents[1]
URDF_OUT = ROOT / "out" / "placo" / "talos_placo.urdf"
PLACO_FRAMES = {"left_foot": "left_sole_link", "right_foot": "right_sole_link", "trunk": "torso_2_link"}
SIDES = {"left": placo.HumanoidRobot_Side.left, "right": placo.HumanoidRobot_Side.right}
OTHER_SIDE = {"left": "right", "right": "left"}


def example_robot_data_talos_urdf() -> Path:
    """``talos_reduced.urdf`` of the example-robot-data wheel installed in this venv."""
    share = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data"
    return share / "robots" / "talos_data" / "robots" / "talos_reduced.urdf"


def write_placo_urdf(source: Path, target: Path) -> Path:
    """``source`` without visual/collision elements, plus placo's massless frames (PLACO_FRAMES), at ``target``."""
    tree = ElementTree.parse(source)
    robot = tree.getroot()
    for link in robot.iter("link"):
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
    for frame, parent in PLACO_FRAMES.items():
        ElementTree.SubElement(robot, "link", name=frame)
        joint = ElementTree.SubElement(robot, "joint", name=f"{frame}_frame_joint", type="fixed")
        ElementTree.SubElement(joint, "parent", link=parent)
        ElementTree.SubElement(joint, "child", link=frame)
        ElementTree.SubElement(joint, "origin", xyz="0 0 0", rpy="0 0 0")
    target.parent.mkdir(parents=True, exist_ok=True)
    tree.write(target)
    return target


@dataclass(frozen=True)
class Phase:
    """One support of the plan: the sides on the ground, its time span, and the feet (placo frames) at its end."""

    stance: tuple[str, ...]
    start: float
    duration: float
    feet_after: dict[str, np.ndarray]


class PlanSupports:
    """The plan's phases, turned into placo supports over a receding horizon."""

    def __init__(self, plan: dict, walk: placo.WalkPatternGenerator, foot_length: float, foot_width: float,
                 sole_shift: float):
        self.walk, self.foot_length, self.foot_width, self.sole_shift = walk, foot_length, foot_width, sole_shift
        self.final_double_support = float(plan["final_double_support"])
        self.phases = self._phases(plan)
        self.starts = [phase.start for phase in self.phases]
        self.duration = self.phases[-1].start + self.phases[-1].duration

    def sole_centre_frame(self, placement: list) -> np.ndarray:
        """The placement moved along its own x axis to the sole rectangle's centre (placo's footstep frame)."""
        frame = np.array(placement, dtype=float)
        frame[:3, 3] += self.sole_shift * frame[:3, 0]
        return frame

    def _phases(self, plan: dict) -> list[Phase]:
        feet = {"left": self.sole_centre_frame(plan["initial_left"]),
                "right": self.sole_centre_frame(plan["initial_right"])}
        spans = [(("left", "right"), float(plan["initial_double_support"]), dict(feet))]
        steps = plan["steps"]
        for index, step in enumerate(steps):
            feet[step["side"]] = self.sole_centre_frame(step["placement"])
            spans.append(((OTHER_SIDE[step["side"]],), float(step["single_support"]), dict(feet)))
            last = index == len(steps) - 1
            double_support = self.final_double_support if last else float(step["double_support"])
            if double_support > 0:
                spans.append((("left", "right"), double_support, dict(feet)))
            elif last or steps[index + 1]["side"] == step["side"]:
                raise ValueError(f"step {index}: placo needs a double support after it (final, or same foot next)")
        starts = np.concatenate([[0.0], np.cumsum([duration for _, duration, _ in spans])])
        return [Phase(stance, float(start), duration, feet_after)
                for (stance, duration, feet_after), start in zip(spans, starts, strict=False)]

    def phase_index(self, t: float) -> int:
        """Index of the phase holding walk time ``t`` (the last one after the end)."""
        return max(0, bisect.bisect_right(self.starts, t) - 1)

    def _footstep(self, side: str, frame: np.ndarray) -> placo.Footstep:
        footstep = placo.Footstep(self.foot_width, self.foot_length)
        footstep.side = SIDES[side]
        footstep.frame = frame
        return footstep

    def _support(self, sides: tuple[str, ...], feet: dict[str, np.ndarray], duration: float, *,
                 start: bool = False, end: bool = False) -> placo.Support:
        support = placo.Support()
        support.footsteps = [self._footstep(side, feet[side]) for side in sides]
        support.start, support.end = start, end
        support.time_ratio = duration / self.walk.support_default_duration(support)
        return support

    def _phase_support(self, index: int) -> placo.Support:
        phase = self.phases[index]
        return self._support(phase.stance, phase.feet_after, phase.duration, start=index == 0,
                             end=index == len(self.phases) - 1)

    def horizon(self, t: float, horizon_steps: int) -> placo.Supports:
        """Supports from the one at ``t`` (its elapsed part marked) until ``horizon_steps`` LIPM steps are covered,
        closed by a virtual end double support if the plan goes on."""
        index = self.phase_index(t)
        current = self._phase_support(index)
        current.t_start = self.phases[index].start
        current.elapsed_ratio = (t - self.phases[index].start) / self.phases[index].duration
        supports = [current]
        covered = max(1, int((1 - current.elapsed_ratio) * self.walk.support_default_timesteps(current)))
        while covered < horizon_steps and index + 1 < len(self.phases):
            index += 1
            supports.append(self._phase_support(index))
            covered += self.walk.support_default_timesteps(supports[-1])
        if index + 1 < len(self.phases):
            supports.append(self._support(("left", "right"), self.phases[index].feet_after,
                                          self.final_double_support, end=True))
        placo_supports = placo.Supports()  # the C++ vector plan() and replan() take by reference
        placo_supports.extend(supports)
        return placo_supports


def walk_parameters(plan: dict, timesteps: int) -> placo.HumanoidParameters:
    """placo's defaults per support kind from the plan's first step and initial double support, and its sole."""
    first = plan["steps"][0]
    single_support = float(first["single_support"])
    parameters = placo.HumanoidParameters()
    parameters.single_support_duration = single_support
    parameters.single_support_timesteps = timesteps
    # at least one LIPM step per double support: a ratio rounding to 0 steps would give a default duration of 0
    parameters.double_support_ratio = max(float(first["double_support"]) / single_support, 1.0 / timesteps)
    parameters.startend_double_support_ratio = float(plan["initial_double_support"]) / single_support
    parameters.walk_com_height = float(plan["com_height"])
    parameters.zmp_margin = float(plan["margin"])
    sole = plan["sole"]
    parameters.foot_length = float(sole["front"]) + float(sole["back"])
    parameters.foot_width = 2.0 * float(sole["half_width"])
    return parameters


def polygon_distance(polygon: list[np.ndarray], point: np.ndarray) -> float:
    """Signed distance from ``point`` to the edge of a convex polygon, either orientation (> 0 inside)."""
    corners = np.array([np.asarray(corner) for corner in polygon])
    edges = np.roll(corners, -1, axis=0) - corners
    counterclockwise = np.sign(np.sum(corners[:, 0] * edges[:, 1] - corners[:, 1] * edges[:, 0]))
    inward = counterclockwise * np.column_stack([-edges[:, 1], edges[:, 0]]) / np.linalg.norm(edges, axis=1)[:, None]
    return float(np.min(np.einsum("ij,ij->i", inward, point - corners)))


def initial_com(plan: dict, supports: PlanSupports) -> np.ndarray:
    if "initial_com" in plan:
        return np.asarray(plan["initial_com"], dtype=float)
    feet = supports.phases[0].feet_after
    centre = 0.5 * (feet["left"][:3, 3] + feet["right"][:3, 3])
    return np.array([centre[0], centre[1], float(plan["com_height"])])


def sole_origin(placo_frame: np.ndarray, sole_shift: float) -> np.ndarray:
    """The placement frame's origin of a placo foot frame (placo's frame is at the sole centre)."""
    return placo_frame[:3, 3] - sole_shift * placo_frame[:3, 0]


def run(plan: dict, urdf: Path, horizon: int, timesteps: int, replan_period: float, dt: float) -> dict:
    robot = placo.HumanoidRobot(str(urdf))
    parameters = walk_parameters(plan, timesteps)
    walk = placo.WalkPatternGenerator(robot, parameters)
    sole_shift = 0.5 * (float(plan["sole"]["front"]) - float(plan["sole"]["back"]))
    supports = PlanSupports(plan, walk, parameters.foot_length, parameters.foot_width, sole_shift)
    omega = placo.LIPM.compute_omega(parameters.walk_com_height)

    clock = time.perf_counter
    t0 = clock()
    trajectory = walk.plan(supports.horizon(0.0, horizon), initial_com(plan, supports), 0.0)
    plan_time = clock() - t0

    times = np.arange(round(supports.duration / dt) + 1) * dt
    samples: dict[str, list] = {key: [] for key in (
        "com_position", "com_velocity", "com_acceleration", "zmp", "dcm", "left_foot", "right_foot",
        "zmp_support_distance")}
    replans: dict[str, list] = {"replan_times": [], "replan_at": [], "replan_success": []}
    last_replan = 0.0
    for t in times:
        if t - last_replan > replan_period and walk.can_replan_supports(trajectory, t):
            horizon_supports = supports.horizon(t, horizon)
            t0 = clock()
            trajectory = walk.replan(horizon_supports, trajectory, t)
            replans["replan_times"].append(clock() - t0)
            replans["replan_at"].append(t)
            replans["replan_success"].append(trajectory.replan_success)
            last_replan = t
        zmp = trajectory.get_p_world_ZMP(t, omega)
        samples["com_position"].append(trajectory.get_p_world_CoM(t))
        samples["com_velocity"].append(trajectory.get_v_world_CoM(t))
        samples["com_acceleration"].append(trajectory.get_a_world_CoM(t))
        samples["zmp"].append(zmp)
        samples["dcm"].append(trajectory.get_p_world_DCM(t, omega))
        samples["left_foot"].append(sole_origin(trajectory.get_T_world_left(t), sole_shift))
        samples["right_foot"].append(sole_origin(trajectory.get_T_world_right(t), sole_shift))
        samples["zmp_support_distance"].append(polygon_distance(trajectory.get_support(t).support_polygon(), zmp))
    return {"time": times, **{key: np.array(values) for key, values in samples.items()},
            "plan_time": plan_time, **{key: np.array(values) for key, values in replans.items()},
            "omega": omega, "dt": dt, "horizon": horizon, "replan_period": replan_period,
            "placo_version": md.version("placo")}


def summary(result: dict) -> str:
    replan_times = result["replan_times"]
    com = result["com_position"]
    least = int(np.argmin(result["zmp_support_distance"]))
    return "\n".join([
        f"placo {result['placo_version']}: {result['time'].size} samples at {result['dt'] * 1e3:g} ms over "
        f"{result['time'][-1]:.3f} s",
        f"plan {result['plan_time'] * 1e3:.2f} ms; {replan_times.size} replans: median "
        f"{np.median(replan_times) * 1e3:.2f} ms, max {np.max(replan_times) * 1e3:.2f} ms, "
        f"{int(np.sum(~result['replan_success']))} failed",
        f"CoM advance {com[-1, 0] - com[0, 0]:.4f} m (x), {com[-1, 1] - com[0, 1]:+.4f} m (y); "
        f"final |dcm - com| {np.linalg.norm(result['dcm'][-1] - com[-1, :2]) * 1e3:.2f} mm",
        f"ZMP distance to the support polygon edge: least {result['zmp_support_distance'][least] * 1e3:+.1f} mm "
        f"at t = {result['time'][least]:.3f} s, median {np.median(result['zmp_support_distance']) * 1e3:+.1f} mm; "
        f"outside on {int(np.sum(result['zmp_support_distance'] < 0))} samples",
    ])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("plan", type=Path, help="footstep plan (JSON, see the module docstring)")
    parser.add_argument("out", type=Path, help="trajectories and timings (.npz)")
    parser.add_argument("--talos-urdf", type=Path, default=example_robot_data_talos_urdf())
    parser.add_argument("--horizon", type=int, default=48, help="LIPM steps planned ahead")
    parser.add_argument("--timesteps", type=int, default=10, help="LIPM steps per single support")
    parser.add_argument("--replan-period", type=float, default=0.1, help="s, least time between replans")
    parser.add_argument("--dt", type=float, default=1e-3, help="s, sampling period of the output")
    args = parser.parse_args(argv)
    plan = json.loads(args.plan.read_text())
    urdf = write_placo_urdf(args.talos_urdf, URDF_OUT)
    result = run(plan, urdf, args.horizon, args.timesteps, args.replan_period, args.dt)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    np.savez(args.out, **result)
    print(summary(result))


if __name__ == "__main__":
    main()
