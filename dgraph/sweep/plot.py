"""The picture of a sweep (matplotlib, when it is installed: the ``plots`` extra), one panel per
graph file.

- A grid: each run at its value of the first swept key; with one axis (or none) its height is the
  time it lasted (its fall time, else the simulated time it reached), with more axes it sits on
  the row of its values of the others and a fall is labelled with its time. The colour is the
  status.
- A bisection: per grid cell, a bar up to the largest surviving value of the bisected key, a red
  line from there to the smallest failing one; a cell that survives ``high`` or fails ``low`` says
  so (no line).
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from dgraph.sweep.bisection import Threshold
from dgraph.sweep.outcome import Outcome
from dgraph.sweep.spec import setting_text

STATUS_COLOURS = {"ok": "tab:green", "fell": "tab:red", "diverged": "tab:purple", "error": "tab:orange",
                  "timeout": "tab:gray", "crashed": "black"}
PANEL_INCHES = (5.0, 4.0)


def _panels(files: Sequence[str], ylabel: str) -> tuple[Any, dict[str, Any]]:
    """A figure with one panel per file, sharing the y axis; the panels by file."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(PANEL_INCHES[0] * len(files), PANEL_INCHES[1]), layout="constrained")
    panels = figure.subplots(1, len(files), squeeze=False, sharey=True)[0]
    for panel, file in zip(panels, files, strict=True):
        panel.set_title(Path(file).name, fontsize="medium")
        panel.grid(alpha=0.3)
    panels[0].set_ylabel(ylabel)
    return figure, dict(zip(files, panels, strict=True))


def _positions(values: Sequence[Any]) -> tuple[list[float], list[str] | None]:
    """Positions along an axis: the values if they are all numbers, else their ranks, with labels."""
    if all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in values):
        return [float(v) for v in values], None
    labels = list(dict.fromkeys(setting_text(v) for v in values))
    return [float(labels.index(setting_text(v))) for v in values], labels


def _label_axis(axis: Any, labels: list[str] | None) -> None:
    if labels is not None:
        axis.set_ticks(range(len(labels)), labels)


def _lasted(outcome: Outcome) -> float:
    """How long the run lasted (s): its fall time, else the simulated time it reached."""
    if outcome.fall_time is not None:
        return outcome.fall_time
    return outcome.simulated_time or 0.0


def plot_grid(outcomes: Sequence[Outcome], axes: Sequence[str], path: str | Path) -> Path:
    """Draw the outcomes of a grid over the keys ``axes`` (see the module docstring) to ``path``."""
    return _save(grid_figure(outcomes, axes), path)


def grid_figure(outcomes: Sequence[Outcome], axes: Sequence[str]) -> Any:
    """The matplotlib figure of :func:`plot_grid`."""
    files = list(dict.fromkeys(o.run.file for o in outcomes))
    figure, panels = _panels(files, "time lasted (s)" if len(axes) <= 1 else ", ".join(axes[1:]))
    x, x_labels = _positions([o.run.settings[axes[0]] if axes else 0 for o in outcomes])
    rows = [", ".join(setting_text(o.run.settings[k]) for k in axes[1:]) for o in outcomes]
    y, y_labels = _positions([_lasted(o) for o in outcomes] if len(axes) <= 1 else rows)
    for file, panel in panels.items():
        mine = [i for i, o in enumerate(outcomes) if o.run.file == file]
        panel.scatter([x[i] for i in mine], [y[i] for i in mine], c=[STATUS_COLOURS[outcomes[i].status] for i in mine],
                      s=40, zorder=3)
        if len(axes) > 1:
            for i in (i for i in mine if outcomes[i].fall_time is not None):
                panel.annotate(f"{outcomes[i].fall_time:.3g} s", (x[i], y[i]), xytext=(4, 4),
                               textcoords="offset points", fontsize="x-small")
        panel.set_xlabel(axes[0] if axes else "")
        panel.margins(0.1)
        _label_axis(panel.xaxis, x_labels)
    if len(axes) <= 1:
        next(iter(panels.values())).set_ylim(bottom=0.0)
    _label_axis(next(iter(panels.values())).yaxis, y_labels)
    _status_legend(figure, {o.status for o in outcomes})
    return figure


def plot_thresholds(thresholds: Sequence[Threshold], axes: Sequence[str], path: str | Path) -> Path:
    """Draw the largest surviving value of each bisected cell (see the module docstring) to ``path``."""
    return _save(thresholds_figure(thresholds, axes), path)


def thresholds_figure(thresholds: Sequence[Threshold], axes: Sequence[str]) -> Any:
    """The matplotlib figure of :func:`plot_thresholds`."""
    files = list(dict.fromkeys(t.cell.file for t in thresholds))
    figure, panels = _panels(files, f"largest surviving {thresholds[0].key}" if thresholds else "")
    for file, panel in panels.items():
        mine = [t for t in thresholds if t.cell.file == file]
        labels = [", ".join(setting_text(t.cell.settings[k]) for k in axes) or "all" for t in mine]
        heights = [t.largest_surviving or 0.0 for t in mine]
        panel.bar(range(len(mine)), heights, color="tab:blue", alpha=0.7, zorder=2)
        for i, t in enumerate(mine):
            if t.verdict == "found":
                panel.plot([i, i], [heights[i], t.smallest_failing], color="tab:red", lw=3, zorder=3)
            else:
                bound = t.smallest_failing if t.verdict == "fails low" else t.largest_surviving
                panel.annotate(f"{t.verdict} ({bound:.3g})", (i, heights[i]), xytext=(0, 4),
                               textcoords="offset points", ha="center", fontsize="x-small")
        panel.set_xticks(range(len(mine)), labels, rotation=30, ha="right", fontsize="small")
        panel.set_xlabel(", ".join(axes))
    return figure


def _status_legend(figure: Any, statuses: set[str]) -> None:
    from matplotlib.lines import Line2D

    shown = [s for s in STATUS_COLOURS if s in statuses]
    handles = [Line2D([], [], marker="o", ls="", color=STATUS_COLOURS[s], label=s) for s in shown]
    figure.legend(handles=handles, loc="outside right upper", fontsize="small")


def _save(figure: Any, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=100)
    return path
