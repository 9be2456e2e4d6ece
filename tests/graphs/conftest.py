"""Every test here runs whole TALOS closed-loop simulations (seconds of simulated time each):
all are marked ``sim``, so ``pytest -m "not sim"`` is the fast loop of a developer."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph_sim.truth import true_com_and_frames

HERE = Path(__file__).parent
ROOT = HERE.parents[1]
SOLES = ("left_sole_link", "right_sole_link")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the tests of this folder ``sim``."""
    for item in items:
        if HERE in Path(item.fspath).parents:
            item.add_marker(pytest.mark.sim)


def run_walk(name: str, folder: Path) -> tuple[dg.Graph, dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """Run ``graphs/<name>.yaml`` to its duration, recording into ``folder``: the graph, its
    recording, and the true CoM and soles (from ``device.q``) at every tick."""
    graph = dg.load(str(ROOT / "graphs" / f"{name}.yaml"),
                    {"recorder.rerun": "off", "recorder.npz_path": str(folder / f"{name}.npz")})
    with graph:
        graph.run(duration=graph.duration, progress=False)
    data = graph["recorder"].data()
    com, soles = true_com_and_frames(data["device.q"], SOLES)
    return graph, data, com, soles


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
