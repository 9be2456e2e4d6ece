"""One run of a sweep and its outcome: a graph file loaded with its settings, run tick by tick for
its duration in this process, ended early by its fall signal, and what came of it.

A failure is an outcome, never an exception: ``status`` is one of :data:`STATUSES`,

- ``ok``: the run lasted its duration without falling;
- ``fell``: the fall signal (a bool output or state) was true at the end of a tick (``fall_time``,
  s), or the device it belongs to raised an error naming it (``stop_on_fall``);
- ``diverged``: the run raised a :class:`~dgraph.errors.DivergenceError` (the simulation
  diverged) or a :class:`~dgraph.errors.NonFiniteError` (a value became NaN, a state infinite),
  or an error caused by one;
- ``error``: any other exception (its type and the first line of its message in ``message``);
- ``timeout``, ``crashed``: the run's process took too long, or died (see
  :mod:`dgraph.sweep.isolation`; not produced here).

The measured signals are read at the last tick reached: a scalar as it is, a vector as its
Euclidean norm, ``entity.signal[i]`` as component ``i`` of the flattened value; NaN if it cannot be
read. Whatever the graph file records is neither sent to Rerun nor written (recorders, views and
videos off), so that runs write nothing but their outcome.
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from dgraph.errors import DGraphError, DivergenceError, NonFiniteError
from dgraph.sweep.spec import setting_text

if TYPE_CHECKING:
    from dgraph.graph import Graph

STATUSES = ("ok", "fell", "diverged", "error", "timeout", "crashed")
QUIET = {"Recorder": {"rerun": "off", "npz_path": None}, "RobotView": {"rerun": "off"},
         "WalkingView": {"rerun": "off"}, "MujocoDevice": {"video_path": None}}
"""The parameters that make an entity of each type write nothing (by type name)."""
MESSAGE_CHARS = 500


def number_text(value: float | None) -> str:
    """A number as the results table stores it: ``repr`` (read back exactly), empty for none."""
    return "" if value is None else repr(float(value))


@dataclass(frozen=True)
class Run:
    """One run: ``file`` loaded with ``settings`` (``entity.name`` -> value, as ``--set``), run
    for ``duration`` s, ended as fallen by ``fall_signal`` (``entity.signal``, a bool; ``None``
    for none), with the final values of ``measures`` recorded. ``folder`` is the working
    directory that relative paths (the file's, those of settings) are read from in a process of
    its own (default: this process's when the run is made); it is not part of what the run is."""

    file: str
    settings: Mapping[str, Any]
    duration: float
    fall_signal: str | None = None
    measures: tuple[str, ...] = ()
    folder: str = field(default_factory=os.getcwd, compare=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "duration", float(self.duration))  # 1 and 1.0: one run, one table row

    def identity(self) -> tuple[Any, ...]:
        """What tells this run from another in a results table: the file, the settings' texts,
        the duration and the fall signal (not the measures: they are the table's columns)."""
        settings = tuple(sorted((key, setting_text(value)) for key, value in self.settings.items()))
        return self.file, settings, number_text(self.duration), self.fall_signal or ""

    def label(self) -> str:
        """``file key=value ...``, for messages."""
        return " ".join([self.file, *(f"{key}={setting_text(value)}" for key, value in self.settings.items())])


@dataclass(frozen=True)
class Outcome:
    """What came of a :class:`Run` (see the module docstring): its ``status``, the simulated
    time of its fall (s, or ``None``), the simulated time it reached (s; ``None`` when its
    process was stopped or died), the wall time it took (s), its measures, and a one-line
    message for a failure."""

    run: Run
    status: str
    fall_time: float | None
    simulated_time: float | None
    wall_time: float
    measures: Mapping[str, float] = field(default_factory=dict)
    message: str = ""

    @property
    def survived(self) -> bool:
        """Whether the run lasted its duration without falling or failing."""
        return self.status == "ok"

    def row(self) -> dict[str, Any]:
        """The outcome as one row of results: the run's file and settings, then the outcome."""
        run = self.run
        return {"file": run.file, **run.settings, "duration": run.duration, "fall_signal": run.fall_signal,
                "status": self.status, "fall_time": self.fall_time, "simulated_time": self.simulated_time,
                "wall_time": self.wall_time, **{name: self.measures.get(name) for name in run.measures},
                "message": self.message}


def quiet_overrides(path: str) -> dict[str, Any]:
    """The settings that keep every recorder, view and video of the graph file at ``path`` from
    writing anything (:data:`QUIET`); what a run's own settings say is applied over them."""
    from dgraph.files import declared_entities, parse, read_text

    entities = declared_entities(parse(read_text(path), path))
    return {f"{name}.{key}": value for name, spec in entities.items()
            for key, value in QUIET.get(spec["type"], {}).items()}


def load_run_graph(file: str, settings: Mapping[str, Any]) -> Graph:
    """The graph of ``file`` with ``settings``, quiet (:func:`quiet_overrides`), validated."""
    import dgraph

    graph = dgraph.load(file, {**quiet_overrides(file), **settings})
    try:
        graph.validate()
    except DGraphError:
        graph.close()
        raise
    return graph


def measure_parts(text: str) -> tuple[str, int | None]:
    """``entity.signal`` and the component of ``entity.signal[i]`` (``None`` without one)."""
    key, bracket, rest = text.partition("[")
    if not bracket:
        return key, None
    if not (rest.endswith("]") and rest[:-1].isdigit()):
        raise ValueError(f"measure {text!r}: expected entity.signal or entity.signal[i]")
    return key, int(rest[:-1])


def measure_value(graph: Graph, text: str) -> float:
    """The value of the measure ``text`` at the graph's current tick (see the module docstring)."""
    key, index = measure_parts(text)
    value = np.asarray(graph.signal(key)(graph.t), dtype=float)
    if index is not None:
        return float(value.reshape(-1)[index])
    return float(value) if value.size == 1 else float(np.linalg.norm(value))


def run_graph(run: Run) -> Outcome:
    """Run ``run`` in this process (see the module docstring); never raises for the run's sake."""
    start = time.perf_counter()
    graph = None
    try:
        graph = load_run_graph(run.file, run.settings)
        status, fall_time, message = _ticks(graph, run)
    except Exception as exc:
        status, fall_time, message = _failure(exc, run, graph)
    measures = {text: _measure_or_nan(graph, text) for text in run.measures}
    if graph is not None:
        _close(graph)
    simulated = graph.t * graph.dt if graph is not None else 0.0
    return Outcome(run, status, fall_time, simulated, time.perf_counter() - start, measures, message)


def _ticks(graph: Graph, run: Run) -> tuple[str, float | None, str]:
    """Step until the duration or the first tick at whose end the fall signal is true."""
    ticks = round(run.duration / graph.dt)
    fallen = graph.signal(run.fall_signal) if run.fall_signal else None
    while True:
        if fallen is not None and bool(fallen(graph.t)):
            return "fell", graph.t * graph.dt, ""
        if graph.t >= ticks:
            return "ok", None, ""
        graph.step()


def _failure(exc: Exception, run: Run, graph: Graph | None) -> tuple[str, float | None, str]:
    """The status, fall time and message of a run that raised ``exc`` (a tick that raises
    commits nothing: a fall it reports is at the end of the tick the graph is in)."""
    message = one_line(exc)
    if isinstance(exc, DGraphError) and graph is not None and run.fall_signal == f"{exc.entity}.{exc.signal}":
        return "fell", (graph.t + 1) * graph.dt, message
    if _caused_by(exc, (DivergenceError, NonFiniteError)):
        return "diverged", None, message
    return "error", None, message


def _caused_by(exc: BaseException | None, kinds: tuple[type[BaseException], ...]) -> bool:
    """Whether ``exc`` or an exception it was raised from (``__cause__``, ``__context__``) is one of ``kinds``."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, kinds):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def one_line(exc: BaseException) -> str:
    """``Type: first line of the message``, at most :data:`MESSAGE_CHARS` characters."""
    lines = str(exc).strip().splitlines()
    text = f"{type(exc).__name__}: {lines[0] if lines else ''}".rstrip(": ")
    return text if len(text) <= MESSAGE_CHARS else text[:MESSAGE_CHARS - 3] + "..."


def _measure_or_nan(graph: Graph | None, text: str) -> float:
    if graph is None:
        return float("nan")
    try:
        return measure_value(graph, text)
    except Exception:  # a signal that cannot be read after a failure: no value
        return float("nan")


def _close(graph: Graph) -> None:
    """Close the graph; a failure to close changes nothing of the outcome (nothing is written)."""
    try:
        graph.close()
    except DGraphError:
        pass
