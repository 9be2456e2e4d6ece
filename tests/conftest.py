"""Small entities used across the tests (not registered: tests build them directly)."""

from __future__ import annotations

import os
import socket
import subprocess

import numpy as np
import pytest
from hypothesis import settings

import dgraph as dg

# Property tests draw the same examples on every run ("repeatable", the default, what CI runs), so a
# result never depends on the run; HYPOTHESIS_PROFILE=explore draws new ones each time (for hunting).
settings.register_profile("repeatable", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))


class Scale(dg.Entity):
    """y = k * u (scalar), with a declared dependency on u only, and z reading y."""

    k = dg.Param(2.0, kind="float")
    u = dg.Input(shape=())
    unused = dg.Input(shape=(), default=0.0)

    @dg.output(shape=(), depends=("u",))
    def y(self, t):
        return self.k * self.u(t)

    @dg.output(shape=(), depends=("y",))
    def z(self, t):
        return self.y(t) + 1.0


class Sum2(dg.Entity):
    """s = a + b, no declared dependencies (conservative default)."""

    a = dg.Input(shape=())
    b = dg.Input(shape=(), default=0.0)

    @dg.output(shape=())
    def s(self, t):
        return self.a(t) + self.b(t)


class Ticker(dg.Device):
    """A device whose state x counts ticks: x(t) = x0 + t."""

    x0 = dg.Param(0.0, kind="float")
    x = dg.State(shape=())

    def reset(self):
        self.x.set(self.x0, 0)

    def prepare_state(self, t):
        self.x.stage(self.x(t) + 1.0)

    def commit_state(self, t_next):
        self.x.commit(t_next)


class Follower(dg.Entity):
    """A stateful entity that pulls its input every tick: s(t + 1) = u(t)."""

    has_state = True
    u = dg.Input(shape=())
    s = dg.State(shape=(), initial=0.0)

    def prepare_state(self, t):
        self.s.stage(self.u(t))

    def commit_state(self, t_next):
        self.s.commit(t_next)


class Clocked(dg.Entity):
    """Time-varying output: value = t (reads nothing)."""

    @dg.output(shape=(), depends=("t",))
    def now(self, t):
        return float(t)


class Periodic(dg.Entity):
    """y = u, recomputed at most every `every` ticks."""

    every = dg.Param(1, kind="int")
    u = dg.Input(shape=())

    def configure(self):
        self.declare("y", dg.Output(_copy_u, shape=(), depends=("u",), period=self.every))


def _copy_u(entity, t):
    return entity.u(t)


@pytest.fixture(autouse=True)
def _work_in_tmp(tmp_path, monkeypatch):
    """Tests run in a temporary directory: default outputs (out/*.rrd) land there."""
    monkeypatch.chdir(tmp_path)


@pytest.fixture
def graph():
    return dg.Graph(dt=0.01, name="test")


@pytest.fixture
def rng():
    return np.random.default_rng(0)


@pytest.fixture
def ports() -> tuple[int, int]:
    """Two TCP ports free on loopback just now (a Rerun server's gRPC and web viewer ports)."""
    probes = [socket.socket() for _ in range(2)]
    for probe in probes:
        probe.bind(("127.0.0.1", 0))
    free = (probes[0].getsockname()[1], probes[1].getsockname()[1])
    for probe in probes:
        probe.close()
    return free


def stop_process(process: subprocess.Popen, timeout: float = 10.0) -> None:
    """End ``process`` if it still runs: SIGTERM, then SIGKILL if it has not ended ``timeout`` s later."""
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
