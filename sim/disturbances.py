"""Disturbances the controller is not told about: scene bodies that vanish at a given time or
when a signal turns true."""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

AWAY = np.array([0.0, 0.0, -100.0])
"""Where a removed body goes: far below the floor, out of every contact."""


class Removals:
    """Moves mocap bodies out of the scene at given times (the block pushed by a tool, a support),
    or when their trigger fires (``triggered``: an event of the run, e.g. a hole breaking through
    once the drill has pushed for a while). A removed body stays away until the data is reset.

    The bodies must be mocap bodies (``Scene.box(..., mocap=True)``): their pose lives in
    ``MjData.mocap_pos``, so removing one changes this simulation only, not the shared model,
    and MuJoCo's saved state (``mjSTATE_INTEGRATION``) covers it.
    """

    def __init__(self, model: mujoco.MjModel, bodies: Sequence[str], times: Sequence[float],
                 triggered: Sequence[str] = ()):
        if len(bodies) != len(times):
            raise ValueError(f"{len(bodies)} bodies to remove but {len(times)} removal times")
        self.model = model
        self.schedule = [(float(time), self._mocap(body)) for body, time in zip(bodies, times, strict=True)]
        self.triggered = [self._mocap(body) for body in triggered]
        """Mocap indices of the bodies removed by a trigger, in the order of ``triggered``."""

    def _mocap(self, body: str) -> int:
        body_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, body)
        if body_id < 0 or self.model.body_mocapid[body_id] < 0:
            raise ValueError(f"cannot remove {body!r}: not a mocap body of the scene")
        return int(self.model.body_mocapid[body_id])

    def apply(self, data: mujoco.MjData, time: float, fired: Sequence[bool] = ()) -> None:
        """Move every body whose removal time has come or whose trigger fired (``fired``: one flag
        per body of ``triggered``); idempotent. When one moves, the position stage is redone
        (``mj_step1``: its contacts were found before it moved), so the step that follows no
        longer feels it."""
        due = [mocap for removal_time, mocap in self.schedule if time >= removal_time]
        due += [mocap for mocap, fire in zip(self.triggered, fired, strict=True) if fire]
        moved = False
        for mocap in due:
            if not np.array_equal(data.mocap_pos[mocap], AWAY):
                data.mocap_pos[mocap] = AWAY
                moved = True
        if moved:
            mujoco.mj_step1(self.model, data)
