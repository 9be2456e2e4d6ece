"""Graph files: YAML descriptions of graphs, composed from one another, loaded safely and
written back identically.

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

``set`` names input constants and parameters alike (``entity.name: value``, as
``dgraph run --set``). ``robot: talos`` gives its model to every entity with a ``model``
parameter that does not set its own.

A file can build on another: ``extends`` (a path relative to the file; chains of at most
``MAX_EXTENDS`` files, no cycles) applies the file, in this order, to the graph the base
describes::

    extends: base/talos.yaml
    name: talos_sway           # name, dt, duration, robot: the nearest file's
    remove:                    # what the base has and this graph does not
      entities: [view]         # with every plug, setting and record that names them
      plugs: [device.q -> view.q]          # or only the input: [view.q]
      set: [waist_task.kd]
      record: [com.error]
    entities:                  # new, or replacing the base's entity of that name (in its place;
      com_reference: {type: Sinusoid, params: {frequency: 0.5}}   # its plugs, settings, records stay)
    set:                       # merged: replaces the base's setting, or its plug, of that input
      com_task.kp: 30.0
    plugs:                     # appended; a plug into an input the base plugs replaces that plug
      - com_reference.velocity -> com.reference_velocity
    record: [com_reference.velocity]       # appended

``overrides`` is the older name of ``set`` in such a file. ``--set`` on the command line is
applied last, over every file.

Safety: the YAML is composed with the safe loader and converted node by node; only plain
scalars, lists and mappings are accepted (no tags, anchors, aliases or merge keys), so a file
can never construct objects or run code. Entity types come only from the registry. Every
error is a :class:`~dgraph.errors.GraphFileError` carrying the file, line and key of the file
that wrote what is wrong.
"""

from __future__ import annotations

import difflib
import math
import os
import re
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import yaml

from dgraph.errors import DGraphError, GraphError, GraphFileError
from dgraph.graph import Graph
from dgraph.params import Param
from dgraph.registry import get_type
from dgraph.signals.signal import Input

MAX_BYTES = 4 * 1024 * 1024
NAME_RE = r"^[A-Za-z_][A-Za-z0-9_\-]*$"
SIGNAL_RE = r"^[A-Za-z_][A-Za-z0-9_\-]*\.[A-Za-z_][A-Za-z0-9_]*$"
PLUG_PATTERN = r"^\s*\S+\s*->\s*\S+\s*$"
UNPLUG_PATTERN = r"^\s*(\S+\s*->\s*)?\S+\s*$"
PLUG_RE = re.compile(r"^\s*(\S+)\s*->\s*(\S+)\s*$")
RECORDER_NAME = "recorder"
COMMAND_LINE = "<command line>"
SCALARS = ("name", "dt", "duration", "robot")
"""Graph-level keys: the nearest file of a chain that gives one wins."""

_SIGNALS = {"type": "array", "items": {"type": "string", "pattern": SIGNAL_RE}}
_SETTINGS = {"type": "object", "propertyNames": {"pattern": SIGNAL_RE}}
SCHEMA: dict[str, Any] = {
    "type": "object",
    "additionalProperties": False,
    "properties": {
        "name": {"type": "string", "minLength": 1},
        "dt": {"type": "number", "exclusiveMinimum": 0},
        "duration": {"type": "number", "minimum": 0},
        "robot": {"type": "string", "minLength": 1},
        "entities": {
            "type": "object",
            "propertyNames": {"pattern": NAME_RE},
            "additionalProperties": {
                "type": "object",
                "additionalProperties": False,
                "required": ["type"],
                "properties": {"type": {"type": "string"}, "params": {"type": "object"}},
            },
        },
        "plugs": {"type": "array", "items": {"type": "string", "pattern": PLUG_PATTERN}},
        "set": _SETTINGS,
        "record": _SIGNALS,
        "extends": {"type": "string", "minLength": 1},
        "remove": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "entities": {"type": "array", "items": {"type": "string", "pattern": NAME_RE}},
                "plugs": {"type": "array", "items": {"type": "string", "pattern": UNPLUG_PATTERN}},
                "set": _SIGNALS,
                "record": _SIGNALS,
            },
        },
        "overrides": _SETTINGS,
    },
    "if": {"not": {"required": ["extends"]}},
    "then": {"required": ["entities"]},
    "dependentRequired": {"remove": ["extends"], "overrides": ["extends"]},
}
MAX_EXTENDS = 8
"""Longest chain of files extending one another."""
_PATTERNS = {SIGNAL_RE: "'entity.signal'", PLUG_PATTERN: "'entity.output -> entity.input'",
             UNPLUG_PATTERN: "'entity.output -> entity.input' or 'entity.input'", NAME_RE: "an entity name"}

