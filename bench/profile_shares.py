"""Where the demo loop's time goes: a py-spy sampling profile, in shares of the loop by category.

    .venv/bin/pip install -e ".[bench]"          # py-spy (or: make bench)
    .venv/bin/python bench/profile_shares.py [--ticks 3000] [--rate 250] [--raw out/profile_raw.txt]
                                             [--top 15] [--json out/profile_shares.json]

py-spy (``record -f raw``, Python frames only) samples a child process of this venv's python
that loads ``graphs/talos_sway.yaml`` (the full demo: four tasks, recorder and 3D view writing an
.rrd into a temporary directory), runs ``--warmup`` ticks, then ``--ticks`` ticks inside the
driver's function ``profiled``; only the samples taken inside it count (no imports, no loading,
no first-tick set-up). BLAS and OpenMP run on one thread, as in bench/talos_tick.py.

Each sample goes to the category of its innermost *project* frame (a file under ``dgraph/`` or
``sim/``; numpy, Pinocchio or Rerun frames below it count for the project code that called them):

- ``dgraph/control/`` (the maths layer: the QP's assembly and its ProxQP driver): **ProxQP
  (update + solve)** when that frame's source line calls ``qp.init``, ``qp.update`` or
  ``qp.solve`` (the line is read from the profiled source, so line numbers may move; if the file
  cannot be read, the functions ``solve`` of ``proxqp.py`` and ``_run`` count as ProxQP), else
  **QP assembly**; ``dgraph/entities/solvers/``: **solver entity**;
- ``dgraph/signals/``: **signal framework**; ``dgraph/entities/{features,tasks,contacts,
  references}``: **features, tasks, contacts, references**; ``.../estimators``: **estimator**;
  ``.../robot``: **robot model** (the Pinocchio pass and its accessors); ``.../recording``:
  **recorder + Rerun**; other entity families: **other entities**;
- ``sim/``: **MuJoCo step** when the source line calls ``mujoco.mj_*`` (``mj_step2``,
  ``mj_step1``, ``mj_getState``, ...), else **device (Python)**;
- the rest of ``dgraph/`` (loop, graph, entity, device hooks): **loop / graph**.

The table gives samples, the share of the loop and, from the wall time of the profiled ticks
(inflated by the sampling: py-spy pauses the process for each sample), the approximate µs per
tick of each category; the calibration line is printed from before and after the profile.
"""

from __future__ import annotations

import argparse
import json
import linecache
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import compare_commits
from calibration import calibrate, calibration_line, single_threaded_env

ROOT = Path(__file__).resolve().parents[1]
PROXQP_CALL = re.compile(r"\bqp\.(init|update|solve)\(")
MUJOCO_CALL = re.compile(r"\bmujoco\.mj_\w+\(")
FRAME = re.compile(r"^(?P<function>.*) \((?P<file>.*):(?P<line>\d+)\)$")
TASK_SIDE = "features, tasks, contacts, references"
ENTITY_FAMILIES = {"features": TASK_SIDE, "tasks": TASK_SIDE, "contacts": TASK_SIDE, "references": TASK_SIDE,
                   "estimators": "estimator", "robot": "robot model", "recording": "recorder + Rerun",
                   "solvers": "solver entity"}
CATEGORIES = ("ProxQP (update + solve)", "QP assembly", "solver entity", "signal framework",
              TASK_SIDE, "estimator", "robot model", "MuJoCo step", "device (Python)",
              "recorder + Rerun", "loop / graph", "other entities", "outside the project")
def py_spy() -> str:
    """The py-spy executable next to this python, or on PATH."""
    local = Path(sys.executable).with_name("py-spy")
    found = str(local) if local.exists() else shutil.which("py-spy")
    if found is None:
        raise SystemExit('py-spy not found: .venv/bin/pip install -e ".[bench]"')
    return found


def record(ticks: int, warmup: int, rate: int, raw: Path) -> dict[str, float]:
    """Profile the demo driver with py-spy into ``raw``; the driver's wall time of the profiled ticks."""
    env = single_threaded_env()
    env["PYTHONPATH"] = str(ROOT)
    result = raw.with_suffix(".timing.json")
    out = subprocess.run([py_spy(), "record", "-f", "raw", "-r", str(rate), "-o", str(raw), "--",
                          sys.executable, "-c", compare_commits.DRIVER, str(ticks), str(warmup), str(result)],
                         cwd=ROOT, env=env, capture_output=True, text=True)
    if out.returncode != 0 or not raw.exists() or not result.exists():
        raise SystemExit(f"py-spy or the demo failed (exit {out.returncode}):\n{out.stderr[-3000:]}")
    timing = json.loads(result.read_text())
    result.unlink()
    return timing


def parse(raw: str) -> Counter[tuple[str, ...]]:
    """py-spy raw lines (``frame;frame;... count``, outermost first) as stack -> samples."""
    stacks: Counter[tuple[str, ...]] = Counter()
    for line in raw.splitlines():
        stack, _, count = line.rpartition(" ")
        if stack and count.isdigit():
            stacks[tuple(stack.split(";"))] += int(count)
    return stacks


