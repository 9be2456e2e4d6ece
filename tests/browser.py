"""Headless Chromium driven through the DevTools protocol over a pipe (``--remote-debugging-pipe``:
JSON messages separated by NUL bytes on file descriptors 3 and 4), with the standard library only.

Chromium is Debian's (``apt-get install chromium``); no browser is downloaded. WebGL is drawn by
SwiftShader, Chromium's software renderer, so the Rerun web viewer (wasm + WebGL) renders
without a display or a GPU.
"""

from __future__ import annotations

import base64
import io
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
"""What works on a headless Debian machine as root, WebGL through SwiftShader."""

PLACE_PIPES = """\
import ctypes, os, signal, sys
read, write, command = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3:]
read, write = os.dup(read), os.dup(write)  # new lowest fds, read's below write's: placing one spares the other
os.dup2(read, 3)
os.dup2(write, 4)
os.set_inheritable(3, True)  # dup2 onto itself (read was 3) keeps os.dup's close-on-exec
os.set_inheritable(4, True)
os.closerange(5, 1 << 16)
ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG: ends with the test process
os.execv(command[0], command)
"""
"""Run by a Python child given the pipe ends (``pass_fds``): puts them at 3 and 4, where
``--remote-debugging-pipe`` wants them, then becomes Chromium. ``preexec_fn`` would do the same
in the forked child but is unsafe in a process with threads (pytest's, Rerun's)."""


def chromium_path() -> str | None:
    """Debian's Chromium, if installed."""
    return shutil.which("chromium") or (str(Path("/usr/bin/chromium")) if Path("/usr/bin/chromium").exists() else None)


class Chromium:
    """One headless Chromium with one page; :meth:`close` ends it (also as a context manager)."""

    def __init__(self, executable: str, width: int = 1280, height: int = 800, timeout: float = 30.0):
        self.profile = tempfile.mkdtemp(prefix="dgraph-chromium-")
        self.timeout = timeout
        to_chrome, from_chrome = os.pipe(), os.pipe()
        self.log = tempfile.TemporaryFile()
        self.process = subprocess.Popen(
            [sys.executable, "-I", "-S", "-c", PLACE_PIPES, str(to_chrome[0]), str(from_chrome[1]),
             executable, *FLAGS, f"--user-data-dir={self.profile}", f"--window-size={width},{height}",
             "--remote-debugging-pipe", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=self.log, stderr=self.log, pass_fds=(to_chrome[0], from_chrome[1]))
        os.close(to_chrome[0])
        os.close(from_chrome[1])
        self._write = os.fdopen(to_chrome[1], "wb", buffering=0)
        self._read = os.fdopen(from_chrome[0], "rb", buffering=0)
        self._buffer = b""
        self._id = 0
        self.session: str | None = None

    def call(self, method: str, params: dict[str, Any] | None = None, page: bool = True) -> dict[str, Any]:
        """Send one DevTools command (to the page's session unless ``page=False``) and return its
        result; ``TimeoutError`` if no reply comes within ``timeout`` seconds."""
        self._id += 1
        message: dict[str, Any] = {"id": self._id, "method": method, "params": params or {}}
        if page and self.session:
            message["sessionId"] = self.session
        self._write.write(json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + self.timeout
        while True:
            while b"\0" not in self._buffer:
                left = deadline - time.monotonic()
                if left <= 0 or not select.select([self._read], [], [], left)[0]:
                    raise TimeoutError(f"chromium: no reply to {method} in {self.timeout:g} s: "
                                       f"{self.output()[-2000:]}")
                chunk = os.read(self._read.fileno(), 1 << 16)
                if not chunk:
                    raise RuntimeError(f"chromium closed the DevTools pipe: {self.output()[-2000:]}")
                self._buffer += chunk
            raw, self._buffer = self._buffer.split(b"\0", 1)
            reply = json.loads(raw)
            if reply.get("id") == self._id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]

    def open(self, url: str) -> None:
        """Open ``url`` in a new page and attach to it."""
        target = self.call("Target.createTarget", {"url": url}, page=False)["targetId"]
        self.session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True},
                                 page=False)["sessionId"]

    def screenshot(self) -> bytes:
        """The page as PNG bytes."""
        return base64.b64decode(self.call("Page.captureScreenshot", {"format": "png"})["data"])

    def output(self) -> str:
        """What Chromium printed."""
        self.log.seek(0)
        return self.log.read().decode(errors="replace")

    def close(self) -> None:
        """End Chromium and remove its profile."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._write.close()
        self._read.close()
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self) -> Chromium:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


PLOT_AREA = (200, 36, 980, 450)
"""Where the Rerun web viewer draws the recording's views in a 1280x800 page: right of its
sources panel, left of its selection panel, above its timeline (left, top, right, bottom)."""


def series_colours(png: bytes, box: tuple[int, int, int, int] = PLOT_AREA, chroma: int = 80,
                   least: int = 100) -> tuple[int, int]:
    """How much of the plot area is drawn in the colours of plotted series: the number of its
    saturated pixels (max - min of R, G, B at least ``chroma``; the viewer's own interface is grey
    but for a blue or orange accent) and the number of twelfths of the hue circle that at least
    ``least`` of them fall in (one per series colour, about)."""
    from PIL import Image

    image = Image.open(io.BytesIO(png)).convert("RGB").crop(box)
    rgb = np.asarray(image, dtype=int)
    saturated = rgb.max(axis=2) - rgb.min(axis=2) >= chroma
    hues = np.asarray(image.convert("HSV"))[..., 0][saturated].astype(int) * 12 // 256
    return int(saturated.sum()), int((np.bincount(hues, minlength=12) >= least).sum())


def wait_for_series(browser: Chromium, pixels: int, hues: int, timeout: float) -> tuple[bytes, int, int]:
    """Screenshots every second until one has at least ``pixels`` pixels in series colours spread
    over ``hues`` hues (:func:`series_colours`); the last one and its measures (also on timeout)."""
    deadline = time.monotonic() + timeout
    while True:
        png = browser.screenshot()
        drawn, spread = series_colours(png)
        if (drawn >= pixels and spread >= hues) or time.monotonic() > deadline:
            return png, drawn, spread
        time.sleep(1.0)