_INT, _FLOAT = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"
MAX_NUMBER_CHARS = 64
_PLAIN_TAGS = {
    "tag:yaml.org,2002:str", "tag:yaml.org,2002:int", "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:bool", "tag:yaml.org,2002:null",
}


class _Document:
    """One file's plain data, converted from YAML nodes, with the line of every path."""

    def __init__(self, file: str):
        self.file = file
        self.layer = 0
        """Its place in a chain of files extending one another: 0 for the deepest base."""
        self.lines: dict[tuple[Any, ...], int] = {}

    @property
    def folder(self) -> Path | None:
        """The folder the file's relative paths start from (None for text without a file)."""
        return None if self.file in ("<string>", COMMAND_LINE) else Path(self.file).parent

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


class _CommandLine(_Document):
    """The ``--set entity.name=value`` settings of the command line: a last layer over the files."""

    def __init__(self) -> None:
        super().__init__(COMMAND_LINE)
        self.layer = MAX_EXTENDS + 1

    def error(self, message: str, path: tuple[Any, ...], cause: DGraphError | None = None) -> GraphFileError:
        key = str(path[-1])
        return GraphFileError(message, file=COMMAND_LINE, key=f"--set {key}",
                              entity=cause.entity if cause else key.partition(".")[0],
                              signal=cause.signal if cause else None)


@dataclass(frozen=True)
class _At:
    """Where a piece of the graph was written: a file and the path of its key."""

    doc: _Document
    path: tuple[Any, ...]

    def error(self, message: str, cause: DGraphError | None = None) -> GraphFileError:
        return self.doc.error(message, self.path, cause)

    def where(self) -> str:
        """``file:line [key]``, for messages that point at a second place."""
        line = self.doc.line(self.path)
        return f"{self.doc.file}{f':{line}' if line else ''} [{'.'.join(map(str, self.path))}]"

    def within(self, *keys: Any) -> _At:
        return _At(self.doc, (*self.path, *keys))


def _latest(first: _At, *others: _At) -> _At:
    """The place written by the nearest file of the chain (``first`` on a tie)."""
    return max((first, *others), key=lambda at: at.doc.layer)


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


def _parse_file(text: str, file: str) -> tuple[dict[str, Any], _Document]:
    """Parse and schema-check the text of one file; returns the data and its line map."""
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
    errors = sorted(jsonschema.Draft202012Validator(SCHEMA).iter_errors(data), key=lambda e: list(e.absolute_path))
    if errors:
        message, path = _schema_message(jsonschema.exceptions.best_match(errors))
        raise doc.error(message, path)
    return data, doc


def _schema_message(err: jsonschema.ValidationError) -> tuple[str, tuple[Any, ...]]:
    """A readable message for a schema violation and the path of the offending key or value."""
    path = tuple(err.absolute_path)
    if err.validator == "additionalProperties":
        allowed = err.schema.get("properties", {})
        extra = [k for k in err.instance if k not in allowed]
        return f"unknown key {extra[0]!r} (allowed: {', '.join(allowed)})", (*path, extra[0])
    if err.validator == "dependentRequired":
        key = next(k for k in SCHEMA["dependentRequired"] if k in err.instance)
        return f"{key!r} is for a file that extends another (it has no 'extends')", (*path, key)
    if "propertyNames" in err.schema_path:  # a key itself is wrong: point at it
        bad = err.instance
        if path == ("entities",):
            return f"invalid entity name {bad!r}: use letters, digits, '_' or '-', starting with a letter", (*path, bad)
        return f"{bad!r} must read 'entity.signal'", (*path, bad)
    if err.validator == "pattern":
        what = "plug " if err.schema["pattern"] in (PLUG_PATTERN, UNPLUG_PATTERN) else ""
        return f"{what}{err.instance!r} must read {_PATTERNS[err.schema['pattern']]}", path
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


