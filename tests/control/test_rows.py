"""RowBlock: the row blocks of the strict-priority solvers, stacked into levels."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.control import RowBlock
from dgraph.control.rows import selection, stacked


def test_equalities_inequalities_and_an_empty_block_have_consistent_shapes():
    rng = np.random.default_rng(0)
    blocks = [RowBlock.equalities(rng.normal(size=(2, 5)), rng.normal(size=2)),
              RowBlock.inequalities(rng.normal(size=(3, 5)), -np.ones(3), np.ones(3), key="limits"),
              RowBlock.empty(5)]
    assert [block.shape_problem(5) for block in blocks] == [None, None, None]
    assert blocks[1].key == "limits" and blocks[2].key is None
    assert blocks[2].residual(rng.normal(size=5)) == 0.0 and blocks[2].is_valid()


def test_a_shape_problem_is_named():
    block = RowBlock.equalities(np.zeros((2, 4)), np.zeros(2))
    assert "over 5 variables" in block.shape_problem(5)
    uneven = RowBlock(np.zeros((0, 3)), np.zeros(0), np.zeros((2, 3)), np.zeros(1), np.zeros(2))
    assert uneven.shape_problem(3) == "1 lower bounds but (2,) upper bounds"


def test_stacked_blocks_keep_their_rows_in_order_under_the_new_key():
    rng = np.random.default_rng(1)
    a = RowBlock(rng.normal(size=(1, 4)), rng.normal(size=1), rng.normal(size=(2, 4)), -np.ones(2), np.ones(2))
    b = RowBlock.equalities(rng.normal(size=(3, 4)), rng.normal(size=3))
    both = stacked([a, b], key=("a", "b"))
    assert both.key == ("a", "b") and both.shape_problem(4) is None
    np.testing.assert_array_equal(both.equality_matrix, np.vstack([a.equality_matrix, b.equality_matrix]))
    np.testing.assert_array_equal(both.inequality_matrix, a.inequality_matrix)
    alone = stacked([b], key="b")
    assert alone.key == "b" and alone.equality_matrix is b.equality_matrix  # one block: no copy


@pytest.mark.parametrize("x", [np.array([0.5, 2.0, -3.0]), np.array([0.0, 0.0, 0.0])])
def test_the_residual_counts_the_equality_error_and_the_bound_violation(x):
    block = RowBlock(np.array([[1.0, 0.0, 0.0]]), np.array([1.0]), selection([1, 2], 3), np.array([-1.0, -1.0]),
                     np.array([1.0, 1.0]))
    violation = np.maximum(np.abs(x[1:]) - 1.0, 0.0)
    assert block.residual(x) == pytest.approx(np.sqrt((x[0] - 1.0) ** 2 + violation @ violation))


def test_selection_picks_the_bounded_variables():
    np.testing.assert_array_equal(selection([2, 0], 3), [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    assert selection([], 4).shape == (0, 4)


def test_nan_data_or_crossed_bounds_make_a_block_invalid():
    assert not RowBlock.equalities(np.eye(2), np.array([np.nan, 0.0])).is_valid()
    assert not RowBlock.inequalities(np.eye(2), np.ones(2), np.zeros(2)).is_valid()
