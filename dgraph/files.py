"""Graph files: YAML descriptions of graphs, loaded safely and written back identically.

A graph file::

    name: pd_double_integrator
    dt: 0.001
    entities:
      robot: {type: KinematicDevice, params: {control_mode: acceleration, size: 1}}
      kp:    {type: Gain, params: {size: 1}}
    plugs:
      - robot.q -> kp.input
    set:
      kp.gain: 25.0
    record: [robot.q]          # shorthand for a Recorder entity named "recorder"

A file can also be a variant of another: ``extends`` (a path relative to the file) and
``overrides`` (``entity.name: value`` pairs, parameters or input constants, as
``dgraph run --set``), with its own ``name`` and ``duration``::

    extends: talos_push_tank.yaml
    name: talos_push_no_tank
    overrides:
      tank.enabled: false

Safety: the YAML is composed with the safe loader and converted node by node; only plain
scalars, lists and mappings are accepted (no tags, anchors, aliases or merge keys), so a file
can never construct objects or run code. Entity types come only from the registry. Every
error is a :class:`~dgraph.errors.GraphFileError` carrying the file, line and key.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import yaml

from dgraph.errors import DGraphError, GraphError, GraphFileError
from dgraph.graph import Graph
from dgraph.registry import get_type
from dgraph.signals.signal import Input

MAX_BYTES = 4 * 1024 * 1024
SIGNAL_RE = r"^[A-Za-z_][A-Za-z0-9_\-]*\.[A-Za-z_][A-Za-z0-9_]*$"
PLUG_RE = re.compile(r"^\s*(\S+)\s*->\s*(\S+)\s*$")
RECORDER_NAME = "recorder"

SCHEMA: dict[str, Any] = {
    "type": "object",
    "additionalProperties": False,
    "required": ["entities"],
    "properties": {
        "name": {"type": "string", "minLength": 1},
        "dt": {"type": "number", "exclusiveMinimum": 0},
        "duration": {"type": "number", "minimum": 0},
        "entities": {
            "type": "object",
            "propertyNames": {"pattern": r"^[A-Za-z_][A-Za-z0-9_\-]*$"},
            "additionalProperties": {
                "type": "object",
                "additionalProperties": False,
                "required": ["type"],
                "properties": {"type": {"type": "string"}, "params": {"type": "object"}},
            },
        },
        "plugs": {"type": "array", "items": {"type": "string", "pattern": r"^\s*\S+\s*->\s*\S+\s*$"}},
        "set": {"type": "object", "propertyNames": {"pattern": SIGNAL_RE}},
        "record": {"type": "array", "items": {"type": "string", "pattern": SIGNAL_RE}},
    },
}

EXTENSION_SCHEMA: dict[str, Any] = {
    "type": "object",
    "additionalProperties": False,
    "required": ["extends"],
    "properties": {
        "extends": {"type": "string", "minLength": 1},
        "name": {"type": "string", "minLength": 1},
        "duration": {"type": "number", "minimum": 0},
        "overrides": {"type": "object", "propertyNames": {"pattern": SIGNAL_RE}},
    },
}
MAX_EXTENDS = 8
"""Longest chain of files extending one another."""

_INT, _FLOAT = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"
MAX_NUMBER_CHARS = 64
_PLAIN_TAGS = {
    "tag:yaml.org,2002:str", "tag:yaml.org,2002:int", "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:bool", "tag:yaml.org,2002:null",
}


class _Document:
    """Plain data converted from YAML nodes, with the line of every path."""

    def __init__(self, file: str):
        self.file = file
        self.lines: dict[tuple[Any, ...], int] = {}

    def line(self, path: tuple[Any, ...]) -> int | None:
        """The line of ``path``, or of its deepest known parent."""
        while path not in self.lines and path:
            path = path[:-1]
        return self.lines.get(path)

    def error(self, message: str, path: tuple[Any, ...], cause: DGraphError | None = None) -> GraphFileError:
        """A :class:`GraphFileError` located at ``path`` (naming the entity and signal of ``cause``)."""
        key = ".".join(str(p) for p in path) or None
        return GraphFileError(message, file=self.file, line=self.line(path), key=key,
                              entity=cause.entity if cause else None, signal=cause.signal if cause else None)


def _convert(doc: _Document, node: yaml.Node, path: tuple[Any, ...], seen: set[int],
             loader: yaml.SafeLoader) -> Any:
    if id(node) in seen:
        raise doc.error("anchors and aliases are not allowed in graph files", path)
    seen.add(id(node))
    doc.lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        if node.tag != "tag:yaml.org,2002:map":
            raise doc.error(f"tag {node.tag!r} is not allowed", path)
        out: dict[str, Any] = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag not in _PLAIN_TAGS:
                raise GraphFileError("mapping keys must be plain scalars (no merge keys or tags)", file=doc.file,
                                     line=key_node.start_mark.line + 1, key=".".join(map(str, path)) or None)
            key = key_node.value  # the text as written: `off:` names 'off', not False
            if key in out:
                raise GraphFileError(f"duplicate key {key!r}", file=doc.file,
                                     line=key_node.start_mark.line + 1, key=".".join(map(str, (*path, key))))
            out[key] = _convert(doc, value_node, (*path, key), seen, loader)
            doc.lines[(*path, key)] = key_node.start_mark.line + 1  # errors point at the key
        return out
    if isinstance(node, yaml.SequenceNode):
        if node.tag != "tag:yaml.org,2002:seq":
            raise doc.error(f"tag {node.tag!r} is not allowed", path)
        return [_convert(doc, item, (*path, i), seen, loader) for i, item in enumerate(node.value)]
    if node.tag not in _PLAIN_TAGS:
        raise doc.error(f"tag {node.tag!r} is not allowed (only plain strings, numbers, booleans, null)", path)
    return _scalar(doc, node, path, loader)


def _scalar(doc: _Document, node: yaml.Node, path: tuple[Any, ...], loader: yaml.SafeLoader) -> Any:
    """A plain scalar's value; an explicit tag on text that does not parse is a file error."""
    def error(message: str) -> GraphFileError:
        return GraphFileError(message, file=doc.file, line=node.start_mark.line + 1,
                              key=".".join(map(str, path)) or None)

    if node.tag in (_INT, _FLOAT) and (":" in node.value or len(node.value) > MAX_NUMBER_CHARS):
        # YAML 1.1 base-60 numbers (1:30) are refused, and so are absurdly long ones: PyYAML
        # converts both in quadratic time
        raise error(f"{node.value[:24]}{'...' if len(node.value) > 24 else ''} is not a supported number")
    try:
        value = loader.construct_object(node)
    except (ValueError, KeyError, IndexError, TypeError, OverflowError, yaml.YAMLError):
        raise error(f"{node.value!r} is not a valid {node.tag.rsplit(':', 1)[-1]}") from None
    too_large = (isinstance(value, float) and math.isinf(value) and node.value.lower().lstrip("+-") != ".inf") or (
        isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 2**63)
    if too_large:
        raise error(f"number {node.value[:24]}{'...' if len(node.value) > 24 else ''} is too large")
    return value


_SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""libyaml's safe loader when PyYAML was built with it (10x faster on large files), else PyYAML's."""


def parse(text: str, file: str = "<string>") -> tuple[dict[str, Any], _Document]:
    """Parse and schema-check graph-file text; returns the data and its line map."""
    doc = _Document(file)
    if len(text) > MAX_BYTES:
        raise GraphFileError(f"file larger than {MAX_BYTES} bytes", file=file)
    loader = None
    try:
        loader = _SAFE_LOADER(text)
        node = loader.get_single_node()
        if node is None:
            raise GraphFileError("the file is empty", file=file, line=1)
        data = _convert(doc, node, (), set(), loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        problem = getattr(exc, "problem", None) or str(exc)
        raise GraphFileError(f"invalid YAML: {problem}", file=file,
                             line=mark.line + 1 if mark else None) from None
    except RecursionError:
        raise GraphFileError("nesting too deep", file=file) from None
    finally:
        if loader is not None:
            loader.dispose()
    if not isinstance(data, dict):
        raise GraphFileError("a graph file must be a mapping with an 'entities' key", file=file, line=1)
    schema = EXTENSION_SCHEMA if "extends" in data else SCHEMA
    errors = sorted(jsonschema.Draft202012Validator(schema).iter_errors(data), key=lambda e: list(e.absolute_path))
    if errors:
        err = jsonschema.exceptions.best_match(errors)
        message, path = _schema_message(err)
        raise doc.error(message, path)
    return data, doc


def _schema_message(err: jsonschema.ValidationError) -> tuple[str, tuple[Any, ...]]:
    """A readable message for a schema violation and the path of the offending key or value."""
    path = tuple(err.absolute_path)
    if err.validator == "additionalProperties":
        allowed = err.schema.get("properties", {})
        extra = [k for k in err.instance if k not in allowed]
        return f"unknown key {extra[0]!r} (allowed: {', '.join(allowed)})", (*path, extra[0])
    if "propertyNames" in err.schema_path:  # a key itself is wrong: point at it
        bad = err.instance
        if path == ("entities",):
            return f"invalid entity name {bad!r}: use letters, digits, '_' or '-', starting with a letter", (*path, bad)
        return f"{bad!r} must read 'entity.signal'", (*path, bad)
    if err.validator == "pattern" and "->" in str(err.schema.get("pattern", "")):
        return f"plug {err.instance!r} must read 'entity.output -> entity.input'", path
    if err.validator == "pattern":
        return f"{err.instance!r} must read 'entity.signal'", path
    return err.message, path


def read_text(path: str | Path) -> str:
    """The text of a graph file (:class:`GraphFileError` if not a readable regular file of at
    most ``MAX_BYTES``, or not UTF-8): a device such as ``/dev/zero`` is never read."""
    path = Path(path)
    try:
        if path.exists() and not path.is_file():
            raise GraphFileError("cannot read: not a regular file", file=str(path))
        if path.stat().st_size > MAX_BYTES:
            raise GraphFileError(f"file larger than {MAX_BYTES} bytes", file=str(path))
        return path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise GraphFileError(f"cannot read: {exc.strerror or exc}", file=str(path)) from None
    except UnicodeDecodeError as exc:
        raise GraphFileError(f"not UTF-8 text: {exc.reason}", file=str(path)) from None


def load(path: str | Path, overrides: dict[str, Any] | None = None) -> Graph:
    """Build the graph described by the file at ``path``.

    ``overrides`` maps ``entity.name`` to a value: a parameter (applied before the entity is
    built) or an input constant (set after the plugs), as ``dgraph run --set`` does.
    """
    return loads(read_text(path), str(path), overrides)


def loads(text: str, file: str = "<string>", overrides: dict[str, Any] | None = None) -> Graph:
    """Build a graph from graph-file text (see :func:`load`)."""
    data, doc = parse(text, file)
    try:
        if "extends" in data:
            return _extend(data, doc, dict(overrides or {}))
        return _build(data, doc, dict(overrides or {}))
    except GraphFileError:
        raise
    except DGraphError as exc:  # anything the library refused, located at the file level
        raise GraphFileError(str(exc), file=file, entity=exc.entity, signal=exc.signal) from exc
    except (ValueError, TypeError, OverflowError, MemoryError) as exc:  # a value no check foresaw
        raise GraphFileError(f"could not build the graph: {type(exc).__name__}: {exc}", file=file) from exc


def _extend(data: dict[str, Any], doc: _Document, command_line: dict[str, Any]) -> Graph:
    """Build the file that ``data`` extends (following a chain of ``extends``), with the name,
    duration and overrides of the files above it: the nearest file wins, the command line wins
    over every file. An error in an override is located at the file and line that set it."""
    from_files: dict[str, tuple[Any, _Document]] = {}
    seen = {Path(doc.file).resolve()}
    while "extends" in data:
        for key, value in data.get("overrides", {}).items():
            from_files.setdefault(key, (value, doc))
        base_file = Path(doc.file).parent / data["extends"]
        if base_file.suffix not in (".yaml", ".yml"):
            raise doc.error(f"can only extend a .yaml graph file, not {data['extends']!r}", ("extends",))
        if base_file.resolve() in seen:
            raise doc.error(f"{data['extends']!r} extends, directly or not, this file (a cycle)", ("extends",))
        if len(seen) > MAX_EXTENDS:
            raise doc.error(f"more than {MAX_EXTENDS} files extend one another", ("extends",))
        seen.add(base_file.resolve())
        try:
            base, base_doc = parse(read_text(base_file), str(base_file))
        except GraphFileError as exc:
            raise doc.error(f"cannot extend {data['extends']!r}: {exc}", ("extends",)) from None
        for key in ("name", "duration"):
            if key in data:
                base.setdefault(f"_{key}", data[key])  # the nearest file's value
        data, doc = base, base_doc
    for key in ("name", "duration"):
        if f"_{key}" in data:
            data[key] = data.pop(f"_{key}")
    entities = declared_entities(data)
    for key, (_, origin) in from_files.items():
        if key.partition(".")[0] not in entities:
            raise origin.error(f"no entity {key.partition('.')[0]!r} in {doc.file}", ("overrides", key))
    origins = {key: origin for key, (_, origin) in from_files.items() if key not in command_line}
    overrides = {**{key: value for key, (value, _) in from_files.items()}, **command_line}
    return _build(data, doc, overrides, origins)


def _build(data: dict[str, Any], doc: _Document, overrides: dict[str, Any],
           origins: dict[str, _Document] | None = None) -> Graph:
    """Build the graph; ``origins`` maps the overrides set by an extending file to that file."""
    origins = origins or {}
    try:
        graph = Graph(dt=data.get("dt", 0.001), name=data.get("name", Path(doc.file).stem or "graph"))
    except DGraphError as exc:
        raise doc.error(str(exc), ("dt",), exc) from None
    duration = data.get("duration")
    if duration is not None and not math.isfinite(duration):
        raise doc.error(f"duration must be finite, got {duration!r}", ("duration",))
    graph.duration = duration
    entities = declared_entities(data)
    if "record" in data and RECORDER_NAME in data["entities"]:
        raise doc.error(f"'record' creates an entity named {RECORDER_NAME!r}, which already exists", ("record",))
    param_overrides, constants = _split_overrides(doc, entities, overrides)
    for name, spec in entities.items():
        params = {**_resolve_paths(doc, spec), **param_overrides.get(name, {})}
        from_file = [key for key in (f"{name}.{p}" for p in param_overrides.get(name, {})) if key in origins]
        if from_file:  # an extending file changed a parameter: errors point at its override
            graph.add(_make_entity(origins[from_file[0]], name, spec["type"], params, ("overrides", from_file[0])))
        else:
            graph.add(_make_entity(doc, name, spec["type"], params, spec.get("_path")))
    for i, plug in enumerate(data.get("plugs", [])):
        source, target = PLUG_RE.match(plug).groups()
        try:
            graph.plug(source, target)
        except DGraphError as exc:
            raise doc.error(str(exc), ("plugs", i), exc) from None
    for key, value in data.get("set", {}).items():
        refused = _set_constant(graph, key, value)
        if refused:
            raise doc.error(str(refused), ("set", key), refused)
    for key, value in constants.items():
        refused = _set_constant(graph, key, value)
        if refused and key in origins:
            raise origins[key].error(str(refused), ("overrides", key), refused)
        if refused:
            raise _override_error(str(refused), key)
    for entity in graph:
        problems = entity.check()
        if problems:
            raise doc.error("; ".join(problems), entities[entity.name].get("_path", ("entities", entity.name)))
    return graph


def _resolve_paths(doc: _Document, spec: dict[str, Any]) -> dict[str, Any]:
    """The entity's parameters, with relative ``path`` parameters taken from the file's folder."""
    params = dict(spec.get("params") or {})
    folder = Path(doc.file).parent if doc.file != "<string>" else None
    try:
        decls = get_type(spec["type"])._param_decls
    except DGraphError:
        return params  # the unknown type is reported where the entity is made
    for name, value in params.items():
        decl = decls.get(name)
        if folder is not None and decl is not None and decl.kind == "path" and isinstance(value, str) \
                and not Path(value).is_absolute():
            params[name] = str(folder / value)
    return params


def _override_error(message: str, key: str) -> GraphFileError:
    """An error in a ``--set entity.name=value`` given on the command line (not in the file)."""
    return GraphFileError(message, file="<command line>", key=f"--set {key}", entity=key.partition(".")[0])


def declared_entities(data: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Entity specs of a parsed file, including the Recorder that ``record`` stands for."""
    entities = dict(data["entities"])
    if "record" in data:
        entities[RECORDER_NAME] = {"type": "Recorder", "params": {"signals": data["record"]},
                                   "_path": ("record",)}
    return entities


