"""The Drake peer of the chain benchmark, run with an interpreter that has pydrake.

    python bench/peer_drake.py 10 100 1000 10000   -> JSON {n: {recompute_us, cached_read_us}}

A chain of n scalar ``Gain`` systems (k = 1) in one Diagram. Each tick fixes the diagram
input to a new value (Drake invalidates the downstream cache entries) and evaluates the
output port (the chain recomputes in C++); a cached read evaluates it again unchanged.
Medians over 7 repeats, like bench/signal_overhead.py.
"""

from __future__ import annotations

import itertools
import json
import statistics
import sys
import time

from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import Gain

REPEATS = 7


def measure(n: int) -> dict[str, float]:
    builder = DiagramBuilder()
    gains = [builder.AddSystem(Gain(1.0, 1)) for _ in range(n)]
    for a, b in itertools.pairwise(gains):
        builder.Connect(a.get_output_port(), b.get_input_port())
    builder.ExportInput(gains[0].get_input_port())
    builder.ExportOutput(gains[-1].get_output_port())
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    inp, out = diagram.get_input_port(0), diagram.get_output_port(0)
    ticks = max(5, min(2000, 200000 // n))
    tick_times, read_times = [], []
    value = 0.0
    for _ in range(REPEATS):
        start = time.perf_counter()
        for _ in range(ticks):
            value += 1.0
            inp.FixValue(context, [value])
            out.Eval(context)
        tick_times.append((time.perf_counter() - start) / ticks)
        start = time.perf_counter()
        for _ in range(20000):
            out.Eval(context)
        read_times.append((time.perf_counter() - start) / 20000)
    tick = statistics.median(tick_times)
    return {"tick_us": 1e6 * tick, "recompute_us": 1e6 * tick / n,
            "cached_read_us": 1e6 * statistics.median(read_times)}


if __name__ == "__main__":
    print(json.dumps({n: measure(int(n)) for n in sys.argv[1:]}))
