"""A graph's rich display in Jupyter: a summary and its drawing, as Markdown.

:meth:`Graph._repr_markdown_ <dgraph.graph.Graph._repr_markdown_>` returns :func:`to_markdown`:
a line with the graph's name, size, period and tick, the entity-level Mermaid drawing in a
```` ```mermaid ```` block (drawn by JupyterLab >= 4.1, Notebook >= 7.1 and GitHub; other
frontends show its source), and a table of the entities with their plugged and missing inputs.
Text only: no Graphviz (``dot`` may be absent), no JavaScript, nothing evaluated.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dgraph.export import to_mermaid

if TYPE_CHECKING:
    from dgraph.graph import Graph

MERMAID_MAX_TEXT = 50_000
"""Mermaid's default ``maxTextSize``: a longer diagram is refused by the renderer."""
MERMAID_MAX_EDGES = 500
"""Mermaid's default ``maxEdges``."""


def _code(text: str) -> str:
    """``text`` as inline Markdown code, whatever backticks it holds."""
    fence = "`"
    while fence in text:
        fence += "`"
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{fence}{pad}{text}{pad}{fence}"


def _seconds(value: float) -> str:
    return f"{value:.6g} s"


def summary(graph: Graph) -> str:
    """One line: name, entities, plugs, period (and rate), the tick reached, the run length and
    the degraded ticks if any."""
    parts = [f"**Graph {_code(graph.name)}**: {len(graph)} entities, {len(graph.plugs())} plugs",
             f"dt = {_seconds(graph.dt)} ({1.0 / graph.dt:.6g} Hz)",
             f"at tick {graph.t} (t = {_seconds(graph.t * graph.dt)})"]
    if graph.duration is not None:
        parts.append(f"duration {_seconds(graph.duration)}")
    degraded = graph.fault_log.degraded_ticks
    if degraded:
        parts.append(f"{degraded} degraded ticks")
    return ", ".join(parts)


def entity_table(graph: Graph) -> str:
    """A Markdown table, one row per entity: type, inputs plugged out of all, outputs, and the
    inputs that are neither plugged, set nor defaulted (what :meth:`Graph.validate` refuses)."""
    rows = ["| entity | type | inputs plugged | outputs | missing inputs |", "|---|---|---|---|---|"]
    for entity in graph:
        inputs = list(entity.inputs.values())
        plugged = sum(inp.source is not None for inp in inputs)
        missing = [inp.name for inp in inputs if inp.source is None and not inp.is_set and not inp.has_default]
        rows.append(f"| {_code(entity.name)} | {_code(entity.type_name)} | {plugged} / {len(inputs)} "
                    f"| {len(entity.outputs)} | {', '.join(_code(m) for m in missing)} |")
    return "\n".join(rows)


def drawing(graph: Graph) -> str:
    """The entity-level Mermaid drawing as a fenced block, or a sentence saying why it is left
    out (an empty graph, or one past Mermaid's default limits)."""
    if len(graph) == 0:
        return "_(no entity to draw)_"
    text = to_mermaid(graph)
    edges = sum("-->" in line for line in text.splitlines())
    if len(text) > MERMAID_MAX_TEXT or edges > MERMAID_MAX_EDGES:
        return (f"_(drawing left out: {len(text)} characters and {edges} edges, past Mermaid's default limits "
                f"of {MERMAID_MAX_TEXT} and {MERMAID_MAX_EDGES}; use `graph.to_dot()` or `graph.to_mermaid()`)_")
    return f"```mermaid\n{text}```"


def to_markdown(graph: Graph) -> str:
    """The summary line, the drawing and the entity table, as one Markdown document."""
    return "\n\n".join([summary(graph), drawing(graph), entity_table(graph)]) + "\n"
