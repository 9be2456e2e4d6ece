"""Headless Chromium driven through the DevTools protocol over a pipe (``--remote-debugging-pipe``:
JSON messages separated by NUL bytes on file descriptors 3 and 4), with the standard library only.

Chromium is Debian's (``apt-get install chromium``); no browser is downloaded. WebGL is drawn by
SwiftShader, Chromium's software renderer, so the Rerun web viewer (wasm + WebGL) renders
without a display or a GPU.
"""

from __future__ import annotations

import base64
import fcntl
import io
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
"""What works on a headless Debian machine as root, WebGL through SwiftShader."""


def chromium_path() -> str | None:
    """Debian's Chromium, if installed."""
    return shutil.which("chromium") or (str(Path("/usr/bin/chromium")) if Path("/usr/bin/chromium").exists() else None)


class Chromium:
    """One headless Chromium with one page; :meth:`close` ends it (also as a context manager)."""

    def __init__(self, executable: str, width: int = 1280, height: int = 800, timeout: float = 30.0):
        self.profile = tempfile.mkdtemp(prefix="dgraph-chromium-")
        self.timeout = timeout
        to_chrome, from_chrome = os.pipe(), os.pipe()
        # Chromium reads commands on fd 3 and writes replies on fd 4: in the child, copies made
        # above 10 (so that neither end is overwritten by the other) go to 3 and 4 (inheritable),
        # after the fds are closed (close_fds=False: Python's own fds are not inheritable anyway)
        high_read = fcntl.fcntl(to_chrome[0], fcntl.F_DUPFD_CLOEXEC, 10)
        high_write = fcntl.fcntl(from_chrome[1], fcntl.F_DUPFD_CLOEXEC, 10)

        def descriptors() -> None:
            os.dup2(high_read, 3)
            os.dup2(high_write, 4)

        self.log = tempfile.TemporaryFile()
        self.process = subprocess.Popen(  # preexec_fn: the only way to place fds 3 and 4
            [executable, *FLAGS, f"--user-data-dir={self.profile}", f"--window-size={width},{height}",
             "--remote-debugging-pipe", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=self.log, stderr=self.log, preexec_fn=descriptors, close_fds=False)
        for fd in (to_chrome[0], from_chrome[1], high_read, high_write):
            os.close(fd)
        self._write = os.fdopen(to_chrome[1], "wb", buffering=0)
        self._read = os.fdopen(from_chrome[0], "rb", buffering=0)
        self._buffer = b""
        self._id = 0
        self.session: str | None = None

    def call(self, method: str, params: dict[str, Any] | None = None, page: bool = True) -> dict[str, Any]:
        """Send one DevTools command (to the page's session unless ``page=False``) and return its result."""
        self._id += 1
        message: dict[str, Any] = {"id": self._id, "method": method, "params": params or {}}
        if page and self.session:
            message["sessionId"] = self.session
        self._write.write(json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self._buffer:
                chunk = self._read.read(1 << 16)
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


def drawn_share(png: bytes) -> tuple[float, int]:
    """How much of an image is drawn: the share of pixels that differ from its most common colour
    (0 for a uniform image) and its number of distinct colours."""
    from PIL import Image

    image = Image.open(io.BytesIO(png)).convert("RGB")
    counts = image.getcolors(maxcolors=image.width * image.height)
    background = max(count for count, _ in counts)
    return 1.0 - background / (image.width * image.height), len(counts)


def wait_until_drawn(browser: Chromium, share: float, colours: int, timeout: float) -> tuple[bytes, float, int]:
    """Screenshots every second until one has at least ``share`` of its pixels off the background
    colour and ``colours`` distinct colours; the last one and its measures (also on timeout)."""
    deadline = time.monotonic() + timeout
    while True:
        png = browser.screenshot()
        drawn, distinct = drawn_share(png)
        if (drawn >= share and distinct >= colours) or time.monotonic() > deadline:
            return png, drawn, distinct
        time.sleep(1.0)
