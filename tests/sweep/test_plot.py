"""The pictures: a grid over one, two or categorical axes, and a bisection's thresholds (made-up outcomes)."""

from __future__ import annotations

from matplotlib.image import imread

from dgraph.sweep.bisection import Threshold
from dgraph.sweep.outcome import Outcome, Run
from dgraph.sweep.plot import STATUS_COLOURS, plot_grid, plot_thresholds


def outcome(file: str, settings: dict, status: str, fall: float | None = None) -> Outcome:
    return Outcome(Run(file, settings, 2.0), status, fall, fall or 2.0, 0.1)


def pixels(path) -> tuple[int, int]:
    image = imread(path)
    return image.shape[1], image.shape[0]


def test_a_grid_over_one_axis_is_the_time_each_run_lasted_per_file(tmp_path):
    outcomes = [outcome(file, {"push.gain": g}, status, fall) for file in ("a.yaml", "b.yaml", "c.yaml")
                for g, status, fall in ((0.5, "ok", None), (1.0, "fell", 1.2), (2.0, "diverged", None))]
    path = plot_grid(outcomes, ["push.gain"], tmp_path / "sub" / "one.png")
    width, height = pixels(path)
    assert width > 2.5 * height  # three panels side by side


def test_a_grid_over_two_axes_and_categories_is_drawn(tmp_path):
    outcomes = [outcome("a.yaml", {"push.direction": d, "fault.kind": k}, s, 0.7 if s == "fell" else None)
                for d in ([1, 0, 0], [0, 1, 0]) for k, s in (("jump", "fell"), ("inf", "timeout"))]
    outcomes.append(outcome("a.yaml", {"push.direction": [1, 1, 0], "fault.kind": "none"}, "crashed"))
    assert pixels(plot_grid(outcomes, ["push.direction", "fault.kind"], tmp_path / "two.png"))[0] > 0
    assert pixels(plot_grid(outcomes[:1], [], tmp_path / "none.png"))[0] > 0
    assert set(STATUS_COLOURS) == {"ok", "fell", "diverged", "error", "timeout", "crashed"}


def test_the_thresholds_of_a_bisection_are_bars(tmp_path):
    cells = [Run(f, {"push.direction": d}, 2.0) for f in ("a.yaml", "b.yaml") for d in ("x", "y")]
    thresholds = [Threshold(cells[0], "push.gain", 10.0, 10.4, "found"),
                  Threshold(cells[1], "push.gain", None, 1.0, "fails low"),
                  Threshold(cells[2], "push.gain", 50.0, None, "survives high"),
                  Threshold(cells[3], "push.gain", 20.0, 21.0, "found")]
    width, height = pixels(plot_thresholds(thresholds, ["push.direction"], tmp_path / "t.png"))
    assert width > 1.5 * height
