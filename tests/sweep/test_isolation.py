"""Each run in a fresh process: the same outcome as in this process; a run past its timeout is
killed, one whose process dies is a crashed run, neither stops anything else."""

from __future__ import annotations

import dataclasses
import math
import multiprocessing
import os
import signal
import time

import pytest
from rising_graph import FALL

from dgraph.sweep.isolation import IsolatedRun, run_isolated
from dgraph.sweep.outcome import Run, run_graph

ENDLESS = {"push.gain": 0.3, "height.on_force": 1e9}
"""Settings under which the rising body never reaches the height (a run as long as its duration)."""


def same_but_wall_time(a, b) -> bool:
    return dataclasses.replace(a, wall_time=0.0) == dataclasses.replace(b, wall_time=0.0)


@pytest.mark.parametrize(("push", "kind"), [(0.3, "jump"), (2.3, "jump"), (0.7, "inf")])
def test_a_run_in_its_own_process_is_the_run_in_this_one(rising, push, kind):
    run = Run(rising, {"push.gain": push, "fault.kind": kind}, 1.0, FALL, ("body.q[2]", "body.v"))
    isolated = run_isolated(run)
    assert same_but_wall_time(isolated, run_graph(run))
    assert isolated.status == {"jump": "fell" if push > 1 else "ok", "inf": "diverged"}[kind]


def test_a_relative_path_is_read_from_the_folder_the_run_was_made_in(rising, tmp_path, monkeypatch):
    run = Run("rising.yaml", {"push.gain": 2.3}, 1.0, FALL)
    assert run.folder == str(tmp_path) and run == Run("rising.yaml", {"push.gain": 2.3}, 1.0, FALL, folder="/")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    outcome = run_isolated(run)
    assert (outcome.status, outcome.fall_time) == ("fell", pytest.approx(0.21))
    assert run_graph(run).status == "error"  # in this process, here, there is no rising.yaml


def test_a_run_past_its_timeout_is_killed(rising):
    start = time.perf_counter()
    outcome = run_isolated(Run(rising, ENDLESS, 1e5, FALL, ("body.q[2]",)), timeout=0.5)
    assert outcome.status == "timeout" and "0.5 s" in outcome.message
    assert 0.5 <= outcome.wall_time < 5.0 and time.perf_counter() - start < 5.0
    assert (outcome.fall_time, outcome.simulated_time) == (None, None) and math.isnan(outcome.measures["body.q[2]"])
    assert not multiprocessing.active_children()


def test_a_run_whose_process_dies_is_a_crashed_run(rising):
    isolated = IsolatedRun(Run(rising, ENDLESS, 1e5, FALL))
    time.sleep(0.2)
    assert isolated.poll() is None
    os.kill(isolated.pid, signal.SIGKILL)
    deadline = time.perf_counter() + 10.0
    while (outcome := isolated.poll()) is None and time.perf_counter() < deadline:
        time.sleep(0.01)
    assert outcome.status == "crashed" and "killed by SIGKILL" in outcome.message
    assert not multiprocessing.active_children()


def test_a_killed_run_gives_no_outcome_and_leaves_no_process(rising):
    isolated = IsolatedRun(Run(rising, ENDLESS, 1e5, FALL))
    time.sleep(0.2)
    assert isolated.poll() is None  # running
    isolated.kill()
    isolated.kill()
    assert not multiprocessing.active_children()
    assert not os.path.exists(isolated._log)  # its log removed


def test_a_folder_that_is_not_there_is_an_error_naming_it(rising, tmp_path):
    gone = tmp_path / "gone"
    outcome = run_isolated(Run(rising, {"push.gain": 2.3}, 1.0, FALL, ("body.q[2]",), folder=str(gone)))
    assert outcome.status == "error" and f"the run's folder {gone} cannot be entered here" in outcome.message
    assert math.isnan(outcome.measures["body.q[2]"])
