"""Fuzzing the graph-file loader (issue 12: a loader that cannot hang).

The shipped graph files, mutated (bytes flipped, deleted or inserted, lines duplicated, cut or
re-indented, YAML tokens put in, values replaced by hostile ones: aliases, huge numbers,
``.inf``, NUL bytes, control characters, long strings, deep nesting, unicode, paths to
``/dev/zero``, FIFOs, sockets, directories and symlink loops), are loaded with
:func:`dgraph.files.load` and :func:`dgraph.files.check` (what ``dgraph run`` and
``dgraph check`` call). Each must build, or raise a located :class:`~dgraph.errors.GraphFileError`,
within ``BUDGET`` seconds (``BUILD_BUDGET`` for a TALOS file, whose build makes a MuJoCo device
and Pinocchio models, 0.2-0.4 s here: the margin is for a slow day on a shared machine): no
other exception escapes and nothing hangs (a case still running after ``DEADLINE`` seconds is
stopped and reported).

The cases come from a fixed seed, so every run tries the same ones: ``CASES`` of them, most on
the small ``pd_double_integrator.yaml``, some on the TALOS files (built with their MuJoCo and
Pinocchio models, loaded once beforehand). A longer run, or other cases::

    DGRAPH_FUZZ_CASES=5000 .venv/bin/pytest -q tests/test_files_fuzz.py
    DGRAPH_FUZZ_SEED=7 DGRAPH_FUZZ_CASES=5000 .venv/bin/pytest -q tests/test_files_fuzz.py

A failure lists the cases that failed, each with what was done to which file and the path of
the mutated text, kept in the test's temporary folder.
"""

from __future__ import annotations

import math
import os
import random
import re
import signal
import socket
import time
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
import yaml

import dgraph as dg
from dgraph.files import MAX_BYTES
from dgraph.registry import entity_types

ROOT = Path(__file__).resolve().parents[1]
GRAPHS = ROOT / "graphs"
SEED = int(os.environ.get("DGRAPH_FUZZ_SEED", "12"))
CASES = int(os.environ.get("DGRAPH_FUZZ_CASES", "600"))
BUDGET = 1.0
"""Seconds one case of the small file may take."""
BUILD_BUDGET = 5.0
"""Seconds one case of a TALOS file may take."""
DEADLINE = 10.0
"""Seconds after which a case is taken to hang, and stopped."""
SMALL = "pd_double_integrator.yaml"
TALOS = ["talos_standing.yaml", "talos_sway.yaml", "talos_push_tank.yaml", "talos_push_no_tank.yaml",
         "talos_ik_position.yaml", "talos_tsid_position.yaml", "base/talos.yaml"]
TALOS_SHARE = 0.08

HOSTILE_PATHS = ["/dev/zero", "fifo.csv", "fifo.yaml", "loop.csv", "loop.yaml", "dir.yaml", "sock.csv",
                 "empty.csv", "big.yaml", "zero.yaml", "/proc/self/environ", "/proc/kmsg", "/etc/passwd", "/",
                 "..", "../" * 40 + "etc/hostname", "data/push_force.csv", "base/talos.yaml", "/tmp",
                 '"fifo\\0.csv"', '"a\\0.yaml"', "'x\x01.yaml'", "\u202e.yaml", "😀.csv"]
PLAIN_PATHS = [*(path for path in HOSTILE_PATHS if path[0] not in "'\""), "fifo\0.csv", "a\0.yaml", "x\x01.yaml"]
"""The paths as Python strings (a NUL byte in a path, as a dumped file will write it)."""
HOSTILE_VALUES = [
    "&a [1, 2]", "*a", "&a", "!!python/object/apply:os.system ['true']", "!!binary aGVsbG8=",
    "!!timestamp 2001-12-14", "!!set {a, b}", "!!omap [a: 1]", "!!float 1e999", "!!int 0x" + "f" * 40,
    "1e400", "-1e400", "9" * 40, "-" + "9" * 19, "0x" + "f" * 30, "0o777", "0b1010", "1_000", "1:30", "190:20:30",
    ".inf", "-.inf", ".nan", "~", "null", "yes", "off", '"\\0"', '"\\x00abc"', '"\\x1b[2J"', '"\\u202e"',
    '"\\ud800"', '"\\U0010ffff"', "é", "😀", "\u0000", "\x07", "\x1b[31m", "x" * 100_000, "'" + "y" * 50_000 + "'",
    "[" * 70 + "]" * 70, "{a: " * 70 + "1" + "}" * 70, "[" + "1, " * 2000 + "1]", "[]", "{}", '""', "''",
    "1.0e+308", "4.9e-324", "-0.0", "0", "-1", "2", "100000000", "[.inf, .nan]", "[1, 2, 3]", "[[1, 2], [3, 4]]",
    "{x: 1}", "|\n  text\n", ">-\n  folded\n", "? a\n: b", "<<: {a: 1}", "!custom 1", "! 1", "!!str 1",
    *HOSTILE_PATHS,
]
TOKENS = ["[", "]", "{", "}", ",", ":", ": ", "- ", "? ", "&a ", "*a", "!!str ", "!x ", "|", ">", "---", "...",
          "%YAML 1.1\n", "%TAG ! tag:x,2000:\n", "#", "'", '"', "\\", "\t", "\n", "\n  ", "<<: ", "->", " -> ",
          ".", "\x00", "\x85", "\u2028", "\ufeff", "@", "`", "%", "!!python/name:os.system "]


