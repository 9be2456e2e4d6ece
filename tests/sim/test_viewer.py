"""The interactive viewer option: refused, naming the device and the parameter, without a display
(or with one GLFW cannot open); under a virtual X display (Xvfb) its window opens at the first
tick, shows the robot, leaves the simulation as it is, works with a video and closes with the graph.

The window tests start their own Xvfb on a free display number; they are skipped when Xvfb or
xwininfo is missing, unless ``CI`` is set (then they fail: ``.ci/run`` installs ``xvfb`` and
``x11-utils``). The runs happen in a child process: GLFW stays connected to the display, which is
killed after the test.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

import dgraph as dg
from dgraph_sim import viewer
from dgraph_sim.device import MujocoDevice
from tests.conftest import stop_process

ROOT = Path(__file__).resolve().parents[2]
PANDA = ROOT / "graphs" / "panda_reach.yaml"


def test_without_a_display_the_viewer_is_refused_naming_the_entity_and_the_parameter(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(viewer.sys, "platform", "linux")
    assert not viewer.display_available()
    with pytest.raises(dg.ParamError, match=r"arm: parameter 'viewer': no display: DISPLAY and WAYLAND_DISPLAY "
                                            r"are unset") as info:
        MujocoDevice("arm", model="panda", viewer=True, dt=0.001)
    assert info.value.entity == "arm"
    assert MujocoDevice("arm", model="panda", dt=0.001)._viewer is None  # the default: no window


def test_a_display_variable_is_enough_to_try(monkeypatch):
    monkeypatch.setattr(viewer.sys, "platform", "linux")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.setenv("WAYLAND_DISPLAY", "wayland-0")
    assert viewer.display_available()


def _require(*programs: str) -> None:
    """Skip (fail with ``CI`` set) unless every program is installed."""
    missing = [p for p in programs if shutil.which(p) is None]
    if missing:
        message = f"{', '.join(missing)} not installed (apt-get install xvfb x11-utils)"
        if os.environ.get("CI"):
            pytest.fail(f"CI is set and {message}: .ci/run installs them")
        pytest.skip(message)


@pytest.fixture
def xvfb() -> Iterator[str]:
    """A virtual X display (1280x800, 24 bits) on a number Xvfb finds free (``-displayfd``);
    yields its ``DISPLAY`` value and kills the server afterwards. ``-noreset``: by default Xvfb
    resets when its last client leaves, refusing the connections made meanwhile (seen: a
    screenshot right after an xwininfo failed with ``X connection failed``)."""
    _require("Xvfb", "xwininfo")
    read, write = os.pipe()
    with tempfile.TemporaryFile() as log:
        server = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "1280x800x24",
                                   "-nolisten", "tcp", "-noreset"],
                                  pass_fds=(write,), stdout=subprocess.DEVNULL, stderr=log)
        os.close(write)
        try:
            with os.fdopen(read) as numbers:
                number = numbers.readline().strip()  # written once the server accepts connections
            if not number:
                server.wait(timeout=10)
                log.seek(0)
                pytest.fail(f"Xvfb did not start: {log.read().decode(errors='replace')}")
            yield f":{number}"
        finally:
            stop_process(server)


# Run in a child process under the virtual display: panda_reach for 0.3 s without a window, with
# one, with one and a video; while each graph is open after its run, the MuJoCo windows that
# xwininfo lists and a screenshot of the screen (Pillow over XCB); after close, the windows again.
CHILD = r"""
import json, subprocess, sys, time
import numpy as np
from PIL import ImageGrab
import dgraph

path, video = sys.argv[1], sys.argv[2]

def windows():
    tree = subprocess.run(["xwininfo", "-root", "-tree"], capture_output=True, text=True, check=True).stdout
    return [line.strip() for line in tree.splitlines() if '"MuJoCo :' in line]

def colours():
    screen = np.asarray(ImageGrab.grab(xdisplay=None).convert("RGB"))
    return len(np.unique(screen.reshape(-1, 3), axis=0))

def run(overrides):
    graph = dgraph.load(path, overrides)
    opened_before_run = windows()
    graph.run(duration=0.3, progress=False)
    q = graph.entity("device").q.value.tolist()
    shown = windows()
    seen, deadline = colours(), time.monotonic() + 10.0
    while shown and seen < 100 and time.monotonic() < deadline:  # the viewer draws in its own thread:
        time.sleep(0.1)                                          # on a loaded machine, after the run
        seen = max(seen, colours())
    graph.close()
    return {"q": q, "before_run": opened_before_run, "shown": shown, "after_close": windows(), "colours": seen}

print(json.dumps({"plain": run({}), "viewer": run({"device.viewer": True}),
                  "video": run({"device.viewer": True, "device.video_path": video})}))
"""


@pytest.mark.timeout(120)
def test_under_a_virtual_display_the_window_shows_the_run_without_changing_it_and_closes(xvfb, tmp_path):
    video = tmp_path / "reach.mp4"
    env = {**os.environ, "DISPLAY": xvfb}
    env.pop("WAYLAND_DISPLAY", None)
    env.pop("MUJOCO_GL", None)  # dgraph_sim's default (egl) for the video: the window is GLFW's anyway
    child = subprocess.run([sys.executable, "-c", CHILD, str(PANDA), str(video)], capture_output=True, text=True,
                           env=env, timeout=100, cwd=tmp_path)
    assert child.returncode == 0, child.stderr
    runs = json.loads(child.stdout.splitlines()[-1])
    plain, shown, filmed = runs["plain"], runs["viewer"], runs["video"]
    assert plain["shown"] == [] and plain["colours"] == 1  # no window: the empty (black) screen
    for run in (shown, filmed):
        assert run["before_run"] == []  # loading a graph opens no window: its first tick does
        assert len(run["shown"]) == 1 and '"MuJoCo : panda"' in run["shown"][0], run["shown"]
        assert run["colours"] >= 100, run["colours"]  # the scene and the viewer's panels (measured: ~850)
        assert run["after_close"] == []  # closing the graph closed the window
        # the window does not change the simulation (runs of one graph differ by ~1e-17 anyway)
        assert max(abs(a - b) for a, b in zip(run["q"], plain["q"], strict=True)) <= 1e-12
    assert video.is_file() and video.stat().st_size > 1000  # offscreen (EGL) video and window together


@pytest.mark.timeout(60)
def test_a_display_that_glfw_cannot_open_is_refused_not_fatal():
    """A DISPLAY naming no X server: GLFW would fail in the viewer's thread, where MuJoCo ends the
    process (``ERROR: could not initialize GLFW``); the device is refused with a ParamError instead,
    naming the display."""
    unused = next(n for n in range(4000, 4200) if not Path(f"/tmp/.X11-unix/X{n}").exists())
    env = {**os.environ, "DISPLAY": f":{unused}"}
    code = ("import dgraph as dg\nfrom dgraph_sim.device import MujocoDevice\n"
            "try:\n    MujocoDevice('arm', model='panda', viewer=True, dt=0.001)\n"
            "except dg.ParamError as exc:\n    print('refused:', exc)\n")
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=50)
    assert child.returncode == 0, child.stderr
    assert f"refused: arm: parameter 'viewer': the MuJoCo viewer could not open: GLFW cannot use the display " \
           f"':{unused}'" in child.stdout, child.stdout