def _split_overrides(doc: _Document, entities: dict[str, Any], overrides: dict[str, Any]
                     ) -> tuple[dict[str, dict[str, Any]], dict[str, Any]]:
    """Sort ``entity.name=value`` overrides into parameters and input constants."""
    params: dict[str, dict[str, Any]] = {}
    constants: dict[str, Any] = {}
    for key, value in overrides.items():
        entity, _, name = key.partition(".")
        if entity not in entities or not name:
            raise _override_error(f"no entity {entity!r} in {doc.file}", key)
        try:
            is_param = name in get_type(entities[entity]["type"])._param_decls
        except DGraphError as exc:
            raise doc.error(str(exc), ("entities", entity, "type"), exc) from None
        if is_param:
            params.setdefault(entity, {})[name] = value
        else:
            constants[key] = value
    return params, constants


def _make_entity(doc: _Document, name: str, type_name: str, params: dict[str, Any],
                 path: tuple[Any, ...] | None = None) -> Any:
    where = path or ("entities", name)
    try:
        cls = get_type(type_name)
    except DGraphError as exc:
        raise doc.error(str(exc), (*where, "type") if path is None else where, exc) from None
    try:
        return cls(name, **params)
    except DGraphError as exc:
        raise doc.error(str(exc), (*where, "params") if path is None else where, exc) from None
    except Exception as exc:  # an entity constructor failing on odd values must not crash the loader
        raise doc.error(f"{name} ({type_name}) could not be built: {type(exc).__name__}: {exc}",
                        (*where, "params") if path is None else where) from None


