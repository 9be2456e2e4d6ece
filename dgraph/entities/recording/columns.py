"""Growable numpy rows: one row per tick in a structured array, one numpy call per row written."""

from __future__ import annotations

from typing import Any

import numpy as np

INITIAL_ROWS = 1024


def field_dtype(value: Any) -> tuple[np.dtype, tuple[int, ...]]:
    """The dtype and shape of a column whose first row is ``value``: its own dtype for numbers
    (float, int, unsigned, bool), else ``object``."""
    first = np.asarray(value)
    return (first.dtype if first.dtype.kind in "fiub" else np.dtype(object)), first.shape


class Table:
    """Rows of a fixed number of columns, stored in one numpy structured array that doubles when full.

    Each column's dtype and row shape come from the first row (:func:`field_dtype`); a row is
    copied in with a single assignment (:meth:`write`, then :meth:`keep`), one numpy call
    whatever the number of columns. A value of another shape raises ``ValueError`` (a scalar
    fills a vector column, as numpy broadcasts it).
    """

    __slots__ = ("_data", "n")

    def __init__(self) -> None:
        self._data: np.ndarray | None = None
        self.n = 0

    def write(self, row: tuple[Any, ...]) -> None:
        """Copy ``row`` (a tuple, one value per column) into the next free row without adding it
        (:meth:`keep` does): a row that does not fit raises here and the table stays as it was,
        so a recorder can check a tick's row before the tick commits."""
        if self._data is None:
            fields = [(f"f{i}", *field_dtype(value)) for i, value in enumerate(row)]
            self._data = np.empty(INITIAL_ROWS, dtype=np.dtype(fields, align=True))
        elif self.n == len(self._data):
            self._data = np.concatenate([self._data, np.empty_like(self._data)])
        self._data[self.n] = row

    def keep(self) -> None:
        """Add the row last written (once)."""
        self.n += 1

    def field_shape(self, i: int) -> tuple[int, ...]:
        """The row shape of column ``i`` (set by the first row written)."""
        return () if self._data is None else self._data.dtype[f"f{i}"].shape

    def column(self, i: int, start: int = 0) -> np.ndarray:
        """A view of column ``i`` from row ``start`` on (shape ``(rows, *row_shape)``)."""
        if self._data is None:
            return np.zeros((0,))
        return self._data[f"f{i}"][start: self.n]
