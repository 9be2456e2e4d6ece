"""Disturbances the controller is not told about: scene bodies that vanish at a given time."""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

AWAY = np.array([0.0, 0.0, -100.0])
"""Where a removed body goes: far below the floor, out of every contact."""


class Removals:
    """Moves mocap bodies out of the scene at given times (the block pushed by a tool, a support).

    The bodies must be mocap bodies (``Scene.box(..., mocap=True)``): their pose lives in
    ``MjData.mocap_pos``, so removing one changes this simulation only, not the shared model,
    and MuJoCo's saved state (``mjSTATE_INTEGRATION``) covers it.
    """

    def __init__(self, model: mujoco.MjModel, bodies: Sequence[str], times: Sequence[float]):
        if len(bodies) != len(times):
            raise ValueError(f"{len(bodies)} bodies to remove but {len(times)} removal times")
        self.model = model
        self.schedule: list[tuple[float, int]] = []
        for body, time in zip(bodies, times, strict=True):
            body_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
            if body_id < 0 or model.body_mocapid[body_id] < 0:
                raise ValueError(f"cannot remove {body!r}: not a mocap body of the scene")
            self.schedule.append((float(time), int(model.body_mocapid[body_id])))

    def apply(self, data: mujoco.MjData, time: float) -> None:
        """Move every body whose removal time has come (idempotent). When one moves, the position
        stage is redone (``mj_step1``: its contacts were found before it moved), so the step that
        follows no longer feels it."""
        moved = False
        for removal_time, mocap in self.schedule:
            if time >= removal_time and not np.array_equal(data.mocap_pos[mocap], AWAY):
                data.mocap_pos[mocap] = AWAY
                moved = True
        if moved:
            mujoco.mj_step1(self.model, data)
