"""Introspection: why a signal would recompute, and where a tick's time goes.

:func:`explain` walks a signal's dependencies back to their sources and says which of them
change at the next tick. :func:`profile` runs ticks with timing on and reports, per entity,
the exclusive time per tick and the number of recomputations.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from dgraph.signals.signal import Input, Output, Signal, State

if TYPE_CHECKING:
    from dgraph.entity import Entity
    from dgraph.graph import Graph


def _upstream(sig: Signal) -> list[Signal]:
    if isinstance(sig, Input):
        return [sig.source] if sig.source is not None else []
    if isinstance(sig, State):
        return []
    return list(sig.deps) if isinstance(sig, Output) else []


def explain(graph: Graph, sig: Signal) -> str:
    """A few lines saying what ``sig`` is, when it was computed, and what will make it recompute."""
    kind = {Input: "input", State: "state"}.get(type(sig), "output")
    lines = [f"{sig.full_name}: {kind} {sig.spec!r}, last stamp t={sig.time}"]
    if isinstance(sig, Input):
        if sig.source is not None:
            lines.append(f"  plugged to {sig.source.full_name}")
            return "\n".join(lines + ["  " + line for line in explain(graph, sig.source).splitlines()])
        status = "holds a constant set by the user" if sig.is_set else (
            "uses its default" if sig.has_default else "is UNPLUGGED: reading it raises")
        return "\n".join([*lines, f"  {status}; a constant changes only when set again"])
    if isinstance(sig, State):
        moves = sig.entity.has_state
        lines.append(f"  state of {sig.entity.name} ({sig.entity.type_name}): set by the entity"
                     + (" at every tick transition" if moves else " only"))
        return "\n".join(lines)
    assert isinstance(sig, Output)
    status = "STALE: the next read recomputes" if sig.stale else "fresh: the next read at the same tick is cached"
    lines.append(f"  computed {sig.count} time(s); period {sig.period}; {status}")
    reasons: list[str] = []
    constants: list[str] = []
    seen: set[int] = set()
    stack: list[Signal] = [sig]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, Output) and node.time_varying:
            reasons.append(f"{node.full_name} depends on time")
        if isinstance(node, State) and node.entity.has_state:
            reasons.append(f"{node.full_name} is the state of {node.entity.name}, committed every tick")
        if isinstance(node, Input) and node.source is None:
            (constants if node.is_set or node.has_default else reasons).append(
                node.full_name if (node.is_set or node.has_default) else f"{node.full_name} is unplugged")
        stack.extend(_upstream(node))
    if reasons:
        lines.append("  will recompute at the next tick because:")
        lines.extend(f"    - {r}" for r in sorted(reasons))
        if sig.period > 1:
            lines.append(f"    (once per {sig.period}-tick window: the next starts at tick {sig.next_sample()})")
    else:
        lines.append("  will NOT recompute at the next tick: nothing it depends on changes by itself")
    if constants:
        lines.append(f"  constants upstream (recompute only when set): {', '.join(sorted(constants))}")
    return "\n".join(lines)


@dataclass
class EntityProfile:
    """Per-entity share of a profiled run."""

    name: str
    type_name: str
    us_per_tick: float
    computations_per_tick: float


@dataclass
class Profile:
    """Result of :func:`profile`: per-entity exclusive time and recomputations per tick."""

    ticks: int
    us_per_tick: float
    entities: list[EntityProfile] = field(default_factory=list)

    def __str__(self) -> str:
        rows = [f"{self.ticks} ticks, {self.us_per_tick:.1f} us per tick (wall clock)",
                f"{'entity':<20} {'type':<18} {'us/tick':>9} {'share':>6} {'computed/tick':>14}"]
        for e in sorted(self.entities, key=lambda e: -e.us_per_tick):
            share = 100 * e.us_per_tick / self.us_per_tick if self.us_per_tick else 0.0
            rows.append(f"{e.name:<20} {e.type_name:<18} {e.us_per_tick:>9.2f} {share:>5.1f}% "
                        f"{e.computations_per_tick:>14.2f}")
        return "\n".join(rows)


def profile(graph: Graph, ticks: int) -> Profile:
    """Run ``ticks`` ticks with timing on and return where the time went.

    Time spent in an output excludes the upstream outputs it pulls; time in a stateful
    entity's ``prepare_state``/``commit_state`` excludes the outputs computed inside them.
    """
    from dgraph.loop import step

    clock = graph.clock
    outputs = [(e, o) for e in graph for o in e.outputs.values()]
    counts0 = {id(o): o.count for _, o in outputs}
    for _, o in outputs:
        o.total_duration = 0.0
    own: dict[str, float] = {e.name: 0.0 for e in graph}

    def timed(entity: Entity, phase: str, t: int) -> None:
        clock.inner = 0.0
        start = time.perf_counter()
        getattr(entity, phase)(t)
        own[entity.name] += time.perf_counter() - start - clock.inner

    clock.profiling = True
    start = time.perf_counter()
    try:
        for _ in range(ticks):
            step(graph, timed)
    finally:
        clock.profiling = False
    wall = time.perf_counter() - start
    n = max(ticks, 1)
    result = Profile(ticks, 1e6 * wall / n)
    for entity in graph:
        mine = [o for e, o in outputs if e is entity]
        seconds = own[entity.name] + sum(o.total_duration for o in mine)
        computed = sum(o.count - counts0[id(o)] for o in mine)
        result.entities.append(EntityProfile(entity.name, entity.type_name, 1e6 * seconds / n, computed / n))
    return result
