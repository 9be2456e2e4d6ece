"""The results table: a row per outcome flushed as it comes, read back by identity, resumed."""

from __future__ import annotations

import math

import pytest

from dgraph.sweep.outcome import Outcome, Run
from dgraph.sweep.spec import SweepError
from dgraph.sweep.table import ResultsTable, header, read_table

KEYS = ["push.gain", "push.direction"]
MEASURES = ["body.q[2]"]


def outcome(gain: float, status: str = "ok", fall: float | None = None, measure: float = 0.25) -> Outcome:
    run = Run("g.yaml", {"push.gain": gain, "push.direction": [0, 0, 1]}, 1.0, "height.in_contact", tuple(MEASURES))
    return Outcome(run, status, fall, fall if fall is not None else 1.0, 0.125, {"body.q[2]": measure},
                   "" if status == "ok" else "SpecError: a, with a comma")


def test_rows_are_flushed_as_they_are_appended_and_read_back(tmp_path):
    path = tmp_path / "results" / "r.csv"
    table = ResultsTable(path, KEYS, MEASURES)
    table.append([outcome(0.5), outcome(1.5, "fell", 0.33)])
    rows = read_table(path)  # before close: flushed
    assert list(rows[0]) == header(KEYS, MEASURES)
    assert rows[1]["push.gain"] == "1.5" and rows[1]["push.direction"] == "[0, 0, 1]"
    assert rows[1]["status"] == "fell" and rows[1]["fall_time"] == "0.33" and rows[0]["fall_time"] == ""
    assert rows[1]["message"] == "SpecError: a, with a comma"
    table.append([outcome(2.5, "diverged", measure=math.nan)])
    table.close()
    again = ResultsTable(path, KEYS, MEASURES)
    assert len(again) == 3
    assert again.reused(outcome(1.5).run) == outcome(1.5, "fell", 0.33)
    assert again.reused(outcome(0.5).run) == outcome(0.5)
    assert math.isnan(again.reused(outcome(2.5).run).measures["body.q[2]"])
    assert again.reused(outcome(9.0).run) is None
    again.close()


def test_a_run_is_identified_by_its_file_settings_duration_and_fall_signal(tmp_path):
    with ResultsTable(tmp_path / "r.csv", KEYS, MEASURES) as table:
        table.append([outcome(0.5)])
        run = outcome(0.5).run
        assert table.reused(run) is not None
        for other in (Run("h.yaml", run.settings, 1.0, run.fall_signal, run.measures),
                      Run(run.file, {**run.settings, "push.direction": [0, 1, 0]}, 1.0, run.fall_signal),
                      Run(run.file, run.settings, 2.0, run.fall_signal), Run(run.file, run.settings, 1.0, None)):
            assert table.reused(other) is None


def test_a_line_cut_short_is_dropped_and_fresh_starts_over(tmp_path):
    path = tmp_path / "r.csv"
    with ResultsTable(path, KEYS, MEASURES) as table:
        table.append([outcome(0.5), outcome(1.5)])
    path.write_text(path.read_text()[:-10])  # an interruption in the middle of the last row
    with ResultsTable(path, KEYS, MEASURES) as table:
        assert len(table) == 1
        table.append([outcome(1.5)])
    assert [row["push.gain"] for row in read_table(path)] == ["0.5", "1.5"]
    with ResultsTable(path, KEYS, MEASURES, fresh=True) as table:
        assert len(table) == 0
    assert read_table(path) == []


def test_a_table_of_another_sweep_is_refused(tmp_path):
    path = tmp_path / "r.csv"
    ResultsTable(path, KEYS, MEASURES).close()
    with pytest.raises(SweepError, match="--fresh"):
        ResultsTable(path, ["push.gain"], MEASURES)
    ResultsTable(path, ["push.gain"], MEASURES, fresh=True).close()
    assert list(read_table(path)) == [] and path.read_text().startswith("file,push.gain,duration")


@pytest.mark.parametrize("text", ["", "file,push.gai"], ids=["empty", "header cut short"])
def test_a_table_without_a_whole_header_gets_one_and_resumes(tmp_path, text):
    path = tmp_path / "r.csv"
    path.write_text(text)  # interrupted before or while its header was written
    with ResultsTable(path, KEYS, MEASURES) as table:
        assert len(table) == 0
        table.append([outcome(0.5)])
    with ResultsTable(path, KEYS, MEASURES) as table:
        assert table.reused(outcome(0.5).run) == outcome(0.5)
    assert list(read_table(path)[0]) == header(KEYS, MEASURES)


def test_a_crashed_run_is_run_again_and_its_next_outcome_is_kept(tmp_path):
    path = tmp_path / "r.csv"
    with ResultsTable(path, KEYS, MEASURES) as table:
        table.append([outcome(0.5, "crashed"), outcome(1.5, "timeout")])
        assert table.reused(outcome(0.5).run) is None  # a process that died says nothing of the run
        assert table.reused(outcome(1.5).run).status == "timeout"
    with ResultsTable(path, KEYS, MEASURES) as table:
        assert table.reused(outcome(0.5).run) is None
        table.append([outcome(0.5, "fell", 0.33)])
    with ResultsTable(path, KEYS, MEASURES) as table:
        assert table.reused(outcome(0.5).run) == outcome(0.5, "fell", 0.33)


def test_a_duration_given_as_an_int_is_the_same_run(tmp_path):
    with ResultsTable(tmp_path / "r.csv", KEYS, MEASURES) as table:
        run = outcome(0.5).run
        integral = Run(run.file, run.settings, 1, run.fall_signal, run.measures)
        table.append([Outcome(integral, "ok", None, 1.0, 0.125, {"body.q[2]": 0.25})])
    with ResultsTable(tmp_path / "r.csv", KEYS, MEASURES) as table:
        assert table.reused(run) is not None and integral == run
