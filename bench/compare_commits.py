"""Real-time factor of the full demo at two commits, measured in the same run: new / old.

    .venv/bin/python bench/compare_commits.py [--base ddec0a5] [--head HEAD | --head WORKTREE]
                                              [--ticks 3000] [--repeats 3] [--json out/compare.json]

The demo is ``graphs/talos_sway.yaml`` as each commit has it (four tasks, the recorder and the 3D
view writing an .rrd into a temporary directory). Each commit is checked out with
``git worktree add --detach`` in a temporary directory (``--head WORKTREE``: this checkout as it
is, uncommitted changes included, run in place), and every run is a fresh process of this venv's
python with its cwd and ``PYTHONPATH`` set to that worktree, so it imports that commit's
``dgraph`` and ``sim`` (also as ``dgraph_sim``: :data:`CHECKOUT_IMPORTS`) and loads that commit's
graph file (the run checks where ``dgraph`` and ``dgraph_sim`` came from).

A run loads the graph, runs ``--warmup`` ticks, then times ``--ticks`` ticks plus closing the
graph (which flushes the recording): real-time factor = simulated time / wall time. Runs
alternate base / head ``--repeats`` times (A/B/A/B); the medians per commit and their ratio
(head / base: 2.0 means the head runs the demo twice as fast) are printed with the calibration
figure (bench/calibration.py) measured before and after. BLAS and OpenMP run on one thread, as
in bench/talos_tick.py. The worktrees are removed at the end, also after an error.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from calibration import calibrate, calibration_line, single_threaded_env

ROOT = Path(__file__).resolve().parents[1]
WORKTREE = "WORKTREE"
CHECKOUT_IMPORTS = r"""
import importlib, importlib.abc, importlib.util, sys

class _SimAlias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    # dgraph_sim.X is this checkout's sim.X (the installed dgraph_sim is the main checkout's sim/
    # folder, and older commits import their simulation part as sim): one module per file
    def find_spec(self, name, path=None, target=None):
        if name == "dgraph_sim" or name.startswith("dgraph_sim."):
            return importlib.util.spec_from_loader(name, self)
        return None

    def create_module(self, spec):
        return importlib.import_module("sim" + spec.name[len("dgraph_sim"):])

    def exec_module(self, module):
        pass

sys.meta_path.insert(0, _SimAlias())
"""
"""Run first in a checkout (cwd and PYTHONPATH): ``dgraph_sim`` imports that checkout's ``sim/`` folder."""
DRIVER = CHECKOUT_IMPORTS + r"""
import json, sys, tempfile, time
import dgraph as dg
import dgraph_sim
ticks, warmup = int(sys.argv[1]), int(sys.argv[2])

def profiled(graph, ticks):  # the timed ticks (bench/profile_shares.py counts the samples inside it)
    start = time.perf_counter()
    graph.run(ticks=ticks, progress=False)
    return time.perf_counter() - start

with tempfile.TemporaryDirectory() as tmp:
    rrd = f"{tmp}/talos_sway.rrd"
    graph = dg.load("graphs/talos_sway.yaml", {"recorder.rrd_path": rrd, "view.rrd_path": rrd})
    graph.run(ticks=warmup, progress=False)
    loop = profiled(graph, ticks)
    start = time.perf_counter()
    graph.close()  # flushes the recording: part of what a run costs
    wall = loop + time.perf_counter() - start
result = json.dumps({"real_time_factor": ticks * graph.dt / wall, "loop_us": wall / ticks * 1e6, "ticks": ticks,
                     "profiled_s": loop, "fallen": bool(graph["device"].fallen.value), "dgraph": dg.__file__,
                     "dgraph_sim": dgraph_sim.__file__})
if len(sys.argv) > 3:  # a file for the result (under py-spy)
    with open(sys.argv[3], "w") as f:
        f.write(result)
print(result)
"""
"""The demo run: ``python -c DRIVER TICKS WARMUP [RESULT_FILE]`` in a checkout; JSON on stdout (and
into RESULT_FILE): real-time factor and loop time with the closing, the ticks' own wall time."""


def git(*args: str) -> str:
    """Run git in this repository; its stdout, stripped."""
    return subprocess.run(["git", "-C", str(ROOT), *args], check=True, capture_output=True, text=True).stdout.strip()


