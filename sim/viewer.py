"""An interactive MuJoCo window on a running simulation (``mujoco.viewer.launch_passive``).

The window shows the simulation's own ``MjData``: the simulation runs in the caller's thread and
:meth:`PassiveViewer.sync` copies its state to the window (and the window's perturbations back)
at a frame rate, waiting if the simulation runs ahead of the wall clock (``realtime``). Closing
the window does not stop the simulation; it is only no longer shown.

A window needs a display: on Linux ``DISPLAY`` (X11) or ``WAYLAND_DISPLAY``. Without one,
:class:`PassiveViewer` refuses with :class:`ViewerError` before touching MuJoCo's GLFW.
"""

from __future__ import annotations

import os
import sys
import time

import mujoco


class ViewerError(RuntimeError):
    """The viewer cannot open (no display, or GLFW failed)."""


def display_available() -> bool:
    """True if a window can be opened: not Linux/BSD, or ``DISPLAY`` / ``WAYLAND_DISPLAY`` set."""
    if not sys.platform.startswith(("linux", "freebsd")):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class PassiveViewer:
    """A MuJoCo viewer window synced every ``1 / fps`` seconds of simulated time.

    ``model``, ``data``: what the simulation steps; ``dt``: its tick in seconds; ``realtime``:
    hold each sync until the wall clock has caught up with the simulated time.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, dt: float, fps: float = 30.0,
                 realtime: bool = True):
        if not display_available():
            raise ViewerError("no display: DISPLAY and WAYLAND_DISPLAY are unset (a headless machine); "
                              "record a video (video_path) or a Rerun recording instead")
        try:
            import mujoco.viewer

            self.handle = mujoco.viewer.launch_passive(model, data)
        except Exception as exc:  # GLFW without a usable display, a missing GL library
            raise ViewerError(f"the MuJoCo viewer could not open: {type(exc).__name__}: {exc}") from None
        self.interval = max(1, round(1.0 / (fps * dt)))
        self.dt, self.realtime = dt, realtime
        self._next = 0
        self._start: tuple[float, float] | None = None  # (wall clock, simulated time) at the first sync

    def sync(self, t: int) -> None:
        """After hook: show the state at tick ``t`` if a frame is due and the window is open."""
        if t < self._next or not self.handle.is_running():
            return
        self._next = t + self.interval
        if self.realtime:
            now, simulated = time.perf_counter(), t * self.dt
            if self._start is None:
                self._start = (now, simulated)
            ahead = (simulated - self._start[1]) - (now - self._start[0])
            if ahead > 0.0:
                time.sleep(ahead)
        self.handle.sync()

    def close(self) -> None:
        """Close the window (if still open)."""
        self.handle.close()