def hostile_lines(names: list[str], rng: random.Random) -> list[str]:
    """Whole lines a file may be given: extends, data files, plugs and settings of its signals."""
    path = rng.choice(HOSTILE_PATHS)
    a, b = rng.choice(names), rng.choice(names)
    return [f"extends: {path}", f"  traj: {{type: TrajectoryFile, params: {{path: {path}}}}}",
            f"  - {a} -> {b}", f"  {a}: {rng.choice(HOSTILE_VALUES)}", f"set: {{{a}: {rng.choice(HOSTILE_VALUES)}}}",
            f"record: [{a}, {a}]", "remove: {entities: [robot]}", f"robot: {rng.choice(HOSTILE_VALUES)}",
            f"dt: {rng.choice(HOSTILE_VALUES)}", f"duration: {rng.choice(HOSTILE_VALUES)}",
            "a: &a [1, *a]", 'x: &a ["lol", "lol"]\ny: &b [*a, *a, *a]\nz: [*b, *b, *b]']


def signal_names(text: str) -> list[str]:
    """The ``entity.signal`` names a file writes, for plugs and settings that make sense."""
    return sorted(set(re.findall(r"[A-Za-z_][\w-]*\.[A-Za-z_]\w*", text))) or ["a.b"]


# -- mutations of the bytes and lines: files that mostly do not parse --------------------------

def _position(data: bytes, rng: random.Random) -> int:
    return rng.randrange(len(data) + 1)


