"""The TALOS sway graph of ``talos_sway.yaml``, built in Python.

Run it with ``python graphs/talos_sway.py [--duration S] [--rrd out/talos_sway.rrd]``; it
builds exactly the graph that ``dgraph.load("graphs/talos_sway.yaml")`` builds (a test checks
that both save to the same file), runs it in MuJoCo and writes a Rerun recording.
"""

from __future__ import annotations

import argparse

import numpy as np

import dgraph as dg
from dgraph.entities.contacts import Contact6d
from dgraph.entities.estimators import FloatingBaseEstimator
from dgraph.entities.features import AngularMomentum, CenterOfMass, FramePose, JointPosture
from dgraph.entities.recording import Recorder, RobotView
from dgraph.entities.recording.rerun_stream import recording_by_default
from dgraph.entities.references import Sinusoid
from dgraph.entities.robot import RobotModel
from dgraph.entities.solvers import InverseDynamicsSolver
from dgraph.entities.tasks import Task
from dgraph_sim.device import MujocoDevice

ROBOT = "talos"  # the robot model, named once: every entity that loads a model takes this one
HALF_SITTING_COM = [-0.0031639, 0.0012374, 0.8766814]
SENSORS = ("imu_orientation", "imu_angular_velocity", "imu_linear_acceleration", "encoder_position",
           "encoder_velocity", "ft_left_ankle", "ft_right_ankle")
# Table 4.3 (TSID torque): posture Kp per joint; legs, torso, arm + gripper (x2), head
POSTURE_KP = [10, 5, 5, 1, 10, 10] * 2 + [100, 100] + [50, 10, 10, 10, 50, 10, 10, 10] * 2 + [100, 100]
RECORDED = ["com_reference.output", "robot.com_position", "com.error", "solver.contact_wrenches",
            "solver.normal_force_total", "solver.tau", "solver.status", "solver.iterations", "solver.solve_time",
            "device.q", "estimator.q", "device.contact_force_total", "device.fallen"]


TASKS = ("com_task", "waist_task", "posture_task", "momentum_task")
FEATURES = {
    "com_task": lambda: CenterOfMass("com"),
    "waist_task": lambda: FramePose("waist", frame="base_link", mask="000111"),
    "posture_task": lambda: JointPosture("posture", model=ROBOT),
    "momentum_task": lambda: AngularMomentum("momentum"),
}


def build(duration: float = 20.0, tasks: tuple[str, ...] = TASKS, record: bool = True) -> dg.Graph:
    """TALOS in MuJoCo, estimator, model, CoM sway, waist, posture, momentum, two feet, ID QP.

    ``tasks`` selects a subset of the tasks (``bench/talos_tick.py`` runs CoM and posture only,
    TSID's benchmark set); ``record=False`` leaves out the Recorder and the 3D view.
    """
    g = dg.Graph(dt=0.001, name="talos_sway")
    g.duration = duration
    g.add(MujocoDevice("device", model=ROBOT, scene="flat", control_mode="torque"))
    g.add(FloatingBaseEstimator("estimator", model=ROBOT))
    g.add(RobotModel("robot", model=ROBOT))
    features = {task: FEATURES[task]() for task in TASKS if task in tasks}  # com_task is required
    for feature in features.values():
        g.add(feature)
    g.add(Sinusoid("com_reference", amplitude=[0.0, 0.05, 0.0], frequency=0.5, ramp=1.0, offset=HALF_SITTING_COM))
    gains = {"com_task": (1000.0, 20.0, 3.0), "waist_task": (1.0, 100.0, 20.0),
             "posture_task": (0.1, POSTURE_KP, None), "momentum_task": (0.02, 10.0, None)}
    tasks = {name: gains[name] for name in TASKS if name in tasks}
    for name in tasks:
        g.add(Task(name, critical_damping=True) if name == "posture_task" else Task(name))
    for side in ("left", "right"):
        g.add(Contact6d(f"{side}_foot", frame=f"{side}_sole_link", mu=0.3, min_normal_force=1.0))
    g.add(InverseDynamicsSolver("solver", model=ROBOT, tasks=list(tasks), contacts=["left_foot", "right_foot"]))

    for sensor in SENSORS:
        g.plug(f"device.{sensor}", f"estimator.{sensor}")
    g.plug("estimator.q", "robot.q")
    g.plug("estimator.v", "robot.v")
    for reader in (*(f.name for f in features.values()), "left_foot", "right_foot", "solver"):
        g.plug("robot.state", f"{reader}.robot")
    g.plug("com_reference.output", "com.reference_position")
    g.plug("com_reference.velocity", "com.reference_velocity")
    g.plug("com_reference.acceleration", "com.reference_acceleration")
    for name in tasks:
        g.plug(f"{features[name].name}.feature", f"{name}.feature")
        g.plug(f"{name}.equation", f"solver.{name}")
    for name in ("left_foot", "right_foot"):
        g.plug(f"{name}.contact", f"solver.{name}")
    g.plug("solver.tau", "device.control")

    for name, (weight, kp, kd) in tasks.items():
        g[name].weight.set(weight)
        g[name].kp.set(np.asarray(kp, dtype=float))
        if kd is not None:  # posture: critically damped; momentum: proportional only (Eq. 2.32)
            g[name].kd.set(kd)
    for name in ("left_foot", "right_foot"):
        g[name].kp.set(30.0)
        g[name].kd.set(11.0)
    if record:
        g.add(RobotView("view", model=ROBOT, decimation=20))
        g.plug("device.q", "view.q")
        g.add(Recorder("recorder", signals=RECORDED))
    return g


def main() -> None:
    """Build, run and record."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0, help="simulated seconds")
    parser.add_argument("--rrd", default="out/talos_sway.rrd", help="Rerun recording to write")
    args = parser.parse_args()
    with recording_by_default("save"):  # the library records nothing unless asked: this script asks
        graph = build(args.duration)
    graph["recorder"].rrd_path = graph["view"].rrd_path = args.rrd  # one recording: series and 3D view
    with graph:
        graph.run(duration=args.duration)
    print(f"wrote {args.rrd}")


if __name__ == "__main__":
    main()
