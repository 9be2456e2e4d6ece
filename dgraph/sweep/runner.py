"""Running a sweep: its runs checked (:mod:`~dgraph.sweep.plan`), handed to a pool of processes or
to Ray (:mod:`~dgraph.sweep.executors`) as many at a time as it takes, their outcomes written to
the results table as they come (:mod:`~dgraph.sweep.table`), those the table already has reused;
for a bisection, each cell's next run asked for when its last one ends
(:mod:`~dgraph.sweep.bisection`); a progress bar over the runs; at the end, the picture
(:mod:`~dgraph.sweep.plot`).

An interruption (Ctrl-C, or an exception from ``on_outcome``) stops the runs in flight (they give
no outcome) and leaves the table with every run that finished: the same sweep started again
resumes there.
"""

from __future__ import annotations

import collections
import importlib.util
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from dgraph.sweep.bisection import CellBisection, Threshold
from dgraph.sweep.executors import Pool, make_pool
from dgraph.sweep.outcome import Outcome, Run
from dgraph.sweep.plan import planned_runs
from dgraph.sweep.spec import Sweep, setting_text
from dgraph.sweep.table import ResultsTable


@dataclass
class SweepResult:
    """What a sweep found: every run's outcome (a grid's in the order of its cells, a
    bisection's cell by cell), a bisection's thresholds (one per cell), the table and picture
    written, and how many outcomes came from the table instead of a run."""

    outcomes: list[Outcome]
    thresholds: list[Threshold] = field(default_factory=list)
    table: Path | None = None
    plot: Path | None = None
    reused: int = 0

    def counts(self) -> dict[str, int]:
        """How many runs ended with each status."""
        return dict(collections.Counter(outcome.status for outcome in self.outcomes))

    def summary(self) -> str:
        """What the sweep found, in a few lines: the runs by status, where they are written,
        and a bisection's thresholds, one line per cell."""
        counts = ", ".join(f"{n} {status}" for status, n in self.counts().items())
        written = ", ".join(str(path) for path in (self.table, self.plot) if path is not None)
        runs = f"{len(self.outcomes)} run{'' if len(self.outcomes) == 1 else 's'}"
        lines = [f"{runs} ({counts}; {self.reused} from the table)" + (f" -> {written}" if written else "")]
        lines += [f"  {_threshold_line(t)}" for t in self.thresholds]
        return "\n".join(lines)


def _threshold_line(threshold: Threshold) -> str:
    """``file key=value ...: KEY survives A, fails B (N runs)`` (or ``fails low A``, ``survives high B``)."""
    cell, key = threshold.cell, threshold.key
    settings = "".join(f" {k}={setting_text(value)}" for k, value in cell.settings.items())
    if threshold.verdict == "fails low":
        found = f"{key} fails low {threshold.smallest_failing:.6g}"
    elif threshold.verdict == "survives high":
        found = f"{key} survives high {threshold.largest_surviving:.6g}"
    else:
        found = f"{key} survives {threshold.largest_surviving:.6g}, fails {threshold.smallest_failing:.6g}"
    return f"{Path(cell.file).name}{settings}: {found} ({len(threshold.outcomes)} runs)"


class _Grid:
    """A grid's runs: all of them at once, nothing after."""

    def __init__(self, runs: list[Run]):
        self.runs = runs

    def first_runs(self) -> list[Run]:
        return list(self.runs)

    def record(self, outcome: Outcome) -> list[Run]:
        return []


class _Bisections:
    """The bisections of every cell, side by side: each cell's next run asked for when its last one ends."""

    def __init__(self, cells: list[Run], sweep: Sweep):
        assert sweep.bisection is not None
        self.cells = [CellBisection(cell, sweep.bisection) for cell in cells]
        self._cell_of: dict[tuple[Any, ...], CellBisection] = {}

    def _asked(self, cell: CellBisection, runs: list[Run]) -> list[Run]:
        self._cell_of.update({run.identity(): cell for run in runs})
        return runs

    def first_runs(self) -> list[Run]:
        return [run for cell in self.cells for run in self._asked(cell, cell.first_runs())]

    def record(self, outcome: Outcome) -> list[Run]:
        cell = self._cell_of[outcome.run.identity()]
        return self._asked(cell, cell.record(outcome))


