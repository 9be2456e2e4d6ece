"""The rising graph (see rising_graph.py) in each test's folder."""

from __future__ import annotations

from pathlib import Path

import pytest
from rising_graph import write_rising


@pytest.fixture
def rising(tmp_path: Path) -> str:
    """The path of the rising graph file, in the test's own folder."""
    return write_rising(tmp_path)
