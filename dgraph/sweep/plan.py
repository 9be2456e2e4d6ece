"""The runs a sweep will make, checked before any starts: every file loaded once per grid cell
(with a bisection, at the bisected key's ``low`` and ``high``) in this process, as its runs will
load it, so that a bad file, key or value stops the sweep with the graph files' own error instead
of failing every run; each file's duration and fall signal resolved, its measures checked."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from dgraph.errors import DGraphError
from dgraph.sweep.outcome import Run, load_run_graph, measure_parts
from dgraph.sweep.spec import AUTO, DEFAULT_FALL_SIGNAL, Sweep, SweepError, setting_text

if TYPE_CHECKING:
    from dgraph.graph import Graph

NUMERIC = ("float", "int", "bool")


def planned_runs(sweep: Sweep) -> list[Run]:
    """The runs of the sweep's grid (one per cell, see :meth:`Sweep.cells`), or with a bisection
    the cells to bisect (runs without the bisected key), each checked (see the module docstring)."""
    runs = []
    for file, settings in sweep.cells():
        bisection = sweep.bisection
        variants = [settings] if bisection is None else [{**settings, bisection.key: value}
                                                         for value in (bisection.low, bisection.high)]
        facts = [_checked(file, variant, sweep) for variant in variants]
        runs.append(Run(file, settings, *facts[0], measures=tuple(sweep.measures)))
    return runs


def _checked(file: str, settings: Mapping[str, Any], sweep: Sweep) -> tuple[float, str | None]:
    """Load ``file`` with ``settings`` as a run would; its duration and fall signal, its
    measures checked; the graph files' error, prefixed by the cell, if it does not load."""
    try:
        graph = load_run_graph(file, settings)
    except DGraphError as exc:
        raise SweepError(f"{_cell_label(file, settings, sweep)}: {exc}") from None
    try:
        _check_measures(graph, file, sweep.measures)
        return _duration(graph, file, sweep), _fall_signal(graph, file, sweep.fall_signal)
    finally:
        graph.close()


def _cell_label(file: str, settings: Mapping[str, Any], sweep: Sweep) -> str:
    """The file and the swept settings of a cell, for errors."""
    swept = [f"{key}={setting_text(value)}" for key, value in settings.items() if key not in sweep.settings]
    return " ".join([file, *swept])


def _duration(graph: Graph, file: str, sweep: Sweep) -> float:
    duration = sweep.duration if sweep.duration is not None else graph.duration
    if duration is None:
        raise SweepError(f"{file}: no run length: give --duration, or 'duration' in the file")
    return float(duration)


def _fall_signal(graph: Graph, file: str, fall_signal: str | None) -> str | None:
    """The fall signal of the graph: :data:`AUTO` resolved, a given one checked (a bool scalar)."""
    if fall_signal == AUTO:
        entity, _, name = DEFAULT_FALL_SIGNAL.partition(".")
        return DEFAULT_FALL_SIGNAL if entity in graph and name in graph.entity(entity).ports else None
    if fall_signal is not None:
        spec = _signal(graph, file, fall_signal, "--fall-signal").spec
        if spec.dtype != "bool" or spec.shape not in (None, ()):
            raise SweepError(f"--fall-signal {fall_signal}: expected a bool scalar signal, it is "
                             f"{spec.type_name} of shape {spec.shape}")
    return fall_signal


def _check_measures(graph: Graph, file: str, measures: Sequence[str]) -> None:
    """Every measure names a numeric signal of the graph, and a component it has."""
    for text in measures:
        try:
            key, index = measure_parts(text)
        except ValueError as exc:
            raise SweepError(f"--measure {exc}") from None
        spec = _signal(graph, file, key, "--measure").spec
        if spec.dtype not in NUMERIC:
            raise SweepError(f"--measure {text}: expected a numeric signal, it is {spec.type_name}")
        size = int(np.prod(spec.shape)) if spec.exact else None
        if index is not None and size is not None and index >= size:
            raise SweepError(f"--measure {text}: {key} has {size} component(s)")


def _signal(graph: Graph, file: str, key: str, option: str) -> Any:
    try:
        return graph.signal(key)
    except DGraphError as exc:
        raise SweepError(f"{option} {key}: {exc} (in {file})") from None
