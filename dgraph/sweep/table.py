"""The results file of a sweep: a CSV table with a header, one row per finished run appended and
flushed as it arrives (in completion order), so that an interrupted sweep keeps every run it
finished; read back when the sweep starts again, its rows are the outcomes of the runs they
identify (:meth:`~dgraph.sweep.outcome.Run.identity`), which are not run again, except a
``crashed`` run (its process died: a killed machine, no memory), which is run again.

Columns: ``file``, one per setting key (the value's YAML text, see
:func:`~dgraph.sweep.spec.setting_text`), ``duration``, ``fall_signal``, ``status``, ``fall_time``,
``simulated_time``, ``wall_time`` (s; empty for none), one per measure, ``message``.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from dgraph.sweep.outcome import Outcome, Run, number_text
from dgraph.sweep.spec import SweepError, setting_text

OUTCOME_COLUMNS = ("status", "fall_time", "simulated_time", "wall_time")


def header(setting_keys: Sequence[str], measures: Sequence[str]) -> list[str]:
    """The columns of a sweep's table (see the module docstring)."""
    return ["file", *setting_keys, "duration", "fall_signal", *OUTCOME_COLUMNS, *measures, "message"]


def _cell(value: Any, column: str, setting_keys: Sequence[str]) -> str:
    if column in setting_keys:
        return setting_text(value)
    if isinstance(value, float):
        return number_text(value)
    return "" if value is None else str(value)


def _number(text: str) -> float | None:
    return None if text == "" else float(text)


class ResultsTable:
    """The table file at ``path`` of a sweep whose runs set ``setting_keys`` and record
    ``measures``; ``fresh`` starts it over, else the rows it has are kept (and reused)."""

    def __init__(self, path: str | Path, setting_keys: Sequence[str], measures: Sequence[str], fresh: bool = False):
        self.path = Path(path)
        self.setting_keys = list(setting_keys)
        self.measures = list(measures)
        self.columns = header(setting_keys, measures)
        self._rows: dict[tuple[Any, ...], dict[str, str]] = {} if fresh else self._read()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if fresh or not self.path.exists() or self.path.stat().st_size == 0:  # no header yet
            self.path.write_text(_csv_line(self.columns))
        self._file = self.path.open("a", newline="", encoding="utf-8")

    def _read(self) -> dict[tuple[Any, ...], dict[str, str]]:
        """The rows of an existing table by identity, but ``crashed`` ones (a last line cut short
        by an interruption is cut off the file in place, the lines before it untouched); a table
        with other columns is refused."""
        if not self.path.exists():
            return {}
        data = self.path.read_bytes()
        if not data.endswith(b"\n"):
            data = data[:data.rfind(b"\n") + 1]
            os.truncate(self.path, len(data))
        rows = list(csv.reader(io.StringIO(data.decode("utf-8"))))
        if rows and rows[0] != self.columns:
            raise SweepError(f"{self.path}: its columns ({', '.join(rows[0])}) are not this sweep's "
                             f"({', '.join(self.columns)}): give another results file, or start over (--fresh)")
        records = [dict(zip(self.columns, row, strict=True)) for row in rows[1:]
                   if len(row) == len(self.columns) and row[self.columns.index("status")] != "crashed"]
        return {self._identity(record): record for record in reversed(records)}  # the first row of a run wins

    def _identity(self, record: dict[str, str]) -> tuple[Any, ...]:
        settings = tuple(sorted((key, record[key]) for key in self.setting_keys))
        return record["file"], settings, record["duration"], record["fall_signal"]

    def __len__(self) -> int:
        return len(self._rows)

    def reused(self, run: Run) -> Outcome | None:
        """The outcome of ``run`` that the table already has, or ``None``."""
        record = self._rows.get(run.identity())
        if record is None:
            return None
        return Outcome(run, record["status"], _number(record["fall_time"]), _number(record["simulated_time"]),
                       float(record["wall_time"]), {name: float(record[name] or math.nan) for name in self.measures},
                       record["message"])

    def append(self, outcomes: Iterable[Outcome]) -> None:
        """Write the rows of ``outcomes`` and flush them to the file."""
        for outcome in outcomes:
            row = outcome.row()
            record = {column: _cell(row[column], column, self.setting_keys) for column in self.columns}
            self._file.write(_csv_line([record[column] for column in self.columns]))
            if outcome.status != "crashed":
                self._rows.setdefault(outcome.run.identity(), record)
        self._file.flush()

    def close(self) -> None:
        """Close the file."""
        self._file.close()

    def __enter__(self) -> ResultsTable:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _csv_line(values: Sequence[str]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(values)
    return buffer.getvalue()


def read_table(path: str | Path) -> list[dict[str, str]]:
    """The rows of a results table as dicts of their texts, column name -> text."""
    with Path(path).open(newline="", encoding="utf-8") as file:
        return list(csv.DictReader(file))