def _chain(text: str, file: str) -> list[tuple[dict[str, Any], _Document]]:
    """The file and every file it extends, the deepest base first (its layer is 0)."""
    data, doc = _parse_file(text, file)
    chain = [(data, doc)]
    seen = {Path(file).resolve()}
    while "extends" in data:
        base = _base_file(data["extends"], doc, seen)
        try:
            base_text = read_text(base)
        except GraphFileError as exc:
            raise doc.error(f"cannot extend {data['extends']!r}: {exc}", ("extends",)) from None
        data, doc = _parse_file(base_text, str(base))  # a mistake in the base names the base
        chain.append((data, doc))
    chain.reverse()
    for layer, (_, doc) in enumerate(chain):
        doc.layer = layer
    return chain


def _base_file(extends: str, doc: _Document, seen: set[Path]) -> Path:
    """The file that ``doc`` extends, refused if not a .yaml file, in a cycle or too deep."""
    base = Path(doc.file).parent / extends
    if base.suffix not in (".yaml", ".yml"):
        raise doc.error(f"can only extend a .yaml graph file, not {extends!r}", ("extends",))
    if base.resolve() in seen:
        raise doc.error(f"{extends!r} extends, directly or not, this file (a cycle)", ("extends",))
    if len(seen) > MAX_EXTENDS:
        raise doc.error(f"more than {MAX_EXTENDS} files extend one another", ("extends",))
    seen.add(base.resolve())
    return base


@dataclass
class _Entity:
    """An entity as the files describe it: type, parameters, and where it was defined."""

    type: str
    params: dict[str, Any]
    at: _At
    """Its definition: ``entities.NAME`` of a file (``record`` for the recorder it stands for)."""

    def where(self, key: str) -> _At:
        """The place of its ``type`` or ``params``."""
        return self.at.within(key) if self.at.path[0] == "entities" else self.at


def _owner(key: str) -> str:
    """The entity of ``entity.name``."""
    return key.partition(".")[0]


