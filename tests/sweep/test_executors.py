"""The same 20-run grid by ``dgraph sweep`` on a pool of local processes and on a local Ray cluster:
identical results (every column but the wall times). Ray starts in a few seconds: ``-k 'not ray'`` leaves it out."""

from __future__ import annotations

import collections
import csv
import logging

import pytest
from rising_graph import FALL, GRID

from dgraph.cli import main
from dgraph.sweep.executors import LocalPool, make_pool
from dgraph.sweep.spec import SweepError


def table_without_wall_times(path) -> list[dict[str, str]]:
    with open(path, newline="") as file:
        rows = [{k: v for k, v in row.items() if k != "wall_time"} for row in csv.DictReader(file)]
    return sorted(rows, key=lambda row: [row[key] for key in GRID])


def test_a_grid_on_ray_is_the_grid_on_local_processes(rising, tmp_path, capsys):
    """``dgraph sweep`` itself, once on two local processes and once with ``--ray``."""
    ray = pytest.importorskip("ray")
    grid = [f"{key}={','.join(map(str, values))}" for key, values in GRID.items()]
    args = ["sweep", rising, "--grid", *grid, "--fall-signal", FALL, "--measure", "body.q[2]", "body.v", "-q",
            "--no-plot"]
    assert main([*args, "--workers", "2", "--out", str(tmp_path / "local.csv")]) == 0
    assert "20 runs (" in capsys.readouterr().out
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, logging_level=logging.ERROR)
    try:
        assert main([*args, "--out", str(tmp_path / "ray.csv"), "--ray"]) == 0
        assert ray.is_initialized()  # Ray initialised before the sweep is left as it was
    finally:
        ray.shutdown()
    assert "20 runs (" in capsys.readouterr().out
    statuses = collections.Counter(row["status"] for row in table_without_wall_times(tmp_path / "ray.csv"))
    assert statuses == {"ok": 3, "fell": 9, "diverged": 8}
    assert table_without_wall_times(tmp_path / "ray.csv") == table_without_wall_times(tmp_path / "local.csv")


def test_pools_are_sized_and_checked():
    assert make_pool(workers=3).capacity == 3 and isinstance(make_pool(), LocalPool)
    for ray in (False, True):  # checked before a Ray cluster is started
        with pytest.raises(SweepError, match="--workers: expected at least 1, got 0"):
            make_pool(ray, workers=0)


def test_a_file_taken_for_the_ray_address_is_refused(rising):
    with pytest.raises(SweepError, match="--ray took the file"):
        make_pool(ray=rising)
