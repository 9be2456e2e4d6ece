"""Debug mode that catches reads of undeclared dependencies.

An output's ``depends`` drives invalidation; if its method reads a port it did not declare,
the output misses that port's changes and silently serves stale values. With
``graph.check_dependencies = True`` every output's method runs with the undeclared ports of
its entity replaced by stand-ins that raise :class:`DependencyError` when read.

The time is a dependency too: a method that uses its argument ``t`` without declaring
``depends=(..., "t")`` is computed once and then served from its cache while nothing else it
depends on changes. In this mode each clock also carries a :class:`_TimeCheck`: at every new
tick, each output without ``"t"`` that its cache would serve (fresh, computed at an earlier
tick, everything it reads fresh) is computed again at the new tick, the cache left as it was,
and compared with its cached value (:func:`differs`); a difference raises
:class:`DependencyError`. Both swaps happen only in this mode: normal runs pay nothing.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from dgraph.errors import DependencyError, DGraphError
from dgraph.signals.clock import Clock
from dgraph.signals.signal import Input, Output, Signal, State


class _Undeclared:
    """Stands in for a port that the computing output did not declare."""

    __slots__ = ("port", "reader")

    def __init__(self, port: Signal, reader: Output):
        self.port = port
        self.reader = reader

    def __call__(self, t: int) -> Any:
        raise DependencyError(
            f"{self.reader.full_name} read {self.port.full_name} at tick {t} but does not declare it: "
            f"add {self.port.name!r} to its depends={self.reader.depends!r}",
            entity=self.reader.entity.name, signal=self.reader.name)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.port, name)


def guard(output: Output) -> None:
    """Make ``output``'s method run with the undeclared ports of its entity guarded."""
    if output._unguarded is not None or output._fn is None:
        return
    entity = output.entity
    ports = entity.ports
    allowed = {dep.name for dep in output.deps} | {output.name}
    view = {name: port if name in allowed else _Undeclared(port, output) for name, port in ports.items()}
    original = output._fn

    def checked(t: int) -> Any:  # attribute access and entity.signal()/inputs/ports all see the view
        saved = {name: entity.__dict__[name] for name in ports}
        saved_signals = entity._signals
        entity.__dict__.update(view)
        entity._signals = view
        try:
            return original(t)
        finally:
            entity.__dict__.update(saved)
            entity._signals = saved_signals

    output._unguarded = original
    output._fn = checked


def unguard(output: Output) -> None:
    """Undo :func:`guard`."""
    if output._unguarded is not None:
        output._fn, output._unguarded = output._unguarded, None


def set_checking(outputs: list[Output], enabled: bool) -> None:
    """Guard or unguard every output in ``outputs``, and watch (or stop watching) those that do
    not declare ``"t"`` with their clock's :class:`_TimeCheck`."""
    action: Callable[[Output], None] = guard if enabled else unguard
    for output in outputs:
        action(output)
    clocks: dict[int, tuple[Clock, list[Output]]] = {}
    for output in outputs:
        if not output.time_varying and output._clock is not None:
            clocks.setdefault(id(output._clock), (output._clock, []))[1].append(output)
    for clock, watched in clocks.values():
        _TimeCheck.of(clock).watch(watched, enabled)


class _TimeCheck:
    """The outputs of one clock that do not declare ``"t"``, checked at each new tick.

    It sits last in its clock's list of time-varying outputs (it is not one), so the clock calls
    :meth:`invalidate` each time it moves, after invalidating the real ones; at a new latest tick
    every watched output that its cache would serve there is computed again and compared. The
    value of that computation is kept until the output's next check: a value may share buffers
    with the computation that made it, and the cached one may read them as long as the latest
    computation is alive and equal (a RobotState and its Pinocchio data)."""

    def __init__(self, clock: Clock):
        self.clock = clock
        self.outputs: dict[int, Output] = {}
        self.kept: dict[int, Any] = {}

    @staticmethod
    def of(clock: Clock) -> _TimeCheck:
        """The check of ``clock``, made (and put last in its time-varying list) if it has none."""
        check = next((o for o in clock.time_varying if isinstance(o, _TimeCheck)), None)
        if check is None:
            check = _TimeCheck(clock)
        else:
            clock.time_varying.remove(check)
        clock.time_varying.append(check)  # last: after the outputs added since
        return check

    def watch(self, outputs: list[Output], enabled: bool) -> None:
        """Start (or stop) watching ``outputs``; with none left the check leaves its clock."""
        for output in outputs:
            if enabled:
                self.outputs[id(output)] = output
            else:
                self.outputs.pop(id(output), None)
                self.kept.pop(id(output), None)
        if not self.outputs:
            self.clock.time_varying.remove(self)

    def invalidate(self) -> None:
        """Called by the clock when it moves: at a new latest tick, check the outputs served from cache."""
        clock = self.clock
        t = clock.t
        if t != clock.latest:  # a read at an earlier tick, by hand
            return
        for output in list(self.outputs.values()):
            if _served_from_cache(output, t, clock):
                self.kept[id(output)] = _compare_with_a_new_computation(output, t)


