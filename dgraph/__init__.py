"""dgraph: lazily cached, time-stamped signal graphs for whole-body robot control.

A graph of entities whose outputs are plugged into inputs; a stateful entity (a device, an
integrator) advances one tick at a time and pulls what it needs, which computes exactly what is
stale (``tests/test_package_doc.py`` runs this example)::

    >>> import dgraph as dg
    >>> from dgraph.entities.discrete import Integrator
    >>> from dgraph.entities.operators import Constant, Gain
    >>> g = dg.Graph(dt=0.01, name="example")
    >>> rate, twice, position = g.add(Constant("rate", value=[1.0, 2.0]), Gain("twice", size=2),
    ...                               Integrator("position", size=2))
    >>> twice.gain.set(2.0)
    >>> g.plug("rate.output", "twice.input")
    >>> g.plug("twice.output", "position.input")
    >>> g.run(ticks=100)                   # 1 s: position = 2 rate t
    >>> position.output(g.t)
    array([2., 4.])
    >>> twice.output.count                 # computed once: nothing it reads has changed since
    1

Graph files (``dg.load``), the ``dgraph`` command and the TALOS graphs are in the README.
"""

from dgraph.device import Device, Hooks
from dgraph.entity import Entity, command
from dgraph.errors import (
    ComputeError,
    CycleError,
    DependencyError,
    DGraphError,
    DivergenceError,
    GraphError,
    GraphFileError,
    HookError,
    NonFiniteError,
    ParamError,
    PlugError,
    RegistryError,
    SpecError,
    UnpluggedInputError,
)
from dgraph.faults import Fault, FaultLog
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
    "DivergenceError",
    "Entity",
    "Fault",
    "FaultLog",
    "Graph",
    "GraphError",
    "GraphFileError",
    "HookError",
    "Hooks",
    "Input",
    "NonFiniteError",
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
