"""Caching off must give identical results: random graphs, random read patterns (hypothesis)."""

from __future__ import annotations

import os

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import dgraph as dg
from dgraph.entities.discrete import Delay, Integrator
from dgraph.entities.operators import Add, Gain, Saturation, Switch
from dgraph.entities.references import Sinusoid
from tests.conftest import Periodic, Ticker

EXAMPLES = int(os.environ.get("DGRAPH_HYPOTHESIS_EXAMPLES", "60"))
"""Random graphs per run; raise it for a long soak (e.g. 2000)."""
KINDS = ("add", "gain", "saturation", "switch", "delay", "integrator", "periodic")


def build(plan, sources_seed: int) -> tuple[dg.Graph, list[dg.Output]]:
    """A graph from a plan: each node is (kind, parents, parameter) over earlier outputs."""
    g = dg.Graph(dt=0.01)
    g.add(Ticker("dev", x0=0.5))
    g.add(Sinusoid("sin", amplitude=1.0, frequency=3.0, phase=float(sources_seed)))
    outs: list[dg.Output] = [g["dev.x"], g["sin.output"]]
    for i, (kind, parents, param) in enumerate(plan):
        a, b = outs[parents[0] % len(outs)], outs[parents[1] % len(outs)]
        name = f"n{i}"
        if kind == "add":
            e = g.add(Add(name, coefficients=[1.0, param]))
            g.plug(a, e.in0)
            g.plug(b, e.in1)
        elif kind == "gain":
            e = g.add(Gain(name))
            e.gain.set(param)
            g.plug(a, e.input)
        elif kind == "saturation":
            e = g.add(Saturation(name))
            e.upper.set(abs(param))
            g.plug(a, e.input)
        elif kind == "switch":
            e = g.add(Switch(name))
            g.plug(a, e.in0)
            g.plug(b, e.in1)
            g.plug(g["dev.x"], g.add(Gain(f"{name}_sel")).input)  # unrelated reader
            e.selection.set(int(param > 0))
        elif kind == "delay":
            e = g.add(Delay(name, initial=param))
            g.plug(a, e.input)
        elif kind == "integrator":
            e = g.add(Integrator(name))
            g.plug(a, e.input)
        else:
            e = g.add(Periodic(name, every=1 + int(abs(param) * 3) % 4))
            g.plug(a, e.u)
        outs.append(e.output if kind != "periodic" else e.y)
    return g, outs


def trace(plan, reads, seed: int, cache: bool, changes=()) -> list[float]:
    """Read the chosen outputs each tick; at the ticks in ``changes`` set every gain constant."""
    g, outs = build(plan, seed)
    g.cache_enabled = cache
    gains = [e.gain for e in g if isinstance(e, Gain)]
    values = []
    for tick, tick_reads in enumerate(reads):
        for when, value in changes:
            if when == tick:
                for gain in gains:
                    gain.set(value)
        for r in tick_reads:
            values.append(outs[r % len(outs)](g.t))
        g.step()
    return values


node = st.tuples(st.sampled_from(KINDS), st.tuples(st.integers(0, 50), st.integers(0, 50)),
                 st.floats(-2.0, 2.0, allow_nan=False))


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plan=st.lists(node, min_size=1, max_size=14),
       reads=st.lists(st.lists(st.integers(0, 60), max_size=5), min_size=1, max_size=25),
       seed=st.integers(0, 5),
       changes=st.lists(st.tuples(st.integers(0, 25), st.floats(-2.0, 2.0, allow_nan=False)), max_size=4))
def test_cache_off_gives_identical_results(plan, reads, seed, changes):
    cached = trace(plan, reads, seed, cache=True, changes=changes)
    uncached = trace(plan, reads, seed, cache=False, changes=changes)
    assert np.array_equal(np.array(cached), np.array(uncached))


def test_cache_reduces_computations_on_a_diamond_heavy_graph():
    plan = [("add", (0, 1), 1.0)] + [("add", (i + 2, i + 2), 0.5) for i in range(10)]
    counts = {}
    for cache in (True, False):
        g, outs = build(plan, 0)
        g.cache_enabled = cache
        for _ in range(5):
            outs[-1](g.t)
            g.step()
        counts[cache] = sum(o.count for o in outs if isinstance(o, dg.Output) and not isinstance(o, dg.State))
    assert counts[True] == 5 * 12  # each node once per tick (sinusoid included)
    assert counts[False] > 100 * counts[True]  # 2^10 paths without the cache
