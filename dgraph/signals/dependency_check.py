"""Debug mode that catches reads of undeclared dependencies.

An output's ``depends`` drives invalidation; if its method reads a port it did not declare,
the output misses that port's changes and silently serves stale values. With
``graph.check_dependencies = True`` every output's method runs with the undeclared ports of
its entity replaced by stand-ins that raise :class:`DependencyError` when read. The swap
happens only in this mode: normal runs pay nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from dgraph.errors import DependencyError
from dgraph.signals.signal import Output, Signal


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
    """Guard or unguard every output in ``outputs``."""
    action: Callable[[Output], None] = guard if enabled else unguard
    for output in outputs:
        action(output)