def _served_from_cache(output: Output, t: int, clock: Clock) -> bool:
    """True if a read of ``output`` at ``t`` would hand out its cached value, computed at an earlier
    tick: it is fresh, on ``clock``, not periodic or at the start of a window (within one a periodic
    output holds by design), and everything it reads is fresh (so computing it reads no new value)."""
    if output._stale or output._time is None or output._time >= t or output._clock is not clock:
        return False
    if output.period > 1 and t % output.period:
        return False
    for dep in output.deps:
        source = dep._source if isinstance(dep, Input) else dep
        if source is not None and not isinstance(source, State) and (source._stale or source._clock is not clock):
            return False
    return True


def _compare_with_a_new_computation(output: Output, t: int) -> Any:
    """Compute ``output`` at ``t`` and compare with its cached value; raise :class:`DependencyError`
    if they differ (or the computation fails), unless a second computation at ``t`` differs from
    the first: an output that does not compute the same value twice from the same inputs (a
    wall-clock time, a warm-started solve) cannot be judged and is left alone. Returns the
    latest value computed (the cache, its stamp and the counters are left as they were)."""
    value = _computed_again(output, t)
    if differs(output._value, value):
        again = _computed_again(output, t)
        if differs(value, again):
            return again
        raise _time_error(output, t, f"computed again at tick {t} it differs from its value of tick {output._time}")
    return value


def _computed_again(output: Output, t: int) -> Any:
    """The value of ``output``'s method at ``t``, the cache, its stamp and the counters restored
    (``DependencyError`` if it fails)."""
    cached, stamp, count, duration = output._value, output._time, output.count, output.total_duration
    try:
        return output._compute(t)
    except DependencyError:
        raise
    except DGraphError as exc:
        raise _time_error(output, t, f"computing it again at tick {t} failed ({exc})") from exc
    finally:
        output._value, output._time, output.count, output.total_duration = cached, stamp, count, duration
        output._stale = False


def _time_error(output: Output, t: int, what: str) -> DependencyError:
    """The error naming ``output``, the ticks and the fix: declare ``"t"``."""
    names = output.depends if output.depends is not None else tuple(dep.name for dep in output.deps)
    return DependencyError(
        f"{output.full_name} would be served from its cache at tick {t} (nothing it depends on changed since tick "
        f"{output._time}), but {what}: its method reads the time; declare it: depends={(*names, 't')!r}",
        entity=output.entity.name, signal=output.name)


MAX_DEPTH = 3
"""How deep :func:`differs` looks into structured values nested in one another."""
_SCALARS = (bool, int, float, complex, str, np.generic)


def differs(cached: Any, fresh: Any, depth: int = 0) -> bool:
    """True if ``fresh`` is known to differ from ``cached``: numpy arrays by shape and value,
    exactly (NaN equals NaN); numbers and strings exactly; tuples and lists element by element;
    structured values (dataclasses, objects with attributes) by the attributes both have, to
    :data:`MAX_DEPTH` levels. What cannot be compared (another library's object, a dict)
    counts as the same."""
    if cached is fresh:
        return False
    if isinstance(cached, np.ndarray) or isinstance(fresh, np.ndarray):
        return _arrays_differ(cached, fresh)
    if isinstance(cached, _SCALARS) or isinstance(fresh, _SCALARS):
        return not (isinstance(cached, _SCALARS) and isinstance(fresh, _SCALARS)) or \
            (cached != fresh and not (cached != cached and fresh != fresh))  # NaN == NaN
    if type(cached) is not type(fresh):
        return cached is None or fresh is None
    if isinstance(cached, (tuple, list)):
        return len(cached) != len(fresh) or any(differs(a, b, depth) for a, b in zip(cached, fresh, strict=True))
    return depth < MAX_DEPTH and any(differs(a, b, depth + 1) for a, b in _attribute_pairs(cached, fresh))


def _arrays_differ(cached: Any, fresh: Any) -> bool:
    """:func:`differs` for a numpy array on either side."""
    if not (isinstance(cached, np.ndarray) and isinstance(fresh, np.ndarray)):
        return True
    if cached.shape != fresh.shape or cached.dtype != fresh.dtype:
        return True
    try:
        return not np.array_equal(cached, fresh, equal_nan=cached.dtype.kind in "fc")
    except TypeError:  # object arrays: not compared
        return False


def _attribute_pairs(cached: Any, fresh: Any) -> Iterator[tuple[Any, Any]]:
    """The values of the attributes both objects hold: a dataclass's fields, else the instance
    dictionary's and the slots' entries (an attribute computed lazily on one only is skipped)."""
    if dataclasses.is_dataclass(cached):
        names = [field.name for field in dataclasses.fields(cached)]
    else:
        names = [*getattr(cached, "__dict__", {})]
        for klass in type(cached).__mro__:
            slots = getattr(klass, "__slots__", ())
            names += [slots] if isinstance(slots, str) else list(slots)
    missing = object()
    for name in names:
        a, b = getattr(cached, name, missing), getattr(fresh, name, missing)
        if a is not missing and b is not missing:
            yield a, b
