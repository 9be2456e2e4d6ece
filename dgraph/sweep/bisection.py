"""Bisection of one grid cell: the largest value of a setting that still survives.

``low`` is run first with ``high`` (``low`` must survive, ``high`` must not: otherwise the cell's
verdict says which), then the midpoint of the bracket ``[largest survivor, smallest failure]``
until ``high - low <= tolerance * high`` (or after :data:`MAX_MIDPOINTS` midpoints, which only a
threshold at 0 needs). A run survives when its status is ``ok``; any other
status (fell, diverged, error, timeout, crashed) is a failure. The values asked depend only on the
outcomes, so a resumed bisection asks for the same runs again and finds them in its table.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from dgraph.sweep.outcome import Outcome, Run
from dgraph.sweep.spec import Bisection

VERDICTS = ("found", "survives high", "fails low")
MAX_MIDPOINTS = 40


@dataclass(frozen=True)
class Threshold:
    """What the bisection of one cell found: the largest surviving value of ``key`` and the
    smallest failing one (``None`` where there is none), the ``verdict`` (one of :data:`VERDICTS`)
    and the cell's outcomes by increasing value of ``key``."""

    cell: Run
    key: str
    largest_surviving: float | None
    smallest_failing: float | None
    verdict: str
    outcomes: list[Outcome] = field(default_factory=list)


class CellBisection:
    """The bisection of ``bisection.key`` in the cell ``cell`` (a run without that key)."""

    def __init__(self, cell: Run, bisection: Bisection):
        self.cell = cell
        self.bisection = bisection
        self.low: float | None = None  # the largest survivor so far
        self.high: float | None = None  # the smallest failure so far
        self.verdict: str | None = None
        self.outcomes: list[Outcome] = []

    def run(self, value: float) -> Run:
        """The cell's run with the bisected key at ``value``."""
        return replace(self.cell, settings={**self.cell.settings, self.bisection.key: float(value)})

    def first_runs(self) -> list[Run]:
        """The runs at ``low`` and ``high``."""
        return [self.run(self.bisection.low), self.run(self.bisection.high)]

    def record(self, outcome: Outcome) -> list[Run]:
        """Take the outcome of one of the cell's runs; the next run to make (none when done)."""
        self.outcomes.append(outcome)
        value = float(outcome.run.settings[self.bisection.key])
        if outcome.survived:
            self.low = value if self.low is None else max(self.low, value)
        else:
            self.high = value if self.high is None else min(self.high, value)
        if len(self.outcomes) > 2:
            return self._next()
        return self._after_bounds() if len(self.outcomes) == 2 else []

    def _after_bounds(self) -> list[Run]:
        """The verdict if ``low`` failed or ``high`` survived, else the first midpoint."""
        survived = {float(o.run.settings[self.bisection.key]): o.survived for o in self.outcomes}
        if not survived[self.bisection.low]:
            self.verdict = "fails low"
        elif survived[self.bisection.high]:
            self.verdict = "survives high"
        return [] if self.verdict else self._next()

    def _next(self) -> list[Run]:
        assert self.low is not None and self.high is not None
        midpoints = len(self.outcomes) - 2
        if self.high - self.low <= self.bisection.tolerance * self.high or midpoints >= MAX_MIDPOINTS:
            self.verdict = "found"
            return []
        return [self.run(0.5 * (self.low + self.high))]

    def threshold(self) -> Threshold:
        """What was found (once :meth:`record` returned no run: the verdict is known)."""
        assert self.verdict is not None, "the bisection of this cell is not finished"
        surviving = self.low if self.verdict != "fails low" else None
        outcomes = sorted(self.outcomes, key=lambda outcome: outcome.run.settings[self.bisection.key])
        return Threshold(self.cell, self.bisection.key, surviving, self.high, self.verdict, outcomes)
