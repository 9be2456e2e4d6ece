"""Every test here runs whole TALOS closed-loop simulations (seconds of simulated time each):
all are marked ``sim``, so ``pytest -m "not sim"`` is the fast loop of a developer."""

from __future__ import annotations

from pathlib import Path

import pytest

HERE = Path(__file__).parent


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the tests of this folder ``sim``."""
    for item in items:
        if HERE in Path(item.fspath).parents:
            item.add_marker(pytest.mark.sim)
