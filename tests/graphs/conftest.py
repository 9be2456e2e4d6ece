"""Every test here runs whole TALOS closed-loop simulations (seconds of simulated time each):
all are marked ``sim``, so ``pytest -m "not sim"`` is the fast loop of a developer."""

from __future__ import annotations

from pathlib import Path

import pytest
from walk_runs import run_walk

HERE = Path(__file__).parent


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the tests of this folder ``sim``."""
    for item in items:
        if HERE in Path(item.fspath).parents:
            item.add_marker(pytest.mark.sim)


@pytest.fixture(scope="module")
def walks(tmp_path_factory):
    """``walks(name)``: :func:`run_walk` of a walking graph, made once per test module when a test
    first asks for it."""
    runs: dict[str, tuple] = {}

    def get(name: str) -> tuple:
        if name not in runs:
            runs[name] = run_walk(name, tmp_path_factory.mktemp(name))
        return runs[name]
    return get
