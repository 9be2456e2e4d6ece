"""Faults: what went wrong at a tick that the loop survived, and what was done about it.

A controller's first duty is to keep sending a safe command: an entity that meets bad data (a
sensor reading that is NaN, infinite, out of range or frozen; a QP that could not be solved; a
command that could not be applied) does not raise, it substitutes a safe value and *reports* a
:class:`Fault` naming the signal, the cause and the action. A tick with at least one fault is
**degraded**.

The graph's :class:`FaultLog` keeps them with the same transaction as the states: faults
reported while a tick is computed are staged, and kept only if the tick commits (a failed and
retried tick is not counted twice). Observers (recorders) read the staged faults of the tick
they record. The log stores the first :data:`KEPT_FAULTS` faults in full and counts every one.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

KEPT_FAULTS = 10_000
"""Faults kept in full by a log (every fault is counted; a sensor dead for minutes at 1 kHz
would otherwise fill the memory)."""


@dataclass(frozen=True)
class Fault:
    """One fault at one tick: ``signal`` (``entity.signal``, with an element index where one
    element was at fault), ``cause`` (a short category: ``NaN``, ``inf``, ``out of range``,
    ``jump``, ``frozen``, ``QP primal infeasible``...), ``action`` (what was used instead) and
    ``detail`` (the numbers: the value, the limit)."""

    tick: int
    signal: str
    cause: str
    action: str
    detail: str = ""

    def __str__(self) -> str:
        detail = f" ({self.detail})" if self.detail else ""
        return f"tick {self.tick}: {self.signal}: {self.cause}{detail}; {self.action}"


class FaultLog:
    """The faults of a graph's run: staged during a tick, kept when it commits.

    ``faults`` (the first :data:`KEPT_FAULTS` kept faults, in order), ``degraded`` (every
    committed tick that had a fault, in order), ``degraded_ticks`` (how many), ``counts``
    (kept faults per ``(signal, cause)``),
    :meth:`staged` (the faults reported so far at a tick that has not committed yet).
    """

    def __init__(self) -> None:
        self.faults: list[Fault] = []
        self.degraded: list[int] = []
        self.counts: Counter[tuple[str, str]] = Counter()
        self._staged: list[Fault] = []

    @property
    def degraded_ticks(self) -> int:
        """How many committed ticks had a fault."""
        return len(self.degraded)

    def report(self, tick: int, signal: str, cause: str, action: str, detail: str = "") -> None:
        """Stage a fault of ``tick`` (the same fault reported again at the same tick, by a
        computation that ran again after a failed attempt, is staged once)."""
        fault = Fault(tick, signal, cause, action, detail)
        if fault not in self._staged:
            self._staged.append(fault)

    def staged(self, tick: int) -> list[Fault]:
        """The faults reported at ``tick`` so far (not committed yet)."""
        return [f for f in self._staged if f.tick == tick]

    def begin(self, tick: int) -> None:
        """A tick starts: forget faults staged for another tick (a tick that failed and was not retried)."""
        if self._staged and any(f.tick != tick for f in self._staged):
            self._staged = self.staged(tick)

    def commit(self, tick: int) -> None:
        """``tick`` committed: keep its staged faults."""
        if not self._staged:
            return
        mine = self.staged(tick)
        self._staged = []
        if not mine:
            return
        self.degraded.append(tick)
        for fault in mine:
            self.counts[fault.signal, fault.cause] += 1
        self.faults.extend(mine[:max(0, KEPT_FAULTS - len(self.faults))])

    def clear(self) -> None:
        """Forget everything (a reset)."""
        self.faults, self.degraded, self._staged = [], [], []
        self.counts.clear()

    def summary(self, limit: int = 5) -> str:
        """One line per frequent ``signal: cause`` with its count, most frequent first."""
        lines = [f"{count} x {signal}: {cause}" for (signal, cause), count in self.counts.most_common(limit)]
        if len(self.counts) > limit:
            lines.append(f"... and {len(self.counts) - limit} other kinds")
        return "\n".join(lines)


__all__ = ["KEPT_FAULTS", "Fault", "FaultLog"]
