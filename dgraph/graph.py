"""The graph: a pool of uniquely named entities, their plugs, and the tick they are at.

``Graph`` owns the clock shared by its signals, refuses plugs that would close an algebraic
loop (only a :class:`~dgraph.State` -- device state or ``Delay`` memory -- may close one),
validates the whole graph, and drives the device loop (:mod:`dgraph.loop`).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Collection, Iterable, Iterator
from typing import Any

import networkx as nx

from dgraph.entity import Entity
from dgraph.errors import CycleError, GraphError, PlugError
from dgraph.faults import FaultLog
from dgraph.signals.clock import Clock
from dgraph.signals.dependency_check import set_checking
from dgraph.signals.signal import Input, Output, Signal, State


class Graph:
    """A control graph.

    Args:
        dt: control period in seconds (1 ms for a humanoid at 1 kHz).
        name: used in recordings and exports.

    Attributes:
        t: the tick the loop is at (the device state is stamped ``t``).
        fault_log: the faults of the ticks run so far (:class:`~dgraph.faults.FaultLog`): which
            ticks were degraded, by what, and what was done instead.
        duration: default run length in seconds (from the graph file), or None.
    """

    def __init__(self, dt: float = 0.001, name: str = "graph"):
        try:
            self.dt = float(dt)
        except (TypeError, ValueError, OverflowError):
            raise GraphError(f"dt must be a number, got {dt!r}") from None
        if not (self.dt > 0 and math.isfinite(self.dt)):
            raise GraphError(f"dt must be positive and finite, got {dt!r}")
        self.name = name
        self.clock = Clock()
        self.t = 0
        self.duration: float | None = None
        self._fault_log = FaultLog()
        self._entities: dict[str, Entity] = {}
        self._roles: dict[str, list[Any]] | None = None
        self._check_dependencies = False

    # -- entities -------------------------------------------------------------------------
    def add(self, *entities: Entity) -> Any:
        """Add entities (names must be unique); returns the entity (or the tuple) given."""
        for entity in entities:
            if not isinstance(entity, Entity):
                raise GraphError(f"graph.add expects entities, got {entity!r}")
            if entity.name in self._entities:
                raise GraphError(f"an entity named {entity.name!r} is already in the graph",
                                 entity=entity.name)
            if entity.graph is not None:
                raise GraphError(f"entity {entity.name!r} already belongs to a graph", entity=entity.name)
        for entity in entities:
            entity._attach_clock(self.clock)
            entity.graph = self
            self._entities[entity.name] = entity
        if self._check_dependencies:
            set_checking(self._computed_outputs(entities), True)
        self._roles = None
        return entities[0] if len(entities) == 1 else entities

    def remove(self, name: str) -> Entity:
        """Unplug every port of entity ``name`` and take it out of the graph."""
        entity = self.entity(name)
        mine = list(entity.ports.values())
        for sig in mine:
            if isinstance(sig, Input):
                sig.unplug()
            elif isinstance(sig, Output):
                for inp in sig.plugged_inputs:
                    inp.unplug()
        set_checking(self._computed_outputs([entity]), False)
        self.clock.forget([s for s in mine if isinstance(s, Output)])
        for sig in mine:
            if isinstance(sig, Output) and sig._held:
                sig.release_hold()  # its readers must not keep a held value forever
        del self._entities[name]
        entity.graph = None
        entity._attach_clock(Clock())
        self._roles = None
        return entity

    @property
    def entities(self) -> dict[str, Entity]:
        """Entities by name, in insertion order."""
        return dict(self._entities)

    def __iter__(self) -> Iterator[Entity]:
        return iter(self._entities.values())

    def __len__(self) -> int:
        return len(self._entities)

    def __contains__(self, name: str) -> bool:
        return name in self._entities

    def entity(self, name: str) -> Entity:
        """The entity called ``name``."""
        try:
            return self._entities[name]
        except KeyError:
            raise GraphError(f"no entity named {name!r} in the graph", entity=name) from None

    def __getitem__(self, key: str) -> Any:
        """``graph["entity"]`` is an entity, ``graph["entity.signal"]`` a signal."""
        if "." not in key:
            return self.entity(key)
        entity, _, signal = key.partition(".")
        return self.entity(entity).signal(signal)

    def signal(self, key: str | Signal) -> Signal:
        """Resolve ``"entity.signal"`` (or pass a signal through after checking it belongs here)."""
        if isinstance(key, Signal):
            if key.entity is None or key.entity.graph is not self:
                raise GraphError(f"signal {key.full_name} is not in this graph")
            return key
        if not isinstance(key, str) or key.count(".") != 1:
            raise GraphError(f"expected 'entity.signal', got {key!r}",
                             entity=key.split(".")[0] if isinstance(key, str) else None)
        return self[key]

    # -- plugs ----------------------------------------------------------------------------
    def plug(self, source: str | Output, target: str | Input) -> None:
        """Plug output ``source`` into input ``target`` (names or signals).

        Refused with :class:`PlugError` on a shape/dtype mismatch or a wrong direction, and
        with :class:`CycleError` (listing the loop) if it would close an algebraic loop.
        """
        out = self.signal(source)
        inp = self.signal(target)
        if not isinstance(out, Output):
            raise PlugError(f"cannot plug from {out.full_name}: it is an input", entity=out.entity.name,
                            signal=out.name)
        if not isinstance(inp, Input):
            raise PlugError(f"cannot plug into {inp.full_name}: it is an output", entity=inp.entity.name,
                            signal=inp.name)
        cycle = _find_loop(out, inp)
        if cycle:
            raise CycleError(f"plugging {out.full_name} -> {inp.full_name} closes a loop with no Delay "
                             f"or device state on it: {' -> '.join(cycle)}", cycle,
                             entity=inp.entity.name, signal=inp.name)
        inp.plug(out)

    def unplug(self, target: str | Input) -> None:
        """Disconnect input ``target`` from its source."""
        inp = self.signal(target)
        if not isinstance(inp, Input):
            raise PlugError(f"{inp.full_name} is not an input", entity=inp.entity.name, signal=inp.name)
        inp.unplug()

    def plugs(self) -> list[tuple[str, str]]:
        """Every plug as ``(source, target)`` full names, in entity order."""
        return [(inp.source.full_name, inp.full_name) for e in self for inp in e.inputs.values()
                if inp.source is not None]

    # -- switches -------------------------------------------------------------------------
    @property
    def cache_enabled(self) -> bool:
        """False makes every read recompute; results must not change (a debugging aid)."""
        return self.clock.cache_enabled

    @cache_enabled.setter
    def cache_enabled(self, enabled: bool) -> None:
        self.clock.cache_enabled = bool(enabled)
        for entity in self:
            for sig in entity.outputs.values():
                if not isinstance(sig, State):
                    sig._stale = True

    @property
    def check_values(self) -> bool:
        """Debug switch: check every computed value against its spec (shape, NaN, inf). Off by default:
        shapes are checked when plugging, and what acts on the world checks what it consumes every
        tick (a device its command, a solver its QP data), falling back safely with a status."""
        return self.clock.check_values

    @check_values.setter
    def check_values(self, enabled: bool) -> None:
        self.clock.check_values = bool(enabled)

    @property
    def check_dependencies(self) -> bool:
        """Debug mode: an output reading a port it did not declare raises DependencyError."""
        return self._check_dependencies

    @check_dependencies.setter
    def check_dependencies(self, enabled: bool) -> None:
        self._check_dependencies = bool(enabled)
        set_checking(self._computed_outputs(), self._check_dependencies)

    def _computed_outputs(self, entities: Iterable[Entity] | None = None) -> list[Output]:
        return [o for e in (self if entities is None else entities) for o in e.outputs.values()
                if not isinstance(o, State)]

    # -- structure --------------------------------------------------------------------------
    def signal_graph(self) -> nx.DiGraph:
        """The signal-level dependency graph (nodes: full names; edges: data flow).

        Edge attribute ``kind`` is ``plug`` (output -> input) or ``dep`` (inside an entity).
        """
        g = nx.DiGraph()
        for entity in self:
            for sig in entity.ports.values():
                g.add_node(sig.full_name, entity=entity.name, signal=sig.name, kind=type(sig).__name__)
            for sig in entity.ports.values():
                if isinstance(sig, Input) and sig.source is not None:
                    g.add_edge(sig.source.full_name, sig.full_name, kind="plug")
                if isinstance(sig, Output):
                    for dep in sig.deps:
                        g.add_edge(dep.full_name, sig.full_name, kind="dep")
        return g

    def problems(self, reported: Collection[str] = ()) -> list[str]:
        """Everything :meth:`validate` would complain about, one line each; ``reported``: full
        names of inputs whose missing source was already reported (a plug the loader refused)."""
        found: list[str] = []
        for entity in self:
            for inp in entity.inputs.values():
                if inp.source is None and not inp.is_set and not inp.has_default:
                    if inp.full_name not in reported:
                        found.append(f"input {inp.full_name} is not plugged, not set and has no default")
                elif inp.source is not None and not inp.spec.accepts(inp.source.spec):
                    found.append(f"{inp.source.full_name} {inp.source.spec!r} does not fit "
                                 f"{inp.full_name} {inp.spec!r}")
            found.extend(f"{entity.name}: {p}" for p in entity.check())
        signals = self.signal_graph()
        if not nx.is_directed_acyclic_graph(signals):  # linear; find_cycle alone is quadratic on long chains
            cycle = nx.find_cycle(signals)
            found.append("algebraic loop: " + " -> ".join(e[0] for e in cycle))
        return found

    def validate(self) -> None:
        """Raise :class:`GraphError` listing every problem (unplugged inputs, mismatches, loops)."""
        found = self.problems()
        if found:
            raise GraphError(f"graph {self.name!r} is not valid:\n  " + "\n  ".join(found))

    def to_dot(self, signals: bool = False) -> str:
        """Graphviz dot source, at entity level or (``signals=True``) at signal level."""
        from dgraph.export import to_dot
        return to_dot(self, signals)

    def to_mermaid(self, signals: bool = False) -> str:
        """Mermaid flowchart source, at entity or signal level."""
        from dgraph.export import to_mermaid
        return to_mermaid(self, signals)

    def _repr_markdown_(self) -> str:
        """Jupyter's rich display: a summary, the Mermaid drawing and the entities
        (:func:`dgraph.display.to_markdown`); text only, nothing is evaluated."""
        from dgraph.display import to_markdown
        return to_markdown(self)

    def explain(self, key: str | Signal) -> str:
        """Why ``entity.signal`` would or would not recompute at the next tick."""
        from dgraph.introspect import explain
        return explain(self, self.signal(key))

    def profile(self, ticks: int = 1000) -> Any:
        """Run ``ticks`` ticks with timing on; returns a :class:`dgraph.introspect.Profile`."""
        from dgraph.introspect import profile
        return profile(self, ticks)

    # -- loop -----------------------------------------------------------------------------
    @property
    def fault_log(self) -> FaultLog:
        """The faults of the ticks run so far (one log per graph: ``fault_log.clear()`` forgets them)."""
        return self._fault_log

    def roles(self) -> dict[str, Any]:
        """What the loop treats specially: ``devices``, ``stateful`` and ``observers`` entities,
        ``periodic`` outputs (sampled by the loop at the start of each period window) and the
        ``faults`` log."""
        if self._roles is None:
            from dgraph.device import Device
            ents = list(self)
            self._roles = {
                "devices": [e for e in ents if isinstance(e, Device)],
                "stateful": [e for e in ents if e.has_state],
                "observers": [e for e in ents if e.observes],
                "commit": [e for e in ents if e.has_state] + [e for e in ents if e.observes and not e.has_state],
                "faults": self._fault_log,
                "periodic": [o for o in self._computed_outputs() if o.period > 1],
            }
        return self._roles

    def step(self) -> None:
        """Advance one tick (see :func:`dgraph.loop.step`)."""
        from dgraph.loop import step
        step(self)

    def run(self, ticks: int | None = None, duration: float | None = None,
            progress: bool | None = None) -> None:
        """Run ``ticks`` ticks or ``duration`` seconds (see :func:`dgraph.loop.run`)."""
        from dgraph.loop import run
        run(self, ticks=ticks, duration=duration, progress=progress)

    def close(self) -> None:
        """Close every entity that holds resources (recorders flush their files).

        Every entity is closed even if one fails; the first failure is then raised, as a
        :class:`GraphError` naming the entity (so one bad file never loses the others).
        """
        failures: list[tuple[str, Exception]] = []
        for entity in self:
            closer = getattr(entity, "close", None)
            if callable(closer):
                try:
                    closer()
                except Exception as exc:
                    failures.append((entity.name, exc))
        if failures:
            name, exc = failures[0]
            others = f" (and {len(failures) - 1} more)" if len(failures) > 1 else ""
            raise GraphError(f"closing {name} failed: {type(exc).__name__}: {exc}{others}", entity=name) from exc

    def __enter__(self) -> Graph:
        return self

    def __exit__(self, *exc: object) -> None:
        """Leaving a ``with`` block closes the graph, even after an error (recordings are kept)."""
        self.close()

    def __repr__(self) -> str:
        return f"<Graph {self.name!r}: {len(self)} entities, {len(self.plugs())} plugs, t={self.t}, dt={self.dt}>"


def plug(source: Output, target: Input) -> None:
    """Plug ``source`` into ``target``; both entities must be in the same graph."""
    for sig in (source, target):
        if not isinstance(sig, Signal) or sig.entity is None:
            raise PlugError(f"plug expects signals of entities, got {sig!r}")
    graph = source.entity.graph
    if graph is None or target.entity.graph is not graph:
        raise PlugError(f"cannot plug {source.full_name} -> {target.full_name}: both entities must "
                        "first be added to the same graph (graph.add(...))",
                        entity=target.entity.name, signal=target.name)
    graph.plug(source, target)


def _find_loop(out: Output, inp: Input) -> list[str]:
    """If plugging ``out`` -> ``inp`` closes a loop, the signals on it; else an empty list.

    Breadth-first search downstream of ``inp`` along the dependency links (States have none,
    which is what makes a loop through a State legal).
    """
    parent: dict[int, Output | None] = {}
    queue: deque[Output] = deque()
    for sub in inp._subs:
        if id(sub) not in parent:
            parent[id(sub)] = None
            queue.append(sub)
    found = None
    while queue:
        node = queue.popleft()
        if node is out:
            found = node
            break
        for nxt in node._down:
            if id(nxt) not in parent:
                parent[id(nxt)] = node
                queue.append(nxt)
    if found is None:
        return []
    chain: list[Output] = []
    node: Output | None = found
    while node is not None:
        chain.append(node)
        node = parent[id(node)]
    chain.reverse()
    names = [out.full_name, inp.full_name]
    for prev, node in zip([None, *chain], chain, strict=False):
        if prev is not None:
            via = [i for i in prev._plugged if node in i._subs]
            if via:
                names.append(via[0].full_name)
        names.append(node.full_name)
    return names
