"""Running a walking graph of graphs/ to its end, for the walking tests of this folder."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import dgraph as dg
from dgraph_sim.truth import true_com_and_frames

ROOT = Path(__file__).resolve().parents[2]
SOLES = ("left_sole_link", "right_sole_link")


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