class _Loop:
    """Runs what a policy (:class:`_Grid`, :class:`_Bisections`) asks for, ``pool.capacity`` at a time."""

    def __init__(self, pool: Pool, table: ResultsTable, bar: Any, on_outcome: Callable[[Outcome], None] | None):
        self.pool, self.table, self.bar, self.on_outcome = pool, table, bar, on_outcome
        self.outcomes: list[Outcome] = []
        self.reused = 0
        self._queue: collections.deque[Run] = collections.deque()
        self._in_flight = 0

    def run(self, policy: _Grid | _Bisections) -> None:
        """Run the policy's runs, and those it asks for as outcomes come, to the last."""
        self._queue.extend(policy.first_runs())
        self._in_flight = 0
        while self._queue or self._in_flight:
            self._start_what_fits(policy)
            if self._in_flight:
                self._collect(policy)

    def _start_what_fits(self, policy: _Grid | _Bisections) -> None:
        """Start queued runs up to the pool's capacity; those the table has are delivered instead."""
        while self._queue and self._in_flight < self.pool.capacity:
            run = self._queue.popleft()
            known = self.table.reused(run)
            if known is None:
                self.pool.submit(run)
                self._in_flight += 1
            else:
                self.reused += 1
                self._deliver(policy, [known])

    def _collect(self, policy: _Grid | _Bisections) -> None:
        """Wait for runs to finish; write, deliver and report their outcomes."""
        finished = self.pool.wait()
        self._in_flight -= len(finished)
        self.table.append(finished)
        self._deliver(policy, finished)
        if self.on_outcome is not None:
            for outcome in finished:
                self.on_outcome(outcome)

    def _deliver(self, policy: _Grid | _Bisections, outcomes: list[Outcome]) -> None:
        for outcome in outcomes:
            self.outcomes.append(outcome)
            self._queue.extend(policy.record(outcome))
        counts = collections.Counter(outcome.status for outcome in self.outcomes)
        self.bar.set_postfix_str(", ".join(f"{n} {status}" for status, n in counts.items()), refresh=False)
        self.bar.update(len(outcomes))


def run_sweep(sweep: Sweep, out: str | Path, *, ray: bool | str = False, workers: int | None = None,
              fresh: bool = False, plot: str | Path | None = None, progress: bool = True,
              on_outcome: Callable[[Outcome], None] | None = None) -> SweepResult:
    """Run ``sweep``, its results in the table ``out`` (kept and resumed unless ``fresh``), on
    this machine with ``workers`` processes (default: one per CPU) or with ``ray`` on a Ray
    cluster (``True``: a local one; a string: its address); a picture to ``plot`` if given;
    ``on_outcome`` called with each new outcome once it is in the table. Raises
    :class:`~dgraph.sweep.spec.SweepError` (or the graph files' error) before any run if a run
    cannot be made (the graph files' own message, prefixed by the grid cell); never for a run
    that fails."""
    from tqdm import tqdm

    runs = planned_runs(sweep)
    policy = _Grid(runs) if sweep.bisection is None else _Bisections(runs, sweep)
    with make_pool(ray, workers, sweep.timeout) as pool, \
            ResultsTable(out, sweep.setting_keys, sweep.measures, fresh) as table, \
            tqdm(total=len(runs) if sweep.bisection is None else None, unit="run", desc="sweep",
                 disable=not progress, leave=False) as bar:
        loop = _Loop(pool, table, bar, on_outcome)
        loop.run(policy)
    result = _result(runs, policy, loop)
    result.table = Path(out)
    if plot is not None:
        result.plot = draw(result, sweep, plot)
    return result


def _result(runs: list[Run], policy: _Grid | _Bisections, loop: _Loop) -> SweepResult:
    """The outcomes in the order of the grid's cells, or cell by cell with their thresholds."""
    if isinstance(policy, _Bisections):
        thresholds = [cell.threshold() for cell in policy.cells]
        return SweepResult([o for t in thresholds for o in t.outcomes], thresholds, reused=loop.reused)
    by_identity = {outcome.run.identity(): outcome for outcome in loop.outcomes}
    return SweepResult([by_identity[run.identity()] for run in runs], reused=loop.reused)


def draw(result: SweepResult, sweep: Sweep, path: str | Path) -> Path | None:
    """The picture of ``result`` at ``path`` (:mod:`~dgraph.sweep.plot`), or ``None`` with a
    warning if matplotlib is not installed."""
    if importlib.util.find_spec("matplotlib") is None:
        warnings.warn("matplotlib is not installed (the 'plots' extra): no plot", stacklevel=2)
        return None
    from dgraph.sweep.plot import plot_grid, plot_thresholds

    axes: Sequence[str] = list(sweep.grid)
    if sweep.bisection is not None:
        return plot_thresholds(result.thresholds, axes, path)
    return plot_grid(result.outcomes, axes, path)
