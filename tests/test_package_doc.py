"""The package docstring's example runs as written (a doctest)."""

from __future__ import annotations

import doctest

import dgraph


def test_the_package_docstring_example_runs():
    results = doctest.testmod(dgraph, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert results.attempted >= 10 and results.failed == 0, results
