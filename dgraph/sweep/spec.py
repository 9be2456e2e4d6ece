"""What a sweep asks for: graph files, settings fixed for every run, grid axes (one value list per
setting key) and optionally a bisection over one more key; the grid cells they expand to.

A setting is what ``dgraph run --set entity.name=value`` takes (a parameter or an input constant);
its values are plain data (numbers, booleans, strings, lists of them), read from the command line by
the graph files' own safe YAML reader (:func:`~dgraph.files.command_line_value`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import yaml

from dgraph.errors import DGraphError, GraphFileError
from dgraph.files import command_line_value, to_plain

AUTO = "auto"
"""The fall signal chosen from the graph: ``device.fallen`` when it has one, none otherwise."""
DEFAULT_FALL_SIGNAL = "device.fallen"


class SweepError(DGraphError):
    """A sweep that cannot start: a file, key, value or option that is wrong."""


def setting_text(value: Any) -> str:
    """The canonical text of a setting's value, as the command line would give it and as the
    results table stores it: YAML flow style (``0.1``, ``[0, 0.05, 0]``, ``true``, ``'1'`` for a
    string that would read as a number), read back to the same value by
    :func:`~dgraph.files.command_line_value`."""
    text = yaml.safe_dump(to_plain(value, "a setting"), default_flow_style=True, width=math.inf, allow_unicode=True)
    return text.removesuffix("\n").removesuffix("\n...").strip()


def _setting_key(key: str, option: str) -> str:
    """``key`` if it reads ``entity.name``, else a :class:`SweepError` naming the option."""
    entity, dot, name = key.partition(".")
    if not (dot and entity and name) or "." in name:
        raise SweepError(f"{option} {key!r}: expected a setting key entity.name")
    return key


@dataclass(frozen=True)
class Bisection:
    """The largest value of ``key`` that still survives, searched between ``low`` (must survive)
    and ``high`` (must fail), ``0 <= low < high``, until ``high - low <= tolerance * high``
    (see :mod:`dgraph.sweep.bisection`). The values are floats."""

    key: str
    low: float
    high: float
    tolerance: float = 0.05

    def __post_init__(self) -> None:
        _setting_key(self.key, "--bisect")
        if not (math.isfinite(self.high) and 0.0 <= self.low < self.high):
            raise SweepError(f"--bisect {self.key}: expected finite 0 <= LOW < HIGH, got {self.low}:{self.high}")
        if not 0.0 < self.tolerance < 1.0:
            raise SweepError(f"--tolerance: expected a relative tolerance in (0, 1), got {self.tolerance}")


@dataclass(frozen=True)
class Sweep:
    """The runs a sweep makes: every file (one more grid axis) times every combination of the
    ``grid`` axes' values, each with ``settings`` under it; with a ``bisection``, each such cell
    is bisected. ``duration`` (s) is each run's length (``None``: each file's ``duration``);
    ``fall_signal`` the bool signal that ends a run as fallen (:data:`AUTO`, or ``None`` for
    none); ``measures`` the signals whose final values are recorded (``entity.signal`` gives a
    scalar, or a vector's Euclidean norm; ``entity.signal[i]`` one component); ``timeout`` (s of
    wall time) ends a run that takes longer."""

    files: Sequence[str]
    settings: Mapping[str, Any] = field(default_factory=dict)
    grid: Mapping[str, Sequence[Any]] = field(default_factory=dict)
    bisection: Bisection | None = None
    duration: float | None = None
    fall_signal: str | None = AUTO
    measures: Sequence[str] = ()
    timeout: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "files", tuple(str(f) for f in self.files))
        object.__setattr__(self, "settings", {_setting_key(k, "--set"): to_plain(v, f"--set {k}")
                                              for k, v in self.settings.items()})
        object.__setattr__(self, "grid", {_setting_key(k, "--grid"): [to_plain(v, f"--grid {k}") for v in values]
                                          for k, values in self.grid.items()})
        object.__setattr__(self, "measures", tuple(self.measures))
        self._check()

    def _check(self) -> None:
        if not self.files:
            raise SweepError("no graph file to sweep")
        for key, values in self.grid.items():
            texts = [setting_text(value) for value in values]
            if not texts:
                raise SweepError(f"--grid {key}: no value")
            repeated = sorted({text for text in texts if texts.count(text) > 1})
            if repeated:
                raise SweepError(f"--grid {key}: {', '.join(repeated)} given more than once (one run per value)")
        keys = [*self.settings, *self.grid, *([self.bisection.key] if self.bisection else [])]
        twice = sorted({k for k in keys if keys.count(k) > 1})
        if twice:
            raise SweepError(f"{', '.join(twice)}: set more than once (by --set, --grid or --bisect)")
        for number, option in ((self.duration, "--duration"), (self.timeout, "--timeout")):
            if number is not None and not (math.isfinite(number) and number > 0):
                raise SweepError(f"{option}: expected a positive number of seconds, got {number}")
        clashes = sorted(set(self.measures) & set(keys))
        if clashes:
            raise SweepError(f"--measure {clashes[0]}: a setting of the sweep, constant in every run")

    @property
    def setting_keys(self) -> list[str]:
        """Every key a run of the sweep sets, in order: the fixed ones, the axes, the bisected one."""
        return [*self.settings, *self.grid, *([self.bisection.key] if self.bisection else [])]

    def cells(self) -> list[tuple[str, dict[str, Any]]]:
        """The grid: ``(file, settings)`` for every file and combination of the axes' values,
        the first axis varying slowest (the files slowest of all)."""
        combos = itertools.product(*self.grid.values())
        return [(file, {**self.settings, **dict(zip(self.grid, combo, strict=True))})
                for file, combo in itertools.product(self.files, list(combos))]


def grid_axis(item: str) -> tuple[str, list[Any]]:
    """The axis of ``--grid KEY=V1,V2,...`` or ``--grid KEY=[V1, V2, ...]``: each value read as
    ``--set`` reads one (a vector value is written in brackets: ``KEY=[1,0,0],[0,1,0]``)."""
    key, eq, text = item.partition("=")
    key = key.strip()
    if not eq or not text.strip():
        raise SweepError(f"--grid {item!r}: expected KEY=V1,V2,... or KEY=[V1, V2, ...]")
    _setting_key(key, "--grid")
    try:
        values = command_line_value(key, text)
    except GraphFileError:  # V1,V2 with a bracketed value is not one YAML value
        values = None
    if not isinstance(values, list):
        values = _value_list(key, text, item)
    return key, values


def grid_axes(items: Sequence[str]) -> dict[str, list[Any]]:
    """The axes of ``--grid`` options (:func:`grid_axis`), in order; a key given twice is refused."""
    axes: dict[str, list[Any]] = {}
    for item in items:
        key, values = grid_axis(item)
        if key in axes:
            raise SweepError(f"--grid {key}: given twice")
        axes[key] = values
    return axes


def _value_list(key: str, text: str, item: str) -> list[Any]:
    """``V1,V2,...`` read as the YAML flow list ``[V1,V2,...]``."""
    try:
        return command_line_value(key, f"[{text}]")
    except GraphFileError as exc:
        raise SweepError(f"--grid {item!r}: expected KEY=V1,V2,... or KEY=[V1, V2, ...] ({exc})") from None


def bisection_option(item: str, tolerance: float) -> Bisection:
    """The :class:`Bisection` of ``--bisect KEY=LOW:HIGH``."""
    key, eq, text = item.partition("=")
    low, colon, high = text.partition(":")
    try:
        bounds = [float(command_line_value(key.strip(), low)), float(command_line_value(key.strip(), high))]
    except (GraphFileError, TypeError, ValueError):
        bounds = []
    if not (eq and colon and bounds):
        raise SweepError(f"--bisect {item!r}: expected KEY=LOW:HIGH with numbers 0 <= LOW < HIGH")
    return Bisection(key.strip(), bounds[0], bounds[1], tolerance)

