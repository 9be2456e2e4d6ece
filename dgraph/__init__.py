"""dgraph: lazily cached, time-stamped signal graphs for whole-body robot control.

The public API::

    import dgraph as dg
    g = dg.Graph(dt=0.001)
    k = g.add(dg.entities.Gain("k", size=3))
    g.plug("ref.output", "k.u")
    g.run(duration=1.0)
"""

from dgraph.device import Device, Hooks
from dgraph.entity import Entity, command
from dgraph.errors import (
    ComputeError,
    CycleError,
    DependencyError,
    DGraphError,
    GraphError,
    GraphFileError,
    HookError,
    ParamError,
    PlugError,
    RegistryError,
    SpecError,
    UnpluggedInputError,
)
from dgraph.graph import Graph, plug
from dgraph.params import Param
from dgraph.registry import entity_types, get_type, register
from dgraph.signals import VALUE_TYPES, Input, Output, Signal, Spec, State, commit_all, output, stage_views, value_type

__version__ = "0.1.0"


def load(path: str, overrides: dict[str, object] | None = None) -> Graph:
    """Build the graph described by the YAML file ``path`` (see :mod:`dgraph.files`)."""
    from dgraph.files import load as _load
    return _load(path, overrides)


def save(graph: Graph, path: str) -> None:
    """Write ``graph`` as a YAML graph file that :func:`load` reads back identically."""
    from dgraph.files import save as _save
    _save(graph, path)


__all__ = [
    "VALUE_TYPES",
    "ComputeError",
    "CycleError",
    "DGraphError",
    "DependencyError",
    "Device",
    "Entity",
    "Graph",
    "GraphError",
    "GraphFileError",
    "HookError",
    "Hooks",
    "Input",
    "Output",
    "Param",
    "ParamError",
    "PlugError",
    "RegistryError",
    "Signal",
    "Spec",
    "SpecError",
    "State",
    "UnpluggedInputError",
    "command",
    "commit_all",
    "entity_types",
    "get_type",
    "load",
    "output",
    "plug",
    "register",
    "save",
    "stage_views",
    "value_type",
]