def describe(commit: str) -> str:
    """``sha subject`` of a commit, or a note for the working tree."""
    if commit == WORKTREE:
        state = "uncommitted changes" if git("status", "--porcelain") else "clean"
        return f"working tree at {git('rev-parse', '--short', 'HEAD')} ({state})"
    return git("log", "-1", "--format=%h %s", commit)[:100]


@contextmanager
def checkouts(commits: list[str]) -> Iterator[dict[str, Path]]:
    """One detached worktree per commit in a temporary directory (WORKTREE: this checkout); removed after."""
    with tempfile.TemporaryDirectory(prefix="dgraph-compare-") as tmp:
        paths: dict[str, Path] = {}
        try:
            for i, commit in enumerate(commits):
                if commit == WORKTREE:
                    paths[commit] = ROOT
                    continue
                paths[commit] = Path(tmp) / f"{i}-{commit.replace('/', '_')}"
                git("worktree", "add", "--detach", str(paths[commit]), commit)
            yield paths
        finally:
            for commit, path in paths.items():
                if commit != WORKTREE:
                    subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(path)],
                                   capture_output=True)
            git("worktree", "prune")


def run_demo(tree: Path, ticks: int, warmup: int) -> dict[str, object]:
    """One timed demo run in ``tree`` (cwd and PYTHONPATH); its JSON line."""
    env = single_threaded_env()
    env["PYTHONPATH"] = str(tree)
    out = subprocess.run([sys.executable, "-c", DRIVER, str(ticks), str(warmup)], cwd=tree, env=env,
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"demo run in {tree} failed (exit {out.returncode}):\n{out.stderr[-3000:]}")
    result = json.loads(out.stdout.strip().splitlines()[-1])
    for package in ("dgraph", "dgraph_sim"):
        if not Path(result[package]).resolve().is_relative_to(tree.resolve()):
            raise RuntimeError(f"the run in {tree} imported {package} from {result[package]}")
    return result


def compare(base: str, head: str, ticks: int = 3000, repeats: int = 3, warmup: int = 200,
            log: bool = True) -> dict[str, object]:
    """Alternate base and head demo runs; medians of the real-time factor and their ratio."""
    commits = {"base": base, "head": head}
    runs: dict[str, list[dict[str, object]]] = {"base": [], "head": []}
    with checkouts(list(commits.values())) as paths:
        for repeat in range(repeats):
            for side, commit in commits.items():
                result = run_demo(paths[commit], ticks, warmup)
                runs[side].append(result)
                if log:
                    print(f"  run {repeat + 1} {side} ({commit}): real-time factor {result['real_time_factor']:.3f}",
                          flush=True)
    medians = {side: statistics.median(r["real_time_factor"] for r in rs) for side, rs in runs.items()}
    return {"base": describe(base), "head": describe(head), "ticks": ticks, "warmup": warmup,
            "repeats": repeats, "runs": runs, "median_real_time_factor": medians,
            "ratio_head_over_base": medians["head"] / medians["base"]}


def main() -> None:
    """Calibrate, compare, calibrate; print the medians and the ratio."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default="ddec0a5", help="the old commit (default ddec0a5)")
    parser.add_argument("--head", default="HEAD", help=f"the new commit, or {WORKTREE} for this checkout")
    parser.add_argument("--ticks", type=int, default=3000, help="timed ticks per run")
    parser.add_argument("--warmup", type=int, default=200, help="ticks before the timing")
    parser.add_argument("--repeats", type=int, default=3, help="runs per commit, alternating")
    parser.add_argument("--json", type=Path, help="write the numbers to this file")
    args = parser.parse_args()
    before = calibrate()
    print(calibration_line(before), flush=True)
    result = compare(args.base, args.head, args.ticks, args.repeats, args.warmup)
    after = calibrate()
    print(calibration_line(after))
    medians = result["median_real_time_factor"]
    print(f"\nfull demo (graphs/talos_sway.yaml, recorder + 3D view to .rrd), {args.ticks} ticks, "
          f"{args.repeats} runs each, alternating:")
    print(f"  base {result['base']}: median real-time factor {medians['base']:.3f}")
    print(f"  head {result['head']}: median real-time factor {medians['head']:.3f}")
    print(f"  ratio head / base: {result['ratio_head_over_base']:.2f}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({**result, "calibration": {"before": before, "after": after}}, indent=1))


if __name__ == "__main__":
    main()
