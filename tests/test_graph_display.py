"""Graph's rich display in Jupyter: summary, Mermaid drawing, entity table (dgraph.display)."""

from __future__ import annotations

import itertools
import subprocess
import sys

from IPython.core.formatters import DisplayFormatter

import dgraph as dg
from dgraph import display
from dgraph.entities.operators import Gain
from tests.conftest import Scale, Ticker


def small_graph() -> dg.Graph:
    g = dg.Graph(dt=0.002, name="small")
    g.add(Ticker("dev"), Scale("a"), Scale("b"))
    g.plug("dev.x", "a.u")
    g.plug("a.y", "b.u")
    return g


def test_markdown_has_summary_drawing_and_entities():
    g = small_graph()
    text = g._repr_markdown_()
    summary, block, table = text.split("\n\n")
    assert summary == ("**Graph `small`**: 3 entities, 2 plugs, dt = 0.002 s (500 Hz), at tick 0 (t = 0 s)")
    assert block == f"```mermaid\n{g.to_mermaid()}```"
    assert 'n_dev -- "x -> u" --> n_a' in block and 'n_a -- "y -> u" --> n_b' in block
    rows = table.splitlines()
    assert rows[0] == "| entity | type | inputs plugged | outputs | missing inputs |"
    assert rows[2:] == ["| `dev` | `Ticker` | 0 / 0 | 1 |  |",
                        "| `a` | `Scale` | 1 / 2 | 2 |  |",
                        "| `b` | `Scale` | 1 / 2 | 2 |  |"]


def test_missing_inputs_duration_tick_and_faults_are_shown():
    g = small_graph()
    g.unplug("b.u")
    g.duration = 1.5
    text = g._repr_markdown_()
    assert "| `b` | `Scale` | 0 / 2 | 2 | `u` |" in text  # `unused` has a default, so only u is missing
    assert "duration 1.5 s" in text and "degraded" not in text
    g.plug("a.y", "b.u")
    g.run(ticks=5, progress=False)
    g.fault_log.report(5, "a.y", "NaN", "held the last value")
    g.step()
    text = g._repr_markdown_()
    assert "at tick 6 (t = 0.012 s)" in text
    assert text.splitlines()[0].endswith(", 1 degraded ticks")


def test_jupyter_picks_the_markdown():
    g = small_graph()
    data, _ = DisplayFormatter().format(g)
    assert data["text/markdown"] == g._repr_markdown_()
    assert data["text/plain"] == repr(g)
    assert "text/html" not in data  # JupyterLab would prefer it to the Markdown and lose the drawing


def test_empty_graph_and_odd_names():
    g = dg.Graph(name="a `quoted` name")
    text = g._repr_markdown_()
    assert text.startswith("**Graph ``a `quoted` name``**: 0 entities, 0 plugs")
    assert dg.Graph(name="`x`")._repr_markdown_().startswith("**Graph `` `x` ``**")
    assert "```mermaid" not in text and "_(no entity to draw)_" in text


def test_a_drawing_past_mermaid_limits_is_left_out():
    g = dg.Graph(name="chain")
    gains = [Gain(f"g{i}") for i in range(display.MERMAID_MAX_EDGES + 2)]
    g.add(*gains)
    for a, b in itertools.pairwise(gains):
        g.plug(a.output, b.input)
    text = g._repr_markdown_()
    assert "```mermaid" not in text
    assert f"{display.MERMAID_MAX_EDGES + 1} edges, past Mermaid's default limits" in text
    assert text.count("\n| `g") == len(gains)  # the table is still there
    g.remove("g0")
    g.remove("g1")
    assert "```mermaid" in g._repr_markdown_()  # 500 edges: drawn


def test_display_imports_no_robotics_code():
    code = ("import sys\nimport dgraph as dg\nfrom dgraph.entities.operators import Gain\n"
            "g = dg.Graph(); g.add(Gain('k')); g._repr_markdown_()\n"
            "print(sorted(m for m in ('pinocchio', 'mujoco', 'proxsuite', 'rerun', 'dgraph_sim', 'IPython',"
            " 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