def project_path(file: str) -> str | None:
    """``dgraph/...`` or ``sim/...`` relative to the repository for a project file, else None."""
    path = Path(file)
    if path.is_absolute():
        try:
            path = path.resolve().relative_to(ROOT)
        except ValueError:
            return None
    return path.as_posix() if path.parts and path.parts[0] in ("dgraph", "sim") else None


def source_line(path: str, line: int) -> str | None:
    """The text of a project file's line, or None if it cannot be read."""
    text = linecache.getline(str(ROOT / path), line)
    return text or None


def categorise_frame(path: str, function: str, line: int) -> str:
    """The category of a sample whose innermost project frame is ``function`` at ``path:line``."""
    parts = path.split("/")
    if parts[:2] == ["dgraph", "control"]:
        text = source_line(path, line)
        name = function.rsplit(".", 1)[-1]
        in_proxqp = name == "_run" or (name == "solve" and path.endswith("proxqp.py"))
        calls_proxqp = in_proxqp if text is None else bool(PROXQP_CALL.search(text))
        return CATEGORIES[0] if calls_proxqp else CATEGORIES[1]
    if parts[0] == "sim":
        return "MuJoCo step" if MUJOCO_CALL.search(source_line(path, line) or "") else "device (Python)"
    if parts[1] == "signals":
        return "signal framework"
    if parts[1] == "entities" and len(parts) > 3:
        return ENTITY_FAMILIES.get(parts[2], "other entities")
    return "loop / graph"


def categorise(stack: tuple[str, ...]) -> str:
    """The category of a stack, from its innermost project frame."""
    for frame in reversed(stack):
        match = FRAME.match(frame)
        path = project_path(match["file"]) if match else None
        if path is not None:
            return categorise_frame(path, match["function"], int(match["line"]))
    return "outside the project"


def innermost_project_function(stack: tuple[str, ...]) -> str:
    """``path:function`` of the innermost project frame (for the list of heaviest functions)."""
    for frame in reversed(stack):
        match = FRAME.match(frame)
        if match and project_path(match["file"]) is not None:
            return f"{project_path(match['file'])}:{match['function']}"
    return "(outside the project)"


def shares(stacks: Counter[tuple[str, ...]]) -> tuple[Counter[str], Counter[str]]:
    """Samples per category and per innermost project function (with its category), inside ``profiled``."""
    loop = {s: n for s, n in stacks.items() if any(frame.startswith("profiled (") for frame in s)}
    by_category: Counter[str] = Counter()
    by_function: Counter[str] = Counter()
    for stack, n in loop.items():
        category = categorise(stack)
        by_category[category] += n
        by_function[f"{innermost_project_function(stack)} ({category})"] += n
    return by_category, by_function


def table(by_category: Counter[str], us_per_tick: float) -> str:
    """Markdown: category, samples, share of the loop, approximate µs per tick."""
    total = sum(by_category.values())
    lines = ["| category | samples | share of the loop | ≈ µs per tick |", "|---|---:|---:|---:|"]
    for name in CATEGORIES:
        n = by_category.get(name, 0)
        lines.append(f"| {name} | {n} | {100 * n / total:.1f} % | {us_per_tick * n / total:.0f} |")
    lines.append(f"| **loop** | **{total}** | **100 %** | **{us_per_tick:.0f}** |")
    return "\n".join(lines)


def main() -> None:
    """Profile, aggregate, print the table and the heaviest functions."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=3000, help="profiled ticks")
    parser.add_argument("--warmup", type=int, default=200, help="ticks before the profiled ones")
    parser.add_argument("--rate", type=int, default=250, help="py-spy samples per second")
    parser.add_argument("--raw", type=Path, help="keep py-spy's raw output here")
    parser.add_argument("--top", type=int, default=15, help="list the N heaviest project functions")
    parser.add_argument("--json", type=Path, help="write the numbers to this file")
    args = parser.parse_args()
    cal = calibrate()
    with tempfile.TemporaryDirectory() as tmp:
        raw = args.raw or Path(tmp) / "profile_raw.txt"
        raw.parent.mkdir(parents=True, exist_ok=True)
        timing = record(args.ticks, args.warmup, args.rate, raw)
        by_category, by_function = shares(parse(raw.read_text()))
    if not by_category:
        raise SystemExit("no sample inside the profiled loop (too few ticks for the sampling rate?)")
    cal_end = calibrate()
    us_per_tick = timing["profiled_s"] / timing["ticks"] * 1e6
    print(calibration_line(cal))
    print(calibration_line(cal_end))
    print(f"demo loop (graphs/talos_sway.yaml, recorder + 3D view), {args.ticks} ticks after {args.warmup}, "
          f"py-spy at {args.rate} Hz: {us_per_tick:.0f} µs per tick under the profiler "
          f"(real-time factor {1e3 / us_per_tick:.2f})\n")
    print(table(by_category, us_per_tick))
    total = sum(by_function.values())
    print(f"\nheaviest innermost project functions (top {args.top}):\n")
    for name, n in by_function.most_common(args.top):
        print(f"- {name}: {100 * n / total:.1f} %")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"calibration": {"start": cal, "end": cal_end}, "ticks": args.ticks,
                                         "warmup": args.warmup, "rate_hz": args.rate, "us_per_tick": us_per_tick,
                                         "samples": dict(by_category), "functions": dict(by_function)}, indent=1))


if __name__ == "__main__":
    main()
