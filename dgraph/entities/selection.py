"""Rows: a selection of rows or entries of an array that keeps views where it can."""

from __future__ import annotations

from typing import TypeAlias

import numpy as np

Rows: TypeAlias = np.ndarray | slice | None
"""Rows kept: all (``None``), a contiguous range (``slice``: selecting gives views) or indices."""


def contiguous(indices: np.ndarray, width: int | None = None) -> Rows:
    """``indices`` as ``None`` if they are all ``width`` rows in order, a slice if they are
    consecutive and increasing (selecting then gives views), else themselves."""
    start = int(indices[0]) if len(indices) else 0
    if not np.array_equal(indices, np.arange(start, start + len(indices))):
        return indices
    return None if start == 0 and len(indices) == width else slice(start, start + len(indices))
