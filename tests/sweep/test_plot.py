"""The pictures: a grid over one, two or categorical axes, and a bisection's thresholds (made-up
outcomes), checked on the figures' artists; the files written."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.image import imread

from dgraph.sweep.bisection import Threshold
from dgraph.sweep.outcome import STATUSES, Outcome, Run
from dgraph.sweep.plot import STATUS_COLOURS, grid_figure, plot_grid, plot_thresholds, thresholds_figure


def outcome(file: str, settings: dict, status: str, fall: float | None = None) -> Outcome:
    return Outcome(Run(file, settings, 2.0), status, fall, fall or 2.0, 0.1)


def legend_labels(figure) -> list[str]:
    return [text.get_text() for text in figure.legends[0].get_texts()]


def test_a_grid_over_one_axis_is_the_time_each_run_lasted_per_file(tmp_path):
    outcomes = [outcome(file, {"push.gain": g}, status, fall) for file in ("a.yaml", "b.yaml", "c.yaml")
                for g, status, fall in ((0.5, "ok", None), (1.0, "fell", 1.2), (2.0, "diverged", None))]
    figure = grid_figure(outcomes, ["push.gain"])
    panels = figure.axes
    assert [panel.get_title() for panel in panels] == ["a.yaml", "b.yaml", "c.yaml"]
    for panel in panels:
        [points] = panel.collections
        np.testing.assert_array_equal(points.get_offsets(), [[0.5, 2.0], [1.0, 1.2], [2.0, 2.0]])
        np.testing.assert_array_equal(points.get_facecolors(),
                                      [to_rgba(STATUS_COLOURS[s]) for s in ("ok", "fell", "diverged")])
    assert legend_labels(figure) == ["ok", "fell", "diverged"]
    path = plot_grid(outcomes, ["push.gain"], tmp_path / "sub" / "one.png")
    assert imread(path).shape[1] > 2.5 * imread(path).shape[0]  # three panels side by side


def test_a_grid_over_two_axes_puts_each_run_on_the_row_of_its_other_values(tmp_path):
    outcomes = [outcome("a.yaml", {"push.direction": d, "fault.kind": k}, s, 0.7 if s == "fell" else None)
                for d in ([1, 0, 0], [0, 1, 0]) for k, s in (("jump", "fell"), ("inf", "timeout"))]
    outcomes.append(outcome("a.yaml", {"push.direction": [1, 1, 0], "fault.kind": "none"}, "crashed"))
    [panel] = grid_figure(outcomes, ["push.direction", "fault.kind"]).axes
    [points] = panel.collections
    np.testing.assert_array_equal(points.get_offsets(), [[0, 0], [0, 1], [1, 0], [1, 1], [2, 2]])
    assert [t.get_text() for t in panel.get_xticklabels()] == ["[1, 0, 0]", "[0, 1, 0]", "[1, 1, 0]"]
    assert [t.get_text() for t in panel.get_yticklabels()] == ["jump", "inf", "none"]
    assert [t.get_text() for t in panel.texts] == ["0.7 s", "0.7 s"]  # the falls' times
    assert plot_grid(outcomes[:1], [], tmp_path / "none.png").is_file()
    assert set(STATUS_COLOURS) == set(STATUSES)  # every status has a colour


def test_the_thresholds_of_a_bisection_are_bars_up_to_the_survivor_and_a_line_to_the_failure(tmp_path):
    cells = [Run(f, {"push.direction": d}, 2.0) for f in ("a.yaml", "b.yaml") for d in ("x", "y")]
    thresholds = [Threshold(cells[0], "push.gain", 10.0, 10.4, "found"),
                  Threshold(cells[1], "push.gain", None, 1.0, "fails low"),
                  Threshold(cells[2], "push.gain", 50.0, None, "survives high"),
                  Threshold(cells[3], "push.gain", 20.0, 21.0, "found")]
    figure = thresholds_figure(thresholds, ["push.direction"])
    first, second = figure.axes
    assert [bar.get_height() for bar in first.patches] == [10.0, 0.0]
    assert [bar.get_height() for bar in second.patches] == [50.0, 20.0]
    assert [line.get_ydata().tolist() for line in first.lines] == [[10.0, 10.4]]
    assert [line.get_ydata().tolist() for line in second.lines] == [[20.0, 21.0]]
    assert [t.get_text() for t in first.texts] == ["fails low (1)"]
    assert [t.get_text() for t in second.texts] == ["survives high (50)"]
    assert first.get_ylabel() == "largest surviving push.gain"
    assert plot_thresholds(thresholds, ["push.direction"], tmp_path / "t.png").is_file()