def flip(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """One bit of one byte flipped."""
    i = rng.randrange(len(data))
    return data[:i] + bytes([data[i] ^ (1 << rng.randrange(8))]) + data[i + 1:]


def delete(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """Up to 40 bytes taken out."""
    i = _position(data, rng)
    return data[:i] + data[i + rng.randint(1, 40):]


def insert_token(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """A YAML token (or a character YAML refuses) put in anywhere."""
    i = _position(data, rng)
    return data[:i] + rng.choice(TOKENS).encode() + data[i:]


def insert_bytes(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """Up to 8 random bytes (UTF-8 or not) put in anywhere."""
    i = _position(data, rng)
    return data[:i] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 8))) + data[i:]


def truncate(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """The file cut anywhere."""
    return data[:_position(data, rng)]


def _lines(data: bytes) -> list[bytes]:
    return data.splitlines(keepends=True) or [b""]


def duplicate_line(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """A line repeated up to 3 times."""
    lines = _lines(data)
    i = rng.randrange(len(lines))
    return b"".join(lines[:i + 1] + [lines[i]] * rng.randint(1, 3) + lines[i + 1:])


def delete_line(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """A line taken out."""
    lines = _lines(data)
    del lines[rng.randrange(len(lines))]
    return b"".join(lines)


def reindent(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """A line given 0 to 6 spaces of indentation."""
    lines = _lines(data)
    i = rng.randrange(len(lines))
    lines[i] = b" " * rng.randint(0, 6) + lines[i].lstrip(b" ")
    return b"".join(lines)


def replace_value(data: bytes, rng: random.Random, _: list[str]) -> bytes:
    """A value after ``key:`` or in a flow list replaced by a hostile one."""
    spots = [m.span(1) for m in re.finditer(rb"(?::\s|\[|,\s?)([^\s,\[\]{}:#][^,\]}\n#]*)", data)]
    if not spots:
        return insert_token(data, rng, _)
    start, end = rng.choice(spots)
    return data[:start] + rng.choice(HOSTILE_VALUES).encode("utf-8", "surrogatepass") + data[end:]


def insert_line(data: bytes, rng: random.Random, names: list[str]) -> bytes:
    """A hostile line (see :func:`hostile_lines`) put in between two lines."""
    lines = _lines(data)
    i = rng.randrange(len(lines) + 1)
    line = rng.choice(hostile_lines(names, rng)).encode("utf-8", "surrogatepass") + b"\n"
    return b"".join([*lines[:i], line, *lines[i:]])


TEXT_MUTATIONS: list[Callable[[bytes, random.Random, list[str]], bytes]] = [
    flip, delete, insert_token, insert_bytes, truncate, duplicate_line, delete_line, reindent,
    replace_value, replace_value, replace_value, insert_line, insert_line, insert_line,
]


def mutate_text(text: str, rng: random.Random) -> tuple[bytes, list[str]]:
    """``text`` after one to three mutations of its bytes or lines, and their names."""
    data, names, done = text.encode(), signal_names(text), []
    for _ in range(rng.choice((1, 1, 2, 3))):
        mutation = rng.choice(TEXT_MUTATIONS)
        data = mutation(data, rng, names) if data else insert_line(data, rng, names)
        done.append(mutation.__name__)
    return data, done


# -- mutations of the plain data: files that parse, reaching the build -------------------------

def deep(depth: int) -> list:
    """An empty list nested ``depth`` lists deep."""
    value: list = []
    for _ in range(depth):
        value = [value]
    return value


HOSTILE_DATA = [
    None, True, False, 0, -1, 1, 3, 2**63 - 1, -(2**63), 10**18, 1e308, -1e308, math.inf, -math.inf, math.nan, -0.0,
    5e-324, "", "x" * 100_000, "\0", "a\0b", "\x1b[2J", "\u202e", "é😀", "1.0", "talos", "a.b", "a.b -> c.d",
    [], {}, [0.0] * 1000, [1.0] * 32, [math.nan, math.inf], [[1.0, 2.0], [3.0]], ["a", 1], [None], deep(30), deep(70),
    {"type": "Gain"}, {"a": {"b": [1, {"c": None}]}}, {"": 1}, {"parent": "x", "translation": [0, 0, "z"]},
    *PLAIN_PATHS,
]


def hostile_value(rng: random.Random) -> object:
    """One of :data:`HOSTILE_DATA`."""
    return rng.choice(HOSTILE_DATA)


def replace_leaf(data: dict, rng: random.Random, graph: Catalogue) -> str:
    """A random value anywhere in the file (a leaf, or now and then a whole list or mapping)
    replaced by a hostile one."""
    parent, key, node = None, None, data
    while isinstance(node, (dict, list)) and node:
        parent, key = node, rng.choice(list(node) if isinstance(node, dict) else range(len(node)))
        node = node[key]
        if rng.random() < 0.2:
            break
    if parent is None:
        return "nothing"
    parent[key] = hostile_value(rng)
    return "replace_leaf"


def add_entity(data: dict, rng: random.Random, graph: Catalogue) -> str:
    """An entity of any registered type, with a few parameters of hostile or plausible values."""
    type_name = rng.choice(list(graph.types))
    decls = list(graph.types[type_name])
    params = {name: graph.value_for(rng, type_name, name) for name in rng.sample(decls, min(len(decls), 2))}
    entities = data.setdefault("entities", {}) if isinstance(data.get("entities", {}), dict) else {}
    entities[f"fz{rng.randrange(100)}"] = {"type": type_name, "params": params}
    return f"add_entity {type_name}"


def set_parameter(data: dict, rng: random.Random, graph: Catalogue) -> str:
    """A parameter of one of the file's entities set to a hostile or plausible value."""
    entities = data.get("entities")
    if not isinstance(entities, dict) or not entities:
        return add_entity(data, rng, graph)
    name = rng.choice(list(entities))
    spec = entities[name] if isinstance(entities[name], dict) else {}
    type_name = spec.get("type")
    decls = list(graph.types.get(type_name, ()) if isinstance(type_name, str) else ()) or ["size"]
    param = rng.choice(decls)
    section = data.setdefault("set", {}) if rng.random() < 0.5 and isinstance(data.get("set", {}), dict) else None
    value = graph.value_for(rng, type_name, param)
    if section is not None:
        section[f"{name}.{param}"] = value
    elif isinstance(spec.get("params", {}), dict):
        spec.setdefault("params", {})[param] = value
    return f"set_parameter {param}"


def set_input(data: dict, rng: random.Random, graph: Catalogue) -> str:
    """An input of the graph set to a hostile value (its plug in this file taken out)."""
    plugs, settings = data.get("plugs", []), data.setdefault("set", {})
    if isinstance(settings, dict) and isinstance(plugs, list) and graph.inputs:
        target = rng.choice(graph.inputs)
        data["plugs"] = [p for p in plugs if not (isinstance(p, str) and p.replace(" ", "").endswith(f">{target}"))]
        settings[target] = hostile_value(rng)
    return "set_input"


def add_plug(data: dict, rng: random.Random, graph: Catalogue) -> str:
    """A plug of any output of the graph into any of its inputs (types and shapes at random)."""
    if isinstance(data.get("plugs", []), list) and graph.inputs and graph.outputs:
        data.setdefault("plugs", []).append(f"{rng.choice(graph.outputs)} -> {rng.choice(graph.inputs)}")
    return "add_plug"


def add_data_file(data: dict, rng: random.Random, graph: Catalogue) -> str:
    """A trajectory read from a hostile path, or a base extended from one."""
    path = rng.choice(PLAIN_PATHS)
    if rng.random() < 0.3:
        data["extends"] = path
        return "extends"
    if isinstance(data.get("entities", {}), dict):
        data.setdefault("entities", {})["traj"] = {"type": "TrajectoryFile", "params": {"path": path}}
    return "add_data_file"


DATA_MUTATIONS: list[Callable[[dict, random.Random, Catalogue], str]] = [
    replace_leaf, replace_leaf, add_entity, set_parameter, set_parameter, set_input, add_plug, add_data_file,
]


class Catalogue:
    """What the mutations draw names from: the registered types with their parameters, and the
    signals of the graph a file describes."""

    def __init__(self, path: Path):
        graph = dg.load(path)
        self.outputs = sorted(s.full_name for e in graph for s in e.outputs.values())
        self.inputs = sorted(s.full_name for e in graph for s in e.inputs.values())
        self.types = {name: dict(cls._param_decls) for name, cls in entity_types().items()}

    def value_for(self, rng: random.Random, type_name: object, param: str) -> object:
        """A hostile value, or (half the time) the default of the parameter, a little off."""
        decl = self.types.get(type_name, {}).get(param) if isinstance(type_name, str) else None
        if decl is None or rng.random() < 0.5 or decl.required:
            return hostile_value(rng)
        default = decl.default
        if isinstance(default, bool) or not isinstance(default, (int, float)):
            return hostile_value(rng) if default is None else default
        return type(default)(default * rng.choice((-1, 0, 2, 1000)))


def mutate_data(text: str, rng: random.Random, graph: Catalogue) -> tuple[bytes, list[str]]:
    """``text`` parsed, one to three mutations of its plain data, and dumped back."""
    data = yaml.safe_load(text)
    done = [rng.choice(DATA_MUTATIONS)(data, rng, graph) for _ in range(rng.choice((1, 1, 2, 3)))]
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=rng.random() < 0.5).encode(), done


class Hung(BaseException):
    """A case ran past ``DEADLINE`` (a BaseException: no ``except Exception`` can swallow it)."""


@contextmanager
def deadline(seconds: float) -> Iterator[None]:
    """Raise :class:`Hung` in what runs after ``seconds``; pytest-timeout's own alarm is put back."""
    def hung(signum: int, frame: object) -> None:
        raise Hung(f"still running after {seconds} s")

    start = time.monotonic()
    previous = signal.signal(signal.SIGALRM, hung)
    outer, _ = signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        if outer:
            signal.setitimer(signal.ITIMER_REAL, max(outer - (time.monotonic() - start), 0.001))


@pytest.fixture(scope="module")
def hostile(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A folder where the mutated files are written: the shipped base and data next to them
    (so the TALOS files still find theirs), and the files a path may name to hang a loader."""
    folder = tmp_path_factory.mktemp("fuzz")
    (folder / "base").symlink_to(GRAPHS / "base")
    (folder / "data").symlink_to(GRAPHS / "data")
    for name in ("fifo.csv", "fifo.yaml"):
        os.mkfifo(folder / name)
    for name in ("loop.csv", "loop.yaml"):
        (folder / name).symlink_to(name)
    (folder / "zero.yaml").symlink_to("/dev/zero")
    (folder / "dir.yaml").mkdir()
    (folder / "empty.csv").write_bytes(b"")
    with (folder / "big.yaml").open("wb") as f:
        f.truncate(MAX_BYTES + 1)
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(folder / "sock.csv"))
    try:
        yield folder
    finally:
        sock.close()


@pytest.fixture(scope="module")
def catalogues() -> dict[str, Catalogue]:
    """Each shipped graph's names to draw from; its first load also reads the TALOS models
    (seconds, not spent on the file), outside the timed cases."""
    return {name: Catalogue(GRAPHS / name) for name in [SMALL, *TALOS]}


def run_case(path: Path, how: str) -> str:
    """Load, check or parse the file at ``path`` (``dgraph run`` parses it for its recorders,
    then loads it); what came of it (``ok`` or the error's class)."""
    try:
        if how == "check":
            dg.files.check(path)
        elif how == "parse":
            dg.files.parse(dg.files.read_text(path), str(path))
        else:
            dg.load(path)
    except dg.GraphFileError as exc:
        assert exc.file, f"no file in {exc!r}"
        return "GraphFileError"
    return "ok"


def fuzz(folder: Path, catalogues: dict[str, Catalogue], cases: int, seed: int) -> tuple[list[str], Counter]:
    """Run ``cases`` mutated files; the failures, and how many cases ended each way."""
    rng = random.Random(seed)
    texts = {name: (GRAPHS / name).read_text() for name in catalogues}
    failures: list[str] = []
    outcomes: Counter = Counter()
    for case in range(cases):
        source = rng.choice(TALOS) if rng.random() < TALOS_SHARE else SMALL
        if rng.random() < 0.5:
            data, done = mutate_text(texts[source], rng)
        else:
            data, done = mutate_data(texts[source], rng, catalogues[source])
        how = rng.choice(("load", "load", "check", "check", "parse"))
        path = folder / f"case_{case}.yaml"
        path.write_bytes(data)
        outcome, elapsed = timed(path, how)
        outcomes[outcome if outcome in ("ok", "GraphFileError") else "failed"] += 1
        if outcome not in ("ok", "GraphFileError") or elapsed > (BUDGET if source == SMALL else BUILD_BUDGET):
            failures.append(f"case {case} ({source}, {'+'.join(done)}, {how}, {elapsed:.2f} s, {path}): {outcome}")
        else:
            path.unlink()
    return failures, outcomes


def timed(path: Path, how: str) -> tuple[str, float]:
    """:func:`run_case`'s outcome (or the exception that escaped, or :class:`Hung`) and its time."""
    start = time.perf_counter()
    try:
        with deadline(DEADLINE):
            outcome = run_case(path, how)
    except (Exception, Hung) as exc:  # any other exception is the failure reported
        outcome = f"{type(exc).__name__}: {str(exc)[:300]}"
    return outcome, time.perf_counter() - start


@pytest.mark.timeout(max(300, 30 + 3 * CASES))
def test_mutated_graph_files_build_or_give_a_located_error_within_a_second(hostile, catalogues):
    failures, outcomes = fuzz(hostile, catalogues, CASES, SEED)
    assert not failures, f"{len(failures)} of {CASES} cases failed (seed {SEED}; {dict(outcomes)}):\n" + "\n".join(
        failures[:20])
    assert outcomes["ok"] > 0 and outcomes["GraphFileError"] > CASES // 2, outcomes


def structured_plugs(count: int, seed: int) -> list[tuple[str, str]]:
    """``count`` plugs of a structured output of the TALOS sway graph into a float input of
    another entity."""
    graph = dg.load(GRAPHS / "talos_sway.yaml")
    outputs = [s for e in graph for s in e.outputs.values() if s.spec.structured]
    inputs = [s for e in graph for s in e.inputs.values() if s.spec.dtype == "float"]
    rng = random.Random(seed)
    plugs = []
    while len(plugs) < count:
        source, target = rng.choice(outputs), rng.choice(inputs)
        if source.entity is not target.entity:
            plugs.append((source.full_name, target.full_name))
    return plugs


@pytest.mark.timeout(120)
def test_a_structured_output_plugged_into_a_float_input_is_refused_by_check_at_its_line(hostile, catalogues):
    """Refused for its type, or (when the plug also closes a loop) for the loop; at its line."""
    (hostile / "sway.yaml").write_text((GRAPHS / "talos_sway.yaml").read_text())
    for case, (source, target) in enumerate([("com.feature", "device.control"), *structured_plugs(5, SEED)]):
        path = hostile / f"structured_{case}.yaml"
        path.write_text(f"extends: sway.yaml\nplugs:\n  - {source} -> {target}\n")
        _, problems = dg.files.check(path)
        refused = [p for p in problems if p.startswith(f"{path}:3 [plugs.0]: ")]
        assert len(refused) == 1, problems
        assert "a different type" in refused[0] or (case and "closes a loop" in refused[0]), refused[0]
