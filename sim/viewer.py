"""An interactive MuJoCo window on a running simulation (``mujoco.viewer.launch_passive``).

The window shows the simulation's own ``MjData``: the simulation runs in the caller's thread and
:meth:`PassiveViewer.sync` copies its state to the window (and the window's perturbations back)
at a frame rate, waiting if the simulation runs ahead of the wall clock (``realtime``). Closing
the window does not stop the simulation; it is only no longer shown.

A window needs a display: on Linux ``DISPLAY`` (X11) or ``WAYLAND_DISPLAY``. :func:`check_display`
refuses with :class:`ViewerError` when there is none, or when GLFW cannot open it (a ``DISPLAY``
naming no X server): MuJoCo's viewer initialises GLFW in its own thread, where a failure ends
the process with ``ERROR: could not initialize GLFW`` instead of raising.

The window is a GLFW one whatever ``MUJOCO_GL`` says: that variable (``egl`` by default in
:mod:`dgraph_sim`) chooses the OpenGL platform of offscreen rendering only (videos, snapshots),
so a viewer and a video can run together.
"""

from __future__ import annotations

import os
import sys
import threading
import time
import warnings

import mujoco

CLOSE_TIMEOUT = 5.0
"""Seconds :meth:`PassiveViewer.close` waits for the window's thread to end."""


class ViewerError(RuntimeError):
    """The viewer cannot open (no display, or GLFW failed)."""


def display_available() -> bool:
    """True if a window can be opened: not Linux/BSD, or ``DISPLAY`` / ``WAYLAND_DISPLAY`` set."""
    if not sys.platform.startswith(("linux", "freebsd")):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def check_display() -> None:
    """Raise :class:`ViewerError` unless a window can open: a display variable is set (see
    :func:`display_available`) and GLFW initialises on it (GLFW then stays initialised, as the
    viewer would leave it; initialising again is a no-op)."""
    if not display_available():
        raise ViewerError("no display: DISPLAY and WAYLAND_DISPLAY are unset (a headless machine); "
                          "record a video (video_path) or a Rerun recording instead")
    try:
        import glfw

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ok = glfw.init()
    except Exception as exc:  # no GLFW library, or GLFW errors reported as exceptions
        raise ViewerError(f"the MuJoCo viewer could not open: {type(exc).__name__}: {exc}") from None
    if not ok:
        why = "; ".join(str(w.message) for w in caught) or "glfw.init() failed"
        display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
        raise ViewerError(f"the MuJoCo viewer could not open: GLFW cannot use the display {display!r}: {why}")


class PassiveViewer:
    """A MuJoCo viewer window synced every ``1 / fps`` seconds of simulated time.

    ``model``, ``data``: what the simulation steps; ``dt``: its tick in seconds; ``realtime``:
    hold each sync until the wall clock has caught up with the simulated time. The window opens
    here (:func:`check_display` first) and :meth:`close` waits until it is gone.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, dt: float, fps: float = 30.0,
                 realtime: bool = True):
        check_display()
        try:
            import mujoco.viewer

            before = set(threading.enumerate())
            self.handle = mujoco.viewer.launch_passive(model, data)
        except Exception as exc:  # a missing GL library, a refused model
            raise ViewerError(f"the MuJoCo viewer could not open: {type(exc).__name__}: {exc}") from None
        # the window's thread (launch_passive keeps no reference to it): joined by close()
        self._threads = [th for th in threading.enumerate() if th not in before]
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
        """Close the window (if still open) and wait (up to :data:`CLOSE_TIMEOUT` s) until it is gone."""
        self.handle.close()
        deadline = time.monotonic() + CLOSE_TIMEOUT
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))
        self._threads = []
