"""Benchmark graphs of trivial signals: chains, diamonds, fan-outs and a mostly-static graph.

Every topology is fed by one device-like state that changes every tick and returns the
signals to pull per tick and how many signals each tick recomputes.
"""

from __future__ import annotations

from dataclasses import dataclass

import dgraph as dg

STALE_IN_PARTIAL = 10


class Source(dg.Entity):
    """A state set by the benchmark loop, as a device would."""

    x = dg.State(shape=(), initial=0.0)


class Copy(dg.Entity):
    """y = u: the trivial signal whose overhead is measured."""

    u = dg.Input(shape=())

    @dg.output(shape=(), depends=("u",))
    def y(self, t: int) -> float:
        return self.u(t)


class Join(dg.Entity):
    """s = a + b (the bottom of a diamond)."""

    a = dg.Input(shape=())
    b = dg.Input(shape=())

    @dg.output(shape=(), depends=("a", "b"))
    def s(self, t: int) -> float:
        return self.a(t) + self.b(t)


@dataclass
class Bench:
    graph: dg.Graph
    source: dg.State
    pulled: list[dg.Output]
    stale_per_tick: int


def _copy(g: dg.Graph, name: str, upstream: dg.Output) -> dg.Output:
    e = g.add(Copy(name))
    g.plug(upstream, e.u)
    return e.y


def chain(n: int) -> Bench:
    g = dg.Graph()
    src = g.add(Source("src")).x
    last = src
    for i in range(n):
        last = _copy(g, f"c{i}", last)
    return Bench(g, src, [last], n)


def diamond(n: int) -> Bench:
    """n // 4 diamonds in series: top, left, right, bottom (4 signals each)."""
    g = dg.Graph()
    src = g.add(Source("src")).x
    last = src
    for i in range(n // 4):
        top = _copy(g, f"top{i}", last)
        left, right = _copy(g, f"left{i}", top), _copy(g, f"right{i}", top)
        join = g.add(Join(f"bottom{i}"))
        g.plug(left, join.a)
        g.plug(right, join.b)
        last = join.s
    return Bench(g, src, [last], 4 * (n // 4))


def fanout(n: int) -> Bench:
    g = dg.Graph()
    src = g.add(Source("src")).x
    leaves = [_copy(g, f"leaf{i}", src) for i in range(n)]
    return Bench(g, src, leaves, n)


def partial(n: int) -> Bench:
    """A graph of n signals of which only STALE_IN_PARTIAL change each tick.

    A constant feeds a chain of n - STALE_IN_PARTIAL - 1 signals; the source feeds a chain of
    STALE_IN_PARTIAL - 1; a join reads both. The constant part is never recomputed.
    """
    g = dg.Graph()
    src = g.add(Source("src")).x
    static = g.add(Copy("static0"))
    static.u.set(1.0)
    s = static.y
    for i in range(1, n - STALE_IN_PARTIAL):
        s = _copy(g, f"static{i}", s)
    moving = src
    for i in range(STALE_IN_PARTIAL - 1):
        moving = _copy(g, f"moving{i}", moving)
    join = g.add(Join("join"))
    g.plug(moving, join.a)
    g.plug(s, join.b)
    return Bench(g, src, [join.s], STALE_IN_PARTIAL)


TOPOLOGIES = {"chain": chain, "diamond": diamond, "fanout": fanout, "partial": partial}
