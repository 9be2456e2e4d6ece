"""Signal overhead: cost per recomputed signal and per cached read, 10 .. 10,000 signals.

    python bench/signal_overhead.py [--sizes 10 100 1000 10000] [--peer PYTHON]

For each topology (bench/topologies.py) and size: every tick sets the source state (as a
device commit does) and pulls the sink(s). Reported: the median over repeats of
  * recompute: µs per recomputed signal (tick time / signals recomputed per tick),
  * tick: µs per tick, which must follow the number of stale signals, not the graph size
    (``partial`` has 10 stale signals whatever its size),
  * cached read: µs per read of an up-to-date output.
With ``--peer``, the same chain is measured in Drake's systems framework (C++ caching,
read from Python through pydrake) by bench/peer_drake.py run with that interpreter.
The 10,000-deep chain runs under the default recursion limit (evaluation is iterative).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from calibration import calibrate, calibration_line
from topologies import TOPOLOGIES

REPEATS = 7


def measure(build, n: int, check_values: bool, ticks: int) -> dict[str, float]:
    bench = build(n)
    bench.graph.check_values = check_values
    src, pulled = bench.source, bench.pulled
    for sig in pulled:  # first computation outside the timing
        sig(0)
    tick_times, counts = [], []
    t = 0
    for _ in range(REPEATS):
        before = sum(o.count for e in bench.graph for o in e.outputs.values())
        start = time.perf_counter()
        for _ in range(ticks):
            t += 1
            src.set(float(t), t)
            for sig in pulled:
                sig(t)
        tick_times.append((time.perf_counter() - start) / ticks)
        counts.append((sum(o.count for e in bench.graph for o in e.outputs.values()) - before) / ticks)
    assert all(c == bench.stale_per_tick for c in counts), (counts, bench.stale_per_tick)
    reads = 20000
    read_times = []
    sink = pulled[-1]
    for _ in range(REPEATS):
        start = time.perf_counter()
        for _ in range(reads):
            sink(t)
        read_times.append((time.perf_counter() - start) / reads)
    tick = statistics.median(tick_times)
    return {"tick_us": 1e6 * tick, "recompute_us": 1e6 * tick / bench.stale_per_tick,
            "cached_read_us": 1e6 * statistics.median(read_times), "stale": bench.stale_per_tick}


def run_peer(python: str, n: int) -> dict[str, float] | str:
    """The Drake chain of size n in its own process; a crash is reported, not raised."""
    script = Path(__file__).with_name("peer_drake.py")
    out = subprocess.run([python, str(script), str(n)], capture_output=True, text=True)
    if out.returncode != 0:
        return f"crashed (exit {out.returncode})"
    return json.loads(out.stdout)[str(n)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 10000])
    parser.add_argument("--peer", help="python interpreter with pydrake, for the Drake chain")
    args = parser.parse_args()
    print(f"# signal overhead; {calibration_line(calibrate())}")
    print(f"# median of {REPEATS} repeats; µs")
    rows = []
    for name, build in TOPOLOGIES.items():
        for n in args.sizes:
            ticks = max(5, min(2000, 200000 // n))
            for check in (True, False):
                r = measure(build, n, check, ticks)
                rows.append((name, n, check, r))
                print(f"{name:<8} n={n:<6} check_values={'on ' if check else 'off'} stale/tick={r['stale']:<6} "
                      f"tick={r['tick_us']:10.1f}  recompute={r['recompute_us']:6.3f}  "
                      f"cached read={r['cached_read_us']:6.3f}", flush=True)
    if args.peer:
        print("# chain, dgraph (check_values on) vs Drake (pydrake) in the same run")
        for n in args.sizes:
            ours = next(r for name, size, check, r in rows if name == "chain" and size == n and check)
            theirs = run_peer(args.peer, n)
            if isinstance(theirs, str):
                print(f"chain n={n:<6} drake {theirs}")
                continue
            print(f"chain n={n:<6} recompute: dgraph {ours['recompute_us']:.3f} / drake {theirs['recompute_us']:.3f}"
                  f" = {ours['recompute_us'] / theirs['recompute_us']:.1f}x | cached read: dgraph "
                  f"{ours['cached_read_us']:.3f} / drake {theirs['cached_read_us']:.3f} = "
                  f"{ours['cached_read_us'] / theirs['cached_read_us']:.2f}x")


if __name__ == "__main__":
    main()  # evaluation is iterative: the 10,000-deep chain needs no larger stack or recursion limit
