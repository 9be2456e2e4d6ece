"""The five-level TALOS inverse-kinematics stack of thesis Table 4.1, shared by the tests and the benchmark.

Levels: 0 feet contacts and joint limits, I CoM height, II CoM lateral-sagittal, III waist
orientation, IV posture (half-sitting); gains of Table 4.3's IK column (contacts 1000, CoM 100,
waist 300, posture 100, 1/s). An optional left-hand position task goes between the CoM and the
waist. A KinematicDevice integrates the velocity (``q+ = q (+) dt v``).
"""

from __future__ import annotations

import numpy as np

import dgraph as dg
from dgraph.entities.devices import KinematicDevice
from dgraph.entities.features import CenterOfMass, FramePose, JointPosture
from dgraph.entities.hierarchy import HierarchicalSolver, JointLimits, VelocityContact, VelocityTask
from dgraph.entities.robot import RobotModel, load_model

HAND_FRAME = "gripper_left_base_link"
GAINS = {"com_height": 100.0, "com_xy": 100.0, "waist": 300.0, "posture": 100.0, "hand": 100.0}


def half_sitting() -> np.ndarray:
    return load_model("talos").referenceConfigurations["half_sitting"].copy()


def build(q: np.ndarray | None = None, *, hand: bool = False, limits: bool = True, **solver_params) -> dg.Graph:
    """The Table 4.1 stack on a kinematic TALOS starting at ``q`` (default half-sitting); with
    ``limits`` the joint limits form a level of their own above it (Table 4.1 does not list
    them; sharing the contacts' level would let a contact correction trade against them)."""
    g = dg.Graph(dt=0.001, name="talos_ik_test")
    q0 = half_sitting() if q is None else q
    g.add(KinematicDevice("device", control_mode="velocity", model="talos", q0=q0))
    g.add(RobotModel("robot"))
    g.plug("device.q", "robot.q")
    g.plug("device.v", "robot.v")
    for side in ("left", "right"):
        foot = g.add(VelocityContact(f"{side}_foot", frame=f"{side}_sole_link"))
        foot.kp.set(1000.0)
        g.plug("robot.state", f"{side}_foot.robot")
    g.add(JointLimits("limits"))
    g.plug("robot.state", "limits.robot")
    com = load_com(q0)
    features = {"com_height": CenterOfMass("com_height_feature", mask="001"),
                "com_xy": CenterOfMass("com_xy_feature", mask="110"),
                "waist": FramePose("waist_feature", frame="base_link", mask="000111"),
                "posture": JointPosture("posture_feature")}
    if hand:
        features["hand"] = FramePose("hand_feature", frame=HAND_FRAME, mask="111000")
    for name, feature in features.items():
        g.add(feature)
        if isinstance(feature, CenterOfMass):
            feature.reference_position.set(com)
        task = g.add(VelocityTask(name))
        task.gain.set(GAINS[name])
        g.plug("robot.state", f"{feature.name}.robot")
        g.plug("robot.state", f"{name}.robot")
        g.plug(f"{feature.name}.feature", f"{name}.feature")
    tasks = ["left_foot", "right_foot", *(["limits"] if limits else []), "com_height", "com_xy",
             *(["hand"] if hand else []), "waist", "posture"]
    top = 1 if limits else 0  # the limits alone on top: nothing below can trade against them
    priorities = [top, top, *([0] if limits else []), top + 1, top + 2, *([top + 3] if hand else []),
                  top + 3 + hand, top + 4 + hand]
    g.add(HierarchicalSolver("solver", tasks=tasks, priorities=priorities, **solver_params))
    for name in tasks:
        g.plug(f"{name}.rows", f"solver.{name}")
    g.plug("solver.velocity", "device.control")
    return g


def load_com(q: np.ndarray) -> np.ndarray:
    import pinocchio as pin

    model = load_model("talos")
    return pin.centerOfMass(model, model.createData(), q).copy()
