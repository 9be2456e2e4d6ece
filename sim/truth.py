"""The ground truth of a run: what the simulator's configurations say of the robot (its CoM, its
frames), for evaluating what a controller only estimated."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from dgraph.entities.robot import load_model


def robot_mass(model: str | Any = "talos") -> float:
    """The robot's mass in its model (kg)."""
    return float(sum(inertia.mass for inertia in load_model(model).inertias))


def true_com_and_frames(q: np.ndarray, frames: Sequence[str],
                        model: str | Any = "talos") -> tuple[np.ndarray, np.ndarray]:
    """The CoM (ticks x 3) and the positions of ``frames`` (ticks x len(frames) x 3), world, of
    each configuration of ``q`` (ticks x nq, Pinocchio convention: ``device.q`` recorded)."""
    robot = load_model(model)
    data = robot.createData()
    missing = [name for name in frames if not robot.existFrame(name)]
    if missing:
        raise ValueError(f"no frame {', '.join(map(repr, missing))} in the model {robot.name!r}")
    ids = [robot.getFrameId(name) for name in frames]
    com, positions = [], []
    for qi in q:
        com.append(pin.centerOfMass(robot, data, qi).copy())
        pin.updateFramePlacements(robot, data)
        positions.append([data.oMf[i].translation.copy() for i in ids])
    return np.array(com), np.array(positions).reshape(len(q), len(ids), 3)
