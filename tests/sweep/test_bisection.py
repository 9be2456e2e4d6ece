"""The bisection of one cell, on outcomes made up from a known threshold (no run)."""

from __future__ import annotations

import pytest

from dgraph.sweep.bisection import MAX_MIDPOINTS, CellBisection
from dgraph.sweep.outcome import Outcome, Run
from dgraph.sweep.spec import Bisection

CELL = Run("g.yaml", {"push.direction": [1, 0, 0]}, 1.0)


def bisect(bisection: Bisection, survives) -> tuple[CellBisection, list[float]]:
    """Run the cell's bisection to its end with ``survives(value)`` as each run's fate; the
    cell and the values asked, in order."""
    cell = CellBisection(CELL, bisection)
    pending, asked = cell.first_runs(), []
    while pending:
        run = pending.pop(0)
        value = run.settings["push.gain"]
        asked.append(value)
        assert run.settings["push.direction"] == [1, 0, 0]
        pending += cell.record(Outcome(run, "ok" if survives(value) else "fell", None, 1.0, 0.0))
    return cell, asked


@pytest.mark.parametrize("threshold", [0.013, 0.5, 1.0, 7.77, 9.99])
@pytest.mark.parametrize("tolerance", [0.05, 0.01])
def test_the_largest_survivor_is_found_to_the_tolerance(threshold, tolerance):
    cell, asked = bisect(Bisection("push.gain", 0.0, 10.0, tolerance), lambda v: v < threshold)
    found = cell.threshold()
    assert found.verdict == "found" and found.key == "push.gain"
    assert found.largest_surviving < threshold <= found.smallest_failing
    assert found.smallest_failing - found.largest_surviving <= tolerance * found.smallest_failing
    assert asked[:2] == [0.0, 10.0] and len(asked) == len(found.outcomes) == len(set(asked))
    assert [o.run.settings["push.gain"] for o in found.outcomes] == sorted(asked)
    _, asked_again = bisect(Bisection("push.gain", 0.0, 10.0, tolerance), lambda v: v < threshold)
    assert asked_again == asked  # deterministic: a resumed bisection asks for the same runs


def test_a_cell_that_fails_low_or_survives_high_says_so_after_two_runs():
    cell, asked = bisect(Bisection("push.gain", 1.0, 2.0), lambda v: False)
    assert (cell.threshold().verdict, cell.threshold().largest_surviving, cell.threshold().smallest_failing) == \
        ("fails low", None, 1.0)
    cell, asked = bisect(Bisection("push.gain", 1.0, 2.0), lambda v: True)
    assert (cell.threshold().verdict, cell.threshold().largest_surviving, cell.threshold().smallest_failing) == \
        ("survives high", 2.0, None)
    assert asked == [1.0, 2.0]
    cell, _ = bisect(Bisection("push.gain", 1.0, 2.0), lambda v: v > 1.5)  # not monotone: low fails
    assert cell.threshold().verdict == "fails low"


def test_a_threshold_at_zero_ends_after_the_longest_bisection():
    cell, asked = bisect(Bisection("push.gain", 0.0, 1.0), lambda v: v == 0.0)
    assert cell.threshold().verdict == "found" and len(asked) == 2 + MAX_MIDPOINTS
    assert cell.threshold().smallest_failing == pytest.approx(2.0 ** -MAX_MIDPOINTS)
