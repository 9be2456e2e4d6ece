"""The library's exceptions: every error raised by dgraph derives from :class:`DGraphError`.

Each error carries the entity and signal it concerns (when there is one) so that a message
from deep inside a 1 kHz loop still says where to look.
"""

from __future__ import annotations


class DGraphError(Exception):
    """Base class of every error raised by dgraph.

    ``entity`` and ``signal`` name the place concerned (``None`` when not applicable).
    """

    def __init__(self, message: str, *, entity: str | None = None, signal: str | None = None):
        super().__init__(message)
        self.entity = entity
        self.signal = signal


class SpecError(DGraphError, ValueError):
    """A value does not match a signal's declared shape or dtype, or holds NaN."""


class NonFiniteError(SpecError):
    """A value holds NaN, or a staged state inf, where a signal declares finite values."""


class DivergenceError(DGraphError):
    """A simulation diverged: its state is no longer finite, or no longer bounded."""


class PlugError(DGraphError):
    """A plug is refused: shape mismatch, wrong direction, or entities in different graphs."""


class CycleError(PlugError):
    """A plug would close a loop with no Delay or device state on it.

    ``cycle`` lists the full names of the signals on the loop, in data-flow order.
    """

    def __init__(self, message: str, cycle: list[str], **kw: str | None):
        super().__init__(message, **kw)
        self.cycle = cycle


class DependencyError(DGraphError):
    """An output read a port of its entity that it does not declare in ``depends``."""


class UnpluggedInputError(DGraphError):
    """An input was read while it is neither plugged nor set and has no default."""


class ComputeError(DGraphError):
    """An output's computation raised; the original exception is chained as ``__cause__``."""


class ParamError(DGraphError, ValueError):
    """An entity parameter is unknown, missing or of the wrong type."""


class RegistryError(DGraphError, KeyError):
    """An entity type is unknown or registered twice."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0])


class GraphError(DGraphError):
    """A graph-level problem: duplicate entity name, unknown signal, failed validation."""


class HookError(DGraphError):
    """A device before/after hook raised. The device state is left consistent."""


class GraphFileError(DGraphError):
    """A graph file is malformed or refers to things that do not exist.

    ``file``, ``line`` and ``key`` locate the problem (line is 1-based, ``None`` if unknown).
    """

    def __init__(self, message: str, *, file: str | None = None, line: int | None = None,
                 key: str | None = None, **kw: str | None):
        where = file or "<graph>"
        if line is not None:
            where += f":{line}"
        if key:
            where += f" [{key}]"
        super().__init__(f"{where}: {message}", **kw)
        self.file = file
        self.line = line
        self.key = key
