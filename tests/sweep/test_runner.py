"""Sweeps run to their end: a 20-run grid whose falls and divergences are rows like the others, an
interrupted sweep resumed without making its finished runs again, a bisection to a known threshold."""

from __future__ import annotations

import multiprocessing

import pytest
from rising_graph import DT, FALL, GRID, expected

from dgraph.sweep.runner import run_sweep
from dgraph.sweep.spec import Bisection, Sweep
from dgraph.sweep.table import read_table


class Stop(Exception):
    """What interrupts a sweep in these tests."""


def check_outcomes(outcomes) -> None:
    """Every outcome is the rising graph's closed form."""
    for outcome in outcomes:
        settings = outcome.run.settings
        status, fall_time, simulated = expected(settings["push.gain"], settings["height.on_force"],
                                                settings["fault.kind"])
        assert outcome.status == status, outcome
        assert outcome.fall_time == (pytest.approx(fall_time) if fall_time else None)
        assert outcome.simulated_time == pytest.approx(simulated)


def test_a_grid_of_20_runs_gives_every_outcome_as_a_row(rising, tmp_path):
    sweep = Sweep([rising], grid=GRID, fall_signal=FALL, measures=["body.q[2]"])
    result = run_sweep(sweep, tmp_path / "r.csv", workers=2, plot=tmp_path / "r.png", progress=False)
    assert result.counts() == {"ok": 3, "fell": 9, "diverged": 8} and result.reused == 0
    assert [o.run.settings for o in result.outcomes] == [s for _, s in sweep.cells()]
    check_outcomes(result.outcomes)
    rows = read_table(tmp_path / "r.csv")
    assert len(rows) == 20 and sorted(r["status"] for r in rows) == sorted(o.status for o in result.outcomes)
    assert all(float(r["body.q[2]"]) == pytest.approx(float(r["simulated_time"] or 0) * float(r["push.gain"]))
               for r in rows if r["status"] != "diverged")
    assert result.plot == tmp_path / "r.png" and result.plot.stat().st_size > 10_000
    assert result.summary().startswith("20 runs (") and "0 from the table" in result.summary()


def test_an_interrupted_sweep_resumes_without_making_its_finished_runs_again(rising, tmp_path):
    sweep = Sweep([rising], grid={"push.gain": [0.3, 0.7, 1.1, 1.7, 2.3], "height.on_force": [0.45, 0.95]},
                  settings={"fault.kind": "jump"}, fall_signal=FALL)
    made: list = []

    def stop_after_three(outcome):
        made.append(outcome)
        if len(made) == 3:
            raise Stop

    with pytest.raises(Stop):
        run_sweep(sweep, tmp_path / "r.csv", workers=2, on_outcome=stop_after_three, progress=False)
    assert not multiprocessing.active_children()  # the runs in flight were stopped
    kept = read_table(tmp_path / "r.csv")
    assert 3 <= len(kept) < 10
    made.clear()
    result = run_sweep(sweep, tmp_path / "r.csv", workers=2, on_outcome=made.append, progress=False)
    assert len(made) == 10 - len(kept) and result.reused == len(kept)
    rows = read_table(tmp_path / "r.csv")
    assert len(rows) == 10 and len({(r["push.gain"], r["height.on_force"]) for r in rows}) == 10
    check_outcomes(result.outcomes)
    assert [o.run.settings for o in result.outcomes] == [s for _, s in sweep.cells()]
    again = run_sweep(sweep, tmp_path / "r.csv", on_outcome=made.append, progress=False)
    assert again.reused == 10 and len(made) == 10 - len(kept) and again.outcomes == result.outcomes
    fresh = run_sweep(sweep, tmp_path / "r.csv", fresh=True, progress=False)
    assert fresh.reused == 0 and len(read_table(tmp_path / "r.csv")) == 10


def test_a_bisection_finds_each_cells_threshold_to_the_tolerance(rising, tmp_path):
    sweep = Sweep([rising], grid={"height.on_force": [0.45, 0.95]}, settings={"fault.kind": "jump"},
                  bisection=Bisection("push.gain", 0.1, 4.0, tolerance=0.02), fall_signal=FALL)
    result = run_sweep(sweep, tmp_path / "b.csv", plot=tmp_path / "b.png", progress=False)
    for threshold, height in zip(result.thresholds, (0.45, 0.95), strict=True):
        falls_from = height / (DT * 99)  # the push that reaches the height at the last tick but one
        assert threshold.verdict == "found" and threshold.cell.settings["height.on_force"] == height
        assert threshold.largest_surviving < falls_from <= threshold.smallest_failing
        assert threshold.smallest_failing - threshold.largest_surviving <= 0.02 * threshold.smallest_failing
    runs = sum(len(t.outcomes) for t in result.thresholds)
    assert len(read_table(tmp_path / "b.csv")) == len(result.outcomes) == runs
    assert "height.on_force=0.95: push.gain survives 0.9" in result.summary()
    resumed = run_sweep(sweep, tmp_path / "b.csv", progress=False)
    assert resumed.reused == len(result.outcomes) and resumed.thresholds == result.thresholds
    assert result.plot.stat().st_size > 10_000
