"""Each run in a fresh process of its own, so that a crash, a hang or memory growth in one run cannot
touch another, and a run is the same on this machine and on a Ray worker.

Processes come from a multiprocessing *forkserver* that has imported dgraph and every entity plugin
once (:mod:`dgraph.sweep.preload`): each run is a new process forked from it, started in a
fraction of a second instead of the second or two that importing the robotics libraries takes, and
discarded after its run. The run ignores Ctrl-C (the sweep stops it), works in the run's folder
(:attr:`~dgraph.sweep.outcome.Run.folder`: relative paths mean what they meant where the run was
made), writes what it prints to a log file of its own, and sends its
:class:`~dgraph.sweep.outcome.Outcome` back through a pipe.
A process that runs past ``timeout`` seconds is killed (status ``timeout``); one that dies before
sending its outcome (a segfault, the out-of-memory killer, a ``kill``) is a ``crashed`` run whose
message says how it died and the last line it printed.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import tempfile
import time
from multiprocessing.connection import Connection, wait
from typing import Any

from dgraph.sweep.outcome import Outcome, Run, one_line, run_graph

PRELOAD = ["dgraph.sweep.preload"]
POLL_SECONDS = 1.0
"""Longest wait between two looks at a run that has no deadline (a Ray task checks for cancellation)."""
LOG_TAIL_BYTES = 4096


def _context() -> Any:
    """The forkserver context, its server importing :data:`PRELOAD` when it starts."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(PRELOAD)
    return context


class IsolatedRun:
    """A run started in a fresh process; :meth:`poll` gives its outcome once there is one."""

    def __init__(self, run: Run, timeout: float | None = None):
        self.run = run
        self.timeout = timeout
        self.start = time.perf_counter()
        handle, self._log = tempfile.mkstemp(prefix="dgraph-sweep-", suffix=".log")
        os.close(handle)
        context = _context()
        self._receiver, sender = context.Pipe(duplex=False)
        self._process = context.Process(target=_child, args=(sender, self._log, run), daemon=True,
                                        name=f"dgraph-sweep {run.label()}"[:200])
        self._process.start()
        sender.close()
        self._finished = False

    @property
    def pid(self) -> int | None:
        """The process's id."""
        return self._process.pid

    @property
    def handles(self) -> list[Any]:
        """What :func:`multiprocessing.connection.wait` waits on: the outcome's pipe, the process's end."""
        return [self._receiver, self._process.sentinel]

    def remaining(self) -> float | None:
        """Seconds left before the timeout (``None``: no timeout)."""
        return None if self.timeout is None else max(0.0, self.start + self.timeout - time.perf_counter())

    def poll(self) -> Outcome | None:
        """The outcome if the run has one now: sent by the process, or ``crashed`` if it died
        without sending one, or ``timeout`` (the process killed) past its deadline."""
        if self._receiver.poll():
            try:
                outcome = self._receiver.recv()
            except (EOFError, OSError):  # the process died with nothing sent
                return self._crashed()
            self._finish()
            return outcome
        if not self._process.is_alive():
            return self._crashed()
        if self.remaining() == 0.0:
            last = _last_line(self._log)  # where it was: the log goes with the process
            self.kill()
            return self._ended("timeout", f"no outcome after {self.timeout:g} s: the process was killed"
                               + (f"; its last output: {last}" if last else ""))
        return None

    def kill(self) -> None:
        """Stop the process now if it still runs (its run gives no outcome) and remove its log."""
        if self._finished:
            return
        if self._process.is_alive():
            self._process.kill()
        self._finish()

    def _finish(self) -> None:
        self._finished = True
        self._process.join()
        self._receiver.close()
        with contextlib.suppress(OSError):
            os.remove(self._log)

    def _crashed(self) -> Outcome:
        self._process.join()
        code = self._process.exitcode
        how = f"killed by {signal.Signals(-code).name}" if code is not None and code < 0 else f"exit status {code}"
        last = _last_line(self._log)
        return self._ended("crashed", f"the run's process died ({how})" + (f": {last}" if last else ""))

    def _ended(self, status: str, message: str) -> Outcome:
        self._finish()
        return Outcome(self.run, status, None, None, time.perf_counter() - self.start,
                       {name: float("nan") for name in self.run.measures}, message)


def run_isolated(run: Run, timeout: float | None = None) -> Outcome:
    """The outcome of ``run`` in a fresh process (what a Ray task runs); the process is killed
    if this is interrupted (a cancelled task)."""
    isolated = IsolatedRun(run, timeout)
    try:
        while True:
            outcome = isolated.poll()
            if outcome is not None:
                return outcome
            remaining = isolated.remaining()
            wait(isolated.handles, POLL_SECONDS if remaining is None else min(remaining, POLL_SECONDS))
    finally:
        isolated.kill()


def _child(sender: Connection, log: str, run: Run) -> None:
    """The run's process: no Ctrl-C, in the run's folder, output to ``log``, the outcome sent back."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with open(log, "wb") as out:
        os.dup2(out.fileno(), 1)
        os.dup2(out.fileno(), 2)
    try:
        os.chdir(run.folder)
    except OSError as exc:  # a node of a cluster without the checkout at the same path
        sender.send(Outcome(run, "error", None, None, 0.0, {name: float("nan") for name in run.measures},
                            f"the run's folder {run.folder} cannot be entered here: {one_line(exc)}"))
    else:
        sender.send(run_graph(run))
    sender.close()


def _last_line(path: str) -> str:
    """The last non-empty line of the file at ``path`` (its last few kilobytes), or ``""``."""
    try:
        with open(path, "rb") as log:
            log.seek(max(0, os.path.getsize(path) - LOG_TAIL_BYTES))
            lines = log.read().decode(errors="replace").strip().splitlines()
    except OSError:
        return ""
    return lines[-1].strip() if lines else ""
