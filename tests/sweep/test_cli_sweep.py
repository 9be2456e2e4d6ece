"""The dgraph sweep command: a grid to a table and a plot, resumed, a bisection's thresholds, and
mistakes that exit with status 2 before any run."""

from __future__ import annotations

import pytest
from rising_graph import FALL

from dgraph.cli import main
from dgraph.sweep.table import read_table


def test_a_grid_writes_its_table_and_plot_and_resumes(rising, tmp_path, capsys):
    args = ["sweep", rising, "--grid", "push.gain=0.3,2.3", "fault.kind=[jump, inf]", "--set", "height.on_force=0.45",
            "--fall-signal", FALL, "--measure", "body.q[2]", "-q"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "4 runs (" in out and "0 from the table" in out and "out/sweep_rising.csv, out/sweep_rising.png" in out
    rows = read_table(tmp_path / "out" / "sweep_rising.csv")
    assert [(r["push.gain"], r["fault.kind"], r["status"], r["fall_time"]) for r in
            sorted(rows, key=lambda r: (float(r["push.gain"]), r["fault.kind"]))] == [
        ("0.3", "inf", "diverged", ""), ("0.3", "jump", "ok", ""), ("2.3", "inf", "fell", "0.21"),
        ("2.3", "jump", "fell", "0.21")]
    assert {r["height.on_force"] for r in rows} == {"0.45"}
    assert (tmp_path / "out" / "sweep_rising.png").stat().st_size > 10_000
    assert main([*args, "--out", "out/sweep_rising.csv", "--no-plot"]) == 0
    assert "4 from the table) -> out/sweep_rising.csv\n" in capsys.readouterr().out


def test_a_bisection_prints_each_cells_threshold(rising, tmp_path, capsys):
    assert main(["sweep", rising, "--bisect", "push.gain=0.1:4", "--tolerance", "0.1", "--grid",
                 "height.on_force=0.45,100", "--fall-signal", FALL, "--out", "b.csv", "--plot", "b.png", "-q"]) == 0
    out = capsys.readouterr().out
    assert "rising.yaml height.on_force=0.45: push.gain survives 0.4" in out
    assert "rising.yaml height.on_force=100: push.gain survives high 4 (2 runs)" in out
    assert (tmp_path / "b.png").exists() and len(read_table(tmp_path / "b.csv")) > 4


@pytest.mark.parametrize(("args", "message"), [
    (["--grid", "push.gian=1,2"], "did you mean 'gain'"),
    (["--grid", "push.gain"], "--grid 'push.gain': expected KEY=V1,V2"),
    (["--set", "push.gain"], "expected entity.name=value"),
    (["--bisect", "push.gain=2:1"], "--bisect"),
    (["--measure", "body.nothing"], "--measure body.nothing"),
    (["--fall-signal", "body.q"], "expected a bool scalar signal"),
    (["--workers", "0"], "--workers"),
    (["--tolerance", "0.1"], "--tolerance: only with --bisect"),
])
def test_a_mistake_exits_with_status_2_before_any_run(rising, tmp_path, capsys, args, message):
    assert main(["sweep", rising, "-q", *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dgraph sweep: error: ") and message in err
    assert not (tmp_path / "out" / "sweep_rising.csv").exists()
