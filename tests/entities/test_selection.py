"""selection.contiguous: a slice (views) for consecutive rows, None for all of them, else the indices."""

from __future__ import annotations

import numpy as np

from dgraph.entities.selection import contiguous


def test_consecutive_rows_become_a_slice_and_all_rows_none():
    assert contiguous(np.array([2, 3, 4])) == slice(2, 5)
    assert contiguous(np.array([0, 1, 2]), 3) is None
    assert contiguous(np.array([0, 1, 2]), 4) == slice(0, 3)
    assert contiguous(np.array([], dtype=np.intp)) == slice(0, 0)


def test_other_rows_stay_indices():
    for rows in ([0, 2, 3], [3, 2, 1], [1, 1]):
        indices = np.array(rows)
        assert contiguous(indices, 4) is indices
