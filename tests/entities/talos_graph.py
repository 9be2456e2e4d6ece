"""A TALOS inverse-dynamics graph on a fixed robot state, shared by the solver and task tests."""

from __future__ import annotations

import numpy as np

import dgraph as dg
from dgraph.entities.contacts import Contact6d
from dgraph.entities.features import CenterOfMass, FramePose, JointPosture
from dgraph.entities.robot import RobotModel, load_model
from dgraph.entities.solvers import InverseDynamicsSolver, TorqueSolver
from dgraph.entities.tasks import Task

TASKS = ("com_task", "posture_task", "waist_task")
CONTACTS = ("left_foot", "right_foot")


def half_sitting() -> np.ndarray:
    return load_model("talos").referenceConfigurations["half_sitting"].copy()


def build(q: np.ndarray | None = None, v: np.ndarray | None = None, contact_forces: str = "corners",
          solver_type: type[TorqueSolver] = InverseDynamicsSolver, **solver_params) -> dg.Graph:
    """Robot state set as constants; CoM held at its half-sitting position; two feet in contact
    (Contact6d with ``forces=contact_forces``); the solver a ``solver_type``."""
    g = dg.Graph(dt=0.001, name="talos_id_test")
    robot = g.add(RobotModel("robot", frames=["left_sole_link"]))
    model = robot.pin_model
    robot.q.set(half_sitting() if q is None else q)
    robot.v.set(np.zeros(model.nv) if v is None else v)
    com = g.add(CenterOfMass("com"))
    com.reference_position.set(_com_at(model, half_sitting()))
    g.add(JointPosture("posture"))
    g.add(FramePose("waist", frame="base_link", mask="000111"))
    for feature in ("com", "posture", "waist"):
        g.plug("robot.state", f"{feature}.robot")
    gains = {"com_task": (20.0, 3.0, 1e3), "waist_task": (100.0, 20.0, 1.0)}
    for name, (kp, kd, w) in gains.items():
        task = g.add(Task(name))
        task.kp.set(kp)
        task.kd.set(kd)
        task.weight.set(w)
    posture_task = g.add(Task("posture_task", critical_damping=True))
    posture_task.kp.set(10.0)
    posture_task.weight.set(0.1)
    for name in TASKS:
        g.plug(f"{name.removesuffix('_task')}.feature", f"{name}.feature")
    for side in ("left", "right"):
        contact = g.add(Contact6d(f"{side}_foot", frame=f"{side}_sole_link", forces=contact_forces))
        contact.kp.set(30.0)
        contact.kd.set(2 * np.sqrt(30.0))
        g.plug("robot.state", f"{side}_foot.robot")
    g.add(solver_type("solver", tasks=list(TASKS), contacts=list(CONTACTS), **solver_params))
    g.plug("robot.state", "solver.robot")
    for name in TASKS:
        g.plug(f"{name}.equation", f"solver.{name}")
    for name in CONTACTS:
        g.plug(f"{name}.contact", f"solver.{name}")
    return g


def _com_at(model, q) -> np.ndarray:
    import pinocchio as pin

    return pin.centerOfMass(model, model.createData(), q).copy()
