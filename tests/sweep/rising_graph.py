"""A cheap graph for the sweep tests, whose outcome is known in closed form.

``body`` (a KinematicDevice in velocity mode) rises at ``push.gain`` m/s: ``q_z(n) = n dt push``.
``height`` (a ContactDetector on ``body.q`` as its force) turns ``in_contact``, the fall signal,
at the end of the tick after the first one where ``q_z >= height.on_force``. ``fault`` (a
SensorFault on the command) adds nothing (``kind: jump``, magnitude 0), or with ``kind: inf``
makes the command infinite at tick 30, where the run diverges (``body.q`` staged infinite).
"""

from __future__ import annotations

import math
from pathlib import Path

DT = 0.01
DURATION = 1.0
FAULT_TICK = 30
RISING = f"""
name: rising
dt: {DT}
duration: {DURATION}
entities:
  direction: {{type: Constant, params: {{value: [0.0, 0.0, 1.0]}}}}
  push: {{type: Gain, params: {{size: 3}}}}
  fault: {{type: SensorFault, params: {{kind: jump, magnitude: 0.0, start: {FAULT_TICK * DT}}}}}
  body: {{type: KinematicDevice, params: {{size: 3}}}}
  height: {{type: ContactDetector, params: {{on_force: 0.45, off_force: 0.01, on_time: 0.0}}}}
plugs:
  - direction.output -> push.input
  - push.output -> fault.reading
  - fault.output -> body.control
  - body.q -> height.force
set:
  push.gain: 0.3
  recorder.npz_path: recorded.npz
record: [body.q]
"""
FALL = "height.in_contact"
GRID = {"push.gain": [0.3, 0.7, 1.1, 1.7, 2.3], "height.on_force": [0.45, 0.95], "fault.kind": ["jump", "inf"]}
"""20 runs: 3 ok, 9 fell, 8 diverged (no push and height put a fall exactly on a tick)."""


def write_rising(folder: Path) -> str:
    """Write the rising graph file into ``folder``; its path."""
    path = folder / "rising.yaml"
    path.write_text(RISING)
    return str(path)


def expected(push: float, height: float, kind: str) -> tuple[str, float | None, float]:
    """The status, fall time and simulated time (s) of a run of the rising graph."""
    fall_tick = math.ceil(height / (DT * push)) + 1
    last_tick = FAULT_TICK if kind == "inf" else round(DURATION / DT)
    if fall_tick <= last_tick:
        return "fell", fall_tick * DT, fall_tick * DT
    return ("diverged" if kind == "inf" else "ok"), None, last_tick * DT
