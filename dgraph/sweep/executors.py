"""Where a sweep's runs execute: a pool of fresh processes on this machine (:class:`LocalPool`), or
Ray tasks on a cluster (:class:`RayPool`); each run, either way, in a fresh process of its own
(:mod:`dgraph.sweep.isolation`), so that it gives the same outcome wherever it runs.

A pool takes up to ``capacity`` runs at a time (:meth:`submit`), gives the outcomes of those that
finished as they finish (:meth:`wait`), and stops those still running when it is closed (their
runs give no outcome).
"""

from __future__ import annotations

import logging
import os
from multiprocessing.connection import wait
from pathlib import Path
from typing import Any, Protocol

from dgraph.sweep.isolation import IsolatedRun, run_isolated
from dgraph.sweep.outcome import Outcome, Run, one_line
from dgraph.sweep.spec import SweepError


class Pool(Protocol):
    """What runs a sweep's runs (see the module docstring)."""

    capacity: int

    def submit(self, run: Run) -> None:
        """Start ``run``."""

    def wait(self) -> list[Outcome]:
        """The outcomes of the runs that finished, at least one (some must be running)."""

    def close(self) -> None:
        """Stop the runs still running; release the pool."""


class LocalPool:
    """Up to ``workers`` runs at a time on this machine (default: one per CPU), each in a fresh
    process, killed past ``timeout`` s."""

    def __init__(self, workers: int | None = None, timeout: float | None = None):
        self.capacity = workers or os.cpu_count() or 1
        self.timeout = timeout
        self._running: list[IsolatedRun] = []

    def submit(self, run: Run) -> None:
        """Start ``run`` in a fresh process."""
        self._running.append(IsolatedRun(run, self.timeout))

    def wait(self) -> list[Outcome]:
        """The outcomes of the runs that finished (waits for one at least)."""
        while True:
            finished = [(isolated, isolated.poll()) for isolated in self._running]
            outcomes = [outcome for _, outcome in finished if outcome is not None]
            if outcomes:
                self._running = [isolated for isolated, outcome in finished if outcome is None]
                return outcomes
            deadlines = [r for r in (isolated.remaining() for isolated in self._running) if r is not None]
            wait([handle for isolated in self._running for handle in isolated.handles],
                 min(deadlines) if deadlines else None)

    def close(self) -> None:
        """Kill the runs still running."""
        for isolated in self._running:
            isolated.kill()
        self._running = []

    def __enter__(self) -> LocalPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class RayPool:
    """Runs as Ray tasks (one CPU each), each running :func:`~dgraph.sweep.isolation.run_isolated`
    in a worker. Connects to the cluster at ``address``, or starts (or joins) a local one without
    an address, unless Ray is already initialised in this process (then that cluster is used,
    and left running). ``workers`` runs at a time (default: the cluster's CPUs). The graph files
    must be at the same paths on every node (a shared checkout)."""

    def __init__(self, address: str | None = None, workers: int | None = None, timeout: float | None = None):
        import ray

        if address is not None and Path(address).is_file():
            raise SweepError(f"--ray took the file {address} as the cluster's address: write --ray after the "
                             "files, or --ray=ADDRESS")
        self._ray = ray
        self._started = not ray.is_initialized()
        if self._started:
            _start_ray(address)
        self._task = ray.remote(num_cpus=1, max_retries=0)(run_isolated)
        self.capacity = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
        self.timeout = timeout
        self._pending: dict[Any, Run] = {}

    def submit(self, run: Run) -> None:
        """Start ``run`` as a Ray task."""
        self._pending[self._task.remote(run, self.timeout)] = run

    def wait(self) -> list[Outcome]:
        """The outcomes of the tasks that finished (waits for one at least)."""
        self._ray.wait(list(self._pending), num_returns=1)
        ready, _ = self._ray.wait(list(self._pending), num_returns=len(self._pending), timeout=0)
        return [self._outcome(ref, self._pending.pop(ref)) for ref in ready]

    def _outcome(self, ref: Any, run: Run) -> Outcome:
        """The task's outcome; a task that failed (its worker died) is a crashed run."""
        try:
            return self._ray.get(ref)
        except self._ray.exceptions.RayError as exc:
            return Outcome(run, "crashed", None, None, 0.0, {name: float("nan") for name in run.measures},
                           f"the Ray task failed: {one_line(exc)}")

    def close(self) -> None:
        """Cancel the tasks still running (their processes are killed); shut Ray down if it was
        started here."""
        for ref in self._pending:
            self._ray.cancel(ref)
        self._pending = {}
        if self._started:
            self._ray.shutdown()

    def __enter__(self) -> RayPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _start_ray(address: str | None) -> None:
    """Connect to the Ray cluster at ``address`` (or a local one), its logs kept from the terminal."""
    import ray

    try:
        ray.init(address=address, include_dashboard=False, log_to_driver=False, logging_level=logging.ERROR)
    except Exception as exc:  # Ray's own: ConnectionError, ValueError, RuntimeError...
        option = f"--ray {address}" if address else "--ray"
        raise SweepError(f"{option}: Ray did not start: {one_line(exc)}") from exc


def make_pool(ray: bool | str = False, workers: int | None = None, timeout: float | None = None) -> LocalPool | RayPool:
    """A :class:`LocalPool`, or with ``ray`` a :class:`RayPool` (``True``: a local cluster; a
    string: the address of one); ``workers`` at least 1 (default: the machine's or the cluster's CPUs)."""
    if workers is not None and workers < 1:
        raise SweepError(f"--workers: expected at least 1, got {workers}")
    if ray is False:
        return LocalPool(workers, timeout)
    return RayPool(None if ray is True else ray, workers, timeout)