def _suggest(name: str, names: Iterable[str]) -> str:
    close = difflib.get_close_matches(name, list(names), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


class _Composition:
    """A graph described by a chain of files, every piece with the file and key that wrote it."""

    def __init__(self, top: _Document):
        self.top = top
        self.scalars: dict[str, tuple[Any, _At]] = {}
        self.entities: dict[str, _Entity] = {}
        self.plugs: dict[str, tuple[str, _At]] = {}  # input -> (output, where)
        self.sets: dict[str, tuple[Any, _At]] = {}  # entity.name -> (value, where)
        self.records: dict[str, _At] = {}

    def apply(self, data: dict[str, Any], doc: _Document) -> None:
        """Lay one file over what the files it extends described."""
        for key in SCALARS:
            if key in data:
                self.scalars[key] = (data[key], _At(doc, (key,)))
        self._remove(data.get("remove", {}), doc)
        for name, spec in data.get("entities", {}).items():
            self.entities[name] = _Entity(spec["type"], dict(spec.get("params") or {}), _At(doc, ("entities", name)))
        for section in ("set", "overrides"):
            for key, value in data.get(section, {}).items():
                self._take(key, _At(doc, (section, key)))
                self.sets[key] = (value, _At(doc, (section, key)))
        for i, plug in enumerate(data.get("plugs", [])):
            source, target = PLUG_RE.match(plug).groups()
            self._take(target, _At(doc, ("plugs", i)))
            self.plugs[target] = (source, _At(doc, ("plugs", i)))
        for i, key in enumerate(data.get("record", [])):
            if key in self.records:
                raise _At(doc, ("record", i)).error(f"{key} is already recorded ({self.records[key].where()})")
            self.records[key] = _At(doc, ("record", i))

    def _take(self, key: str, at: _At) -> None:
        """Forget what the files below plugged into or set on ``key``: ``at`` replaces it. One
        file may not say it twice."""
        for table, how in ((self.plugs, "plugged"), (self.sets, "set")):
            earlier = table.pop(key, None)
            if earlier is not None and earlier[1].doc is at.doc:
                raise at.error(f"{key} is already {how} by this file ({earlier[1].where()})")

    def _remove(self, remove: dict[str, list[str]], doc: _Document) -> None:
        for i, name in enumerate(remove.get("entities", [])):
            self._remove_entity(name, _At(doc, ("remove", "entities", i)))
        for i, text in enumerate(remove.get("plugs", [])):
            self._unplug(text, _At(doc, ("remove", "plugs", i)))
        for section, table, how in (("set", self.sets, "set"), ("record", self.records, "recorded")):
            for i, key in enumerate(remove.get(section, [])):
                if table.pop(key, None) is None:
                    raise _At(doc, ("remove", section, i)).error(
                        f"{key} is not {how} by the files this one extends{_suggest(key, table)}")

    def _remove_entity(self, name: str, at: _At) -> None:
        """Take out entity ``name`` with every plug, setting and record that names it."""
        if self.entities.pop(name, None) is None:
            raise at.error(f"no entity {name!r} to remove in the files this one extends{_suggest(name, self.entities)}")
        self.plugs = {t: (s, a) for t, (s, a) in self.plugs.items() if name not in (_owner(t), _owner(s))}
        self.sets = {key: v for key, v in self.sets.items() if _owner(key) != name}
        self.records = {key: a for key, a in self.records.items() if _owner(key) != name}

    def _unplug(self, text: str, at: _At) -> None:
        """Take out the plug ``source -> target``, or whatever is plugged into ``target``."""
        source, arrow, target = (part.strip() for part in text.rpartition("->"))
        plugged = self.plugs.get(target)
        if plugged is None or (arrow and plugged[0] != source):
            found = f" ({target} is plugged to {plugged[0]})" if plugged else ""
            raise at.error(f"no plug {text.strip()!r} in the files this one extends{found}")
        del self.plugs[target]

    def declared(self) -> dict[str, _Entity]:
        """The entities, with the Recorder that ``record`` stands for."""
        if not self.records:
            return dict(self.entities)
        record = _At(list(self.records.values())[-1].doc, ("record",))
        if RECORDER_NAME in self.entities:
            raise _latest(record, self.entities[RECORDER_NAME].at).error(
                f"'record' creates an entity named {RECORDER_NAME!r}, which already exists")
        return {**self.entities, RECORDER_NAME: _Entity("Recorder", {"signals": list(self.records)}, record)}

    def flat(self) -> dict[str, Any]:
        """The plain data of one file, in the top file's folder, that describes this graph."""
        params, constants = _split_settings(self.sets, self.entities)
        data: dict[str, Any] = {key: self.scalars[key][0] for key in SCALARS if key in self.scalars}
        data["entities"] = {name: _flat_entity(spec, params.get(name, {}), self.top.folder)
                            for name, spec in self.entities.items()}
        if self.plugs:
            data["plugs"] = [f"{source} -> {target}" for target, (source, _) in self.plugs.items()]
        if constants:
            data["set"] = {key: value for key, (value, _) in constants.items()}
        if self.records:
            data["record"] = list(self.records)
        return data


def _compose(text: str, file: str, command_line: dict[str, Any] | None = None) -> _Composition:
    """The graph that the file and the files it extends describe, then the command line's settings."""
    chain = _chain(text, file)
    composition = _Composition(chain[-1][1])
    for data, doc in chain:
        composition.apply(data, doc)
    if command_line:
        composition.apply({"set": command_line}, _CommandLine())
    return composition


def _decls(spec: _Entity | None) -> dict[str, Param]:
    """The parameter declarations of an entity's type (none if the type is unknown)."""
    try:
        return get_type(spec.type)._param_decls if spec is not None else {}
    except DGraphError:
        return {}  # the unknown type is reported where the entity is made


def _split_settings(settings: dict[str, tuple[Any, _At]], entities: dict[str, _Entity]
                    ) -> tuple[dict[str, dict[str, tuple[Any, _At]]], dict[str, tuple[Any, _At]]]:
    """Sort ``entity.name`` settings into parameters (by entity) and input constants."""
    params: dict[str, dict[str, tuple[Any, _At]]] = {}
    constants: dict[str, tuple[Any, _At]] = {}
    for key, setting in settings.items():
        entity, _, name = key.partition(".")
        if name in _decls(entities.get(entity)):
            params.setdefault(entity, {})[name] = setting
        else:
            constants[key] = setting
    return params, constants


def _path_param(decl: Param | None, value: Any, doc: _Document) -> Any:
    """A ``path`` parameter's value, taken from the folder of the file that wrote it."""
    if decl is None or decl.kind != "path" or not isinstance(value, str) or doc.folder is None \
            or Path(value).is_absolute():
        return value
    return os.path.normpath(doc.folder / value)


def _relative(value: Any, decl: Param | None, folder: Path | None) -> Any:
    """A ``path`` parameter's value relative to ``folder`` (default: the working directory)."""
    if decl is None or decl.kind != "path" or not isinstance(value, str):
        return value
    return os.path.relpath(value, folder or os.curdir)


def _flat_entity(spec: _Entity, settings: dict[str, tuple[Any, _At]], folder: Path | None) -> dict[str, Any]:
    """An entity's type and parameters (its definition's, then the settings'), paths from ``folder``."""
    decls = _decls(spec)
    params = {key: (value, spec.at.doc) for key, value in spec.params.items()}
    params.update({key: (value, at.doc) for key, (value, at) in settings.items()})
    out: dict[str, Any] = {"type": spec.type}
    if params:
        out["params"] = {key: _relative(_path_param(decls.get(key), value, doc), decls.get(key), folder)
                         for key, (value, doc) in params.items()}
    return out


def parse(text: str, file: str = "<string>") -> tuple[dict[str, Any], _Document]:
    """The graph that graph-file text describes, as the plain data of one file without
    ``extends`` (the files it extends composed, parameters given by ``set`` folded into their
    entities, ``path`` parameters relative to the file's folder), and the file's line map.

    The YAML, the schema and what ``remove`` names are checked here; types, parameters and
    signals when the graph is built (:func:`loads`).
    """
    composition = _compose(text, file)
    return composition.flat(), composition.top


def load(path: str | Path, overrides: dict[str, Any] | None = None) -> Graph:
    """Build the graph described by the file at ``path`` (and the files it extends).

    ``overrides`` maps ``entity.name`` to a value: a parameter (applied before the entity is
    built) or an input constant, as ``dgraph run --set`` does; they win over every file.
    """
    return loads(read_text(path), str(path), overrides)


def loads(text: str, file: str = "<string>", overrides: dict[str, Any] | None = None) -> Graph:
    """Build a graph from graph-file text (see :func:`load`)."""
    composition = _compose(text, file, overrides)
    try:
        return _build(composition, file)
    except GraphFileError:
        raise
    except DGraphError as exc:  # anything the library refused, located at the file level
        raise GraphFileError(str(exc), file=file, entity=exc.entity, signal=exc.signal) from exc
    except (ValueError, TypeError, OverflowError, MemoryError) as exc:  # a value no check foresaw
        raise GraphFileError(f"could not build the graph: {type(exc).__name__}: {exc}", file=file) from exc


def check(path: str | Path) -> tuple[Graph, list[str]]:
    """Everything wrong with the graph file at ``path``, one line each, without running a tick:
    every plug the graph refuses (a structured type or a shape that does not fit, a loop), each
    located at its file and line, then what :meth:`Graph.problems` finds in the graph built from
    the rest (an input left unplugged by a refused plug is not listed again), with that graph.
    A mistake that stops the build (YAML, schema, an unknown type or parameter) raises
    :class:`GraphFileError`, as :func:`load` does.
    """
    refused: list[tuple[str, GraphFileError]] = []
    file = str(path)
    graph = _build(_compose(read_text(path), file), file, refused)
    unplugged = {f"input {target} is not plugged, not set and has no default" for target, _ in refused}
    return graph, [str(error) for _, error in refused] + [p for p in graph.problems() if p not in unplugged]


def _build(composition: _Composition, file: str, refused: list[tuple[str, GraphFileError]] | None = None
           ) -> Graph:
    """Make the entities, plug them, set the constants, check what is recorded. With a
    ``refused`` list, a refused plug is added to it (with its target) and the build goes on
    without it; otherwise it is raised."""
    entities = composition.declared()
    _check_settings(composition.sets, entities, file)
    params, constants = _split_settings(composition.sets, entities)
    graph = _new_graph(composition, file)
    robot = composition.scalars.get("robot")
    for name, spec in entities.items():
        graph.add(_make_entity(name, spec, params.get(name, {}), robot))
    for target, (source, at) in composition.plugs.items():
        try:
            graph.plug(source, target)
        except DGraphError as exc:
            error = _refusal(exc, at, (source, target), entities)
            if refused is None:
                raise error from None
            refused.append((target, error))
    for key, (value, at) in constants.items():
        refused = _set_constant(graph, key, value)
        if refused:
            raise _refusal(refused, at, (key,), entities)
    for key, at in composition.records.items():
        try:
            graph.signal(key)
        except DGraphError as exc:
            raise _refusal(exc, at, (key,), entities, f"recorded signal {key!r}: ") from None
    for entity in graph:
        problems = entity.check()
        if problems:
            raise entities[entity.name].at.error("; ".join(problems))
    return graph


def _refusal(exc: DGraphError, at: _At, keys: Iterable[str], entities: dict[str, _Entity],
             prefix: str = "") -> GraphFileError:
    """The error of a plug, setting or record that the graph refused, at its own place, or at
    the definition of an entity it names if a nearer file (re)defined that entity."""
    blame = _latest(at, *(entities[_owner(key)].at for key in keys if _owner(key) in entities))
    note = "" if blame is at else f" (from {at.where()})"
    return blame.error(f"{prefix}{exc}{note}", exc)


def _check_settings(settings: dict[str, tuple[Any, _At]], entities: dict[str, _Entity], file: str) -> None:
    """Every setting names an entity of the graph."""
    for key, (_, at) in settings.items():
        entity, _, name = key.partition(".")
        if not name:
            raise at.error(f"{key!r} must read 'entity.name'")
        if entity not in entities:
            raise at.error(f"no entity {entity!r} in {file}{_suggest(entity, entities)}")


def _new_graph(composition: _Composition, file: str) -> Graph:
    """The empty graph with the chain's name, dt and duration."""
    top = _At(composition.top, ())
    dt, dt_at = composition.scalars.get("dt", (0.001, top))
    name = composition.scalars.get("name", (Path(file).stem or "graph", top))[0]
    try:
        graph = Graph(dt=dt, name=name)
    except DGraphError as exc:
        raise dt_at.error(str(exc), exc) from None
    duration, at = composition.scalars.get("duration", (None, top))
    if duration is not None and not math.isfinite(duration):
        raise at.error(f"duration must be finite, got {duration!r}")
    graph.duration = duration
    return graph


def _make_entity(name: str, spec: _Entity, settings: dict[str, tuple[Any, _At]],
                 robot: tuple[str, _At] | None) -> Any:
    try:
        cls = get_type(spec.type)
    except DGraphError as exc:
        raise spec.where("type").error(str(exc), exc) from None
    params, blame = _params(name, spec, cls._param_decls, settings, robot)
    try:
        return cls(name, **params)
    except DGraphError as exc:
        raise blame.error(str(exc), exc) from None
    except Exception as exc:  # an entity constructor failing on odd values must not crash the loader
        raise blame.error(f"{name} ({spec.type}) could not be built: {type(exc).__name__}: {exc}") from None


def _params(name: str, spec: _Entity, decls: dict[str, Param], settings: dict[str, tuple[Any, _At]],
            robot: tuple[str, _At] | None) -> tuple[dict[str, Any], _At]:
    """The entity's parameters: its definition's, over them the settings of the files and the
    command line, and the graph's robot as the ``model`` that none of them gives; and where a
    refusal of the constructor is reported (the nearest file that had a say)."""
    params = {key: _path_param(decls.get(key), value, spec.at.doc) for key, value in spec.params.items()}
    extra = dict(settings)
    if robot is not None and "model" in decls and "model" not in params:
        extra.setdefault("model", robot)
    blame = spec.where("params")
    for key, (value, at) in extra.items():
        try:
            decls[key].convert(value, name)
        except DGraphError as exc:
            raise at.error(str(exc), exc) from None
        params[key] = _path_param(decls[key], value, at.doc)
        blame = _latest(blame, at)
    return params, blame


def declared_entities(data: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Entity specs of parsed data (see :func:`parse`), including the Recorder that ``record``
    stands for."""
    entities = dict(data["entities"])
    if "record" in data:
        entities[RECORDER_NAME] = {"type": "Recorder", "params": {"signals": data["record"]}}
    return entities


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


def dumps(graph: Graph, folder: str | Path | None = None) -> str:
    """The graph-file text of ``graph``: the robot named once (``robot``, for every ``model``
    that is that robot), ``path`` parameters relative to ``folder`` (default: the working
    directory, where :func:`loads` without a file name looks for them)."""
    robot = _robot(graph)
    folder = Path(folder) if folder is not None else None
    data: dict[str, Any] = {"name": graph.name, "dt": graph.dt}
    if graph.duration is not None:
        data["duration"] = graph.duration
    if robot is not None:
        data["robot"] = robot
    data["entities"] = {e.name: _saved_entity(e, robot, folder) for e in graph}
    data["plugs"] = [f"{a} -> {b}" for a, b in graph.plugs()]
    constants = {inp.full_name: to_plain(inp.value, inp.full_name)
                 for e in graph for inp in e.inputs.values() if inp.is_set}
    if constants:
        data["set"] = constants
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)


def _robot(graph: Graph) -> str | None:
    """The robot most entities give as their ``model`` (None if none names one)."""
    names = Counter(e.given_params["model"] for e in graph if isinstance(e.given_params.get("model"), str))
    return names.most_common(1)[0][0] if names else None


def _saved_entity(entity: Any, robot: str | None, folder: Path | None) -> dict[str, Any]:
    """An entity's type and given parameters, as a file with ``robot`` must say them."""
    decls = type(entity)._param_decls
    params = {key: to_plain(_relative(value, decls[key], folder), f"{entity.name}.{key}")
              for key, value in entity.given_params.items() if not (key == "model" and _is(value, robot))}
    model = decls.get("model")
    if robot is not None and model is not None and "model" not in entity.given_params and model.default != robot:
        params["model"] = to_plain(model.default, f"{entity.name}.model")  # not the robot it would get
    spec: dict[str, Any] = {"type": entity.type_name}
    if params:
        spec["params"] = params
    return spec


def _is(value: Any, robot: str | None) -> bool:
    """``value`` names ``robot`` (a model may be a ``pinocchio.Model``, not comparable to text)."""
    return isinstance(value, str) and value == robot


def save(graph: Graph, path: str | Path) -> None:
    """Write ``graph`` to ``path`` as a graph file (paths relative to the file's folder)."""
    Path(path).write_text(dumps(graph, Path(path).parent))
