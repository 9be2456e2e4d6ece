"""Growable numpy columns: one row per tick, amortised O(1) append, no per-row Python objects."""

from __future__ import annotations

from typing import Any

import numpy as np

INITIAL_ROWS = 1024


class Column:
    """Rows of equal shape stored in one numpy array that doubles when full.

    The dtype and row shape come from the first row (float, int, bool, or object for values
    that are not numbers). A row of another shape raises ``ValueError``.
    """

    __slots__ = ("_data", "n")

    def __init__(self) -> None:
        self._data: np.ndarray | None = None
        self.n = 0

    def append(self, value: Any) -> None:
        """Add one row (copied)."""
        if self._data is None:
            first = np.asarray(value)
            dtype = first.dtype if first.dtype.kind in "fiub" else object
            self._data = np.empty((INITIAL_ROWS, *first.shape), dtype=dtype)
        elif self.n == len(self._data):
            self._data = np.concatenate([self._data, np.empty_like(self._data)])
        self._data[self.n] = value
        self.n += 1

    def last(self, count: int) -> np.ndarray:
        """A view of the last ``count`` rows."""
        return self.values()[self.n - count:]

    def values(self) -> np.ndarray:
        """A view of all rows (shape ``(n, *row_shape)``)."""
        if self._data is None:
            return np.zeros((0,))
        return self._data[: self.n]