def _set_constant(graph: Graph, key: str, value: Any) -> DGraphError | None:
    """Set input ``key`` to ``value``; the refusal, if any (the caller locates it)."""
    try:
        sig = graph.signal(key)
        if not isinstance(sig, Input):
            return GraphError(f"{key} is an output: only inputs (and parameters, with --set) can be set",
                              entity=sig.entity.name, signal=sig.name)
        sig.set(value)
    except DGraphError as exc:
        return exc
    return None


def to_plain(value: Any, where: str) -> Any:
    """Convert a parameter or constant to YAML-safe plain data (lists, numbers, strings)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, (list, tuple)):
        return [to_plain(v, where) for v in value]
    if isinstance(value, dict) and all(isinstance(k, str) for k in value):
        return {k: to_plain(v, f"{where}.{k}") for k, v in value.items()}
    raise GraphError(f"{where}: a {type(value).__name__} cannot be written to a graph file")


def dumps(graph: Graph) -> str:
    """The graph-file text of ``graph``."""
    entities = {}
    for e in graph:
        spec: dict[str, Any] = {"type": e.type_name}
        if e.given_params:
            spec["params"] = {k: to_plain(v, f"{e.name}.{k}") for k, v in e.given_params.items()}
        entities[e.name] = spec
    data: dict[str, Any] = {"name": graph.name, "dt": graph.dt}
    if graph.duration is not None:
        data["duration"] = graph.duration
    data |= {"entities": entities,
                            "plugs": [f"{a} -> {b}" for a, b in graph.plugs()]}
    constants = {inp.full_name: to_plain(inp.value, inp.full_name)
                 for e in graph for inp in e.inputs.values() if inp.is_set}
    if constants:
        data["set"] = constants
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)


def save(graph: Graph, path: str | Path) -> None:
    """Write ``graph`` to ``path`` as a graph file."""
    Path(path).write_text(dumps(graph))
