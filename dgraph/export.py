"""Drawings of a graph: Graphviz dot and Mermaid, at entity level or at signal level.

Entity level: one node per entity (name and type), one edge per plug labelled
``output -> input``. Signal level: one cluster (subgraph) per entity holding its ports;
plugs are solid edges, dependencies inside an entity dashed, states drawn as boxes.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from dgraph.signals.signal import Input, Output, State

if TYPE_CHECKING:
    from dgraph.graph import Graph


_MERMAID_BRACKETS = {Input: ("([", "])"), State: ("[[", "]]")}


def _node_id(name: str) -> str:
    return "n_" + re.sub(r"[^A-Za-z0-9_]", "_", name)


def _entity_edges(graph: Graph) -> dict[tuple[str, str], list[str]]:
    edges: dict[tuple[str, str], list[str]] = {}
    for src, dst in graph.plugs():
        key = (src.split(".")[0], dst.split(".")[0])
        edges.setdefault(key, []).append(f"{src.split('.')[1]} -> {dst.split('.')[1]}")
    return edges


def _internal_edges(graph: Graph) -> list[tuple[str, str]]:
    return [(dep.full_name, sig.full_name) for e in graph for sig in e.outputs.values()
            if isinstance(sig, Output) for dep in sig.deps]


def to_dot(graph: Graph, signals: bool = False) -> str:
    """Graphviz source of ``graph``."""
    out = [f'digraph "{graph.name}" {{', "  rankdir=LR;", '  node [fontname="Helvetica"];']
    if not signals:
        for e in graph:
            out.append(f'  {_node_id(e.name)} [shape=box, style=rounded, label="{e.name}\\n({e.type_name})"];')
        for (a, b), labels in _entity_edges(graph).items():
            label = "\\n".join(labels)
            out.append(f'  {_node_id(a)} -> {_node_id(b)} [label="{label}"];')
    else:
        for e in graph:
            out.append(f'  subgraph "cluster_{e.name}" {{')
            out.append(f'    label="{e.name} ({e.type_name})"; style=rounded;')
            for sig in e.ports.values():
                shape = {Input: "ellipse", State: "box"}.get(type(sig), "box")
                style = ', style="filled", fillcolor="#eeeeee"' if isinstance(sig, State) else ""
                out.append(f'    {_node_id(sig.full_name)} [shape={shape}{style}, label="{sig.name}"];')
            out.append("  }")
        for src, dst in graph.plugs():
            out.append(f"  {_node_id(src)} -> {_node_id(dst)};")
        for src, dst in _internal_edges(graph):
            out.append(f"  {_node_id(src)} -> {_node_id(dst)} [style=dashed];")
    out.append("}")
    return "\n".join(out) + "\n"


def to_mermaid(graph: Graph, signals: bool = False) -> str:
    """Mermaid flowchart source of ``graph``."""
    out = ["flowchart LR"]
    if not signals:
        for e in graph:
            out.append(f'  {_node_id(e.name)}["{e.name}<br/>({e.type_name})"]')
        for (a, b), labels in _entity_edges(graph).items():
            out.append(f'  {_node_id(a)} -- "{"<br/>".join(labels)}" --> {_node_id(b)}')
    else:
        for e in graph:
            out.append(f'  subgraph {_node_id(e.name)}["{e.name} ({e.type_name})"]')
            for sig in e.ports.values():
                left, right = _MERMAID_BRACKETS.get(type(sig), ("[", "]"))
                out.append(f'    {_node_id(sig.full_name)}{left}"{sig.name}"{right}')
            out.append("  end")
        for src, dst in graph.plugs():
            out.append(f"  {_node_id(src)} --> {_node_id(dst)}")
        for src, dst in _internal_edges(graph):
            out.append(f"  {_node_id(src)} -.-> {_node_id(dst)}")
    return "\n".join(out) + "\n"
