"""The composition of a chain of graph files: the file, the files it ``extends``, each parsed
and schema-checked on its own, then laid over one another from the deepest base up (the
command line's settings last), into tables of entities, plugs, settings and records that
remember the file and key that wrote each entry.

A file may extend several files (``extends: [a.yaml, b.yaml]``): a's chain, then b's, each file
once, at its first place, so a base they share is applied once and b's own layers are laid over
what a's chain describes (a scenario on a shared layer: the 20 cm walk on the position scheme's
servos and stabiliser)."""

from __future__ import annotations

import difflib
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dgraph.errors import DGraphError, GraphFileError
from dgraph.files.paths import ROBOT, from_file, relative
from dgraph.files.schema import PLUG_RE, validate
from dgraph.files.source import (
    COMMAND_LINE,
    MAX_BYTES,
    At,
    Document,
    Unreadable,
    check_regular,
    latest,
    plain_data,
    read_text,
)
from dgraph.params import Param
from dgraph.registry import get_type

MAX_EXTENDS = 8
"""Longest chain of files extending one another."""
RECORDER_NAME = "recorder"
SCALARS = ("name", "dt", "duration", "robot")
"""Graph-level keys: the nearest file of a chain that gives one wins."""

Setting = tuple[Any, At]
"""A value and where it was set."""


class CommandLine(Document):
    """The ``--set entity.name=value`` settings of the command line: a last layer over the files."""

    def __init__(self) -> None:
        super().__init__(COMMAND_LINE)
        self.layer = MAX_EXTENDS + 1

    def error(self, message: str, path: tuple[Any, ...], cause: DGraphError | None = None) -> GraphFileError:
        """A :class:`GraphFileError` naming the ``--set`` option of ``path``."""
        key = str(path[-1])
        return GraphFileError(message, file=COMMAND_LINE, key=f"--set {key}",
                              entity=cause.entity if cause else key.partition(".")[0],
                              signal=cause.signal if cause else None)


def command_line_value(key: str, text: str) -> Any:
    """The value of ``--set key=text``: ``text`` read as YAML, a scalar or a list (``1.5``,
    ``[0, 0.05, 0]``, ``true``, ``abc``) with the loader of graph files; a mistake is a
    :class:`GraphFileError` naming the option, without a line."""
    try:
        value = plain_data(text, COMMAND_LINE)[0] if text.strip() else None
    except GraphFileError as exc:
        where = str(GraphFileError("", file=exc.file, line=exc.line, key=exc.key))
        reason = "missing value" if "file is empty" in str(exc) else str(exc).removeprefix(where)
        raise CommandLine().error(f"{text!r}: {reason}", (key,)) from exc
    if not text.strip():
        raise CommandLine().error("missing value", (key,))
    if isinstance(value, dict):
        raise CommandLine().error(f"{text!r}: expected a scalar or a list, got a mapping", (key,))
    return value


def command_line_settings(items: Iterable[str]) -> dict[str, Any]:
    """The settings of ``--set entity.name=value`` options, each value read by
    :func:`command_line_value`; what :func:`~dgraph.files.load` takes as ``overrides``."""
    out: dict[str, Any] = {}
    for item in items:
        key, eq, text = item.partition("=")
        key = key.strip()
        if not eq or key.count(".") != 1 or not all(key.partition(".")[::2]):
            raise GraphFileError(f"--set {item!r}: expected entity.name=value", file=COMMAND_LINE)
        out[key] = command_line_value(key, text)
    return out


def _parse_file(text: str, file: str) -> tuple[dict[str, Any], Document]:
    """Parse and schema-check the text of one file; returns the data and its line map."""
    data, doc = plain_data(text, file)
    return validate(data, doc), doc


def _chain(text: str, file: str) -> list[tuple[dict[str, Any], Document]]:
    """The file and every file it extends, the deepest base first (its layer is 0): the files
    each extends, in order, each with its own bases before it, every file once (at its first
    place), then the file."""
    chain: list[tuple[dict[str, Any], Document]] = []
    _append_with_bases(_parse_file(text, file), {_identity(file)} - {None}, set(), chain)
    for layer, (_, doc) in enumerate(chain):
        doc.layer = layer
    return chain


def _extended(data: dict[str, Any]) -> list[tuple[str, tuple[Any, ...]]]:
    """The files ``data`` extends, each with the key that names it (``extends``, or
    ``extends.i`` in a list)."""
    extends = data.get("extends")
    if extends is None:
        return []
    if isinstance(extends, str):
        return [(extends, ("extends",))]
    return [(name, ("extends", i)) for i, name in enumerate(extends)]


def _append_with_bases(parsed: tuple[dict[str, Any], Document], ancestors: set[tuple[int, int]],
                       applied: set[tuple[int, int]], chain: list[tuple[dict[str, Any], Document]]) -> None:
    """Append to ``chain`` the bases of ``parsed`` not yet in it, then ``parsed``. ``ancestors``:
    the files extending it, directly or not (itself included); ``applied``: the bases in ``chain``."""
    data, doc = parsed
    for extends, key in _extended(data):
        base = _base_path(extends, doc, key)
        identity = _base_identity(base, extends, doc, key)
        if identity in ancestors:
            raise doc.error(f"{extends!r} extends, directly or not, this file (a cycle)", key)
        if identity in applied:
            continue
        if len(applied | ancestors) >= MAX_EXTENDS:  # the files read so far
            raise doc.error(f"a chain of more than {MAX_EXTENDS} files extending one another", key)
        applied.add(identity)
        try:
            text = read_text(base)
        except GraphFileError as exc:
            raise _cannot_extend(extends, doc, key, exc) from exc
        _append_with_bases(_parse_file(text, str(base)), ancestors | {identity}, applied, chain)
    chain.append(parsed)


def _identity(file: str) -> tuple[int, int] | None:
    """The device and inode of ``file`` (its identity through any symlink), None if it names
    no file."""
    try:
        status = os.stat(file)
    except (OSError, ValueError):
        return None
    return status.st_dev, status.st_ino


def _base_path(extends: str, doc: Document, key: tuple[Any, ...]) -> Path:
    """The file that ``doc`` extends at ``key``, refused if not a .yaml graph file."""
    base = Path(doc.file).parent / extends
    if base.suffix not in (".yaml", ".yml"):
        raise doc.error(f"can only extend a .yaml graph file, not {extends!r}", key)
    return base


def _base_identity(base: Path, extends: str, doc: Document, key: tuple[Any, ...]) -> tuple[int, int]:
    """The identity of ``base``, refused (at ``doc``'s ``key``) if it is not a regular file within
    the size limit."""
    try:
        status = check_regular(base, MAX_BYTES)
    except Unreadable as exc:
        raise _cannot_extend(extends, doc, key, exc) from exc
    return status.st_dev, status.st_ino


def _cannot_extend(extends: str, doc: Document, key: tuple[Any, ...], exc: GraphFileError) -> GraphFileError:
    """The error, at ``doc``'s ``key`` (its ``extends``), of a base that cannot be read."""
    reason = exc.reason if isinstance(exc, Unreadable) else str(exc)
    return doc.error(f"cannot extend {extends!r}: {reason}", key)


@dataclass
class EntitySpec:
    """An entity as the files describe it: type, parameters, and where it was defined."""

    type: str
    params: dict[str, Any]
    at: At
    """Its definition: ``entities.NAME`` of a file (``record`` for the recorder it stands for)."""

    def where(self, *keys: str) -> At:
        """The place of its ``type``, its ``params`` or one of them (``"params", name``)."""
        return self.at.within(*keys) if self.at.path[0] == "entities" else self.at


def owner(key: str) -> str:
    """The entity of ``entity.name``."""
    return key.partition(".")[0]


def suggest(name: str, names: Iterable[str]) -> str:
    """``; did you mean 'x'?`` for the closest of ``names``, or nothing."""
    close = difflib.get_close_matches(name, list(names), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


class Composition:
    """A graph described by a chain of files, every piece with the file and key that wrote it."""

    def __init__(self, top: Document):
        self.top = top
        self.scalars: dict[str, Setting] = {}
        self.entities: dict[str, EntitySpec] = {}
        self.plugs: dict[str, tuple[str, At]] = {}  # input -> (output, where)
        self.sets: dict[str, Setting] = {}  # entity.name -> (value, where)
        self.records: dict[str, At] = {}

    def apply(self, data: dict[str, Any], doc: Document) -> None:
        """Lay one file over what the files it extends described."""
        for key in SCALARS:
            if key in data:
                self.scalars[key] = (data[key], At(doc, (key,)))
        self._remove(data.get("remove", {}), doc)
        for name, spec in data.get("entities", {}).items():
            self._define(name, spec, At(doc, ("entities", name)))
        for section in ("set", "overrides"):
            for key, value in data.get(section, {}).items():
                self._take(key, At(doc, (section, key)))
                self.sets[key] = (value, At(doc, (section, key)))
        for i, plug in enumerate(data.get("plugs", [])):
            source, target = PLUG_RE.match(plug).groups()
            self._take(target, At(doc, ("plugs", i)))
            self.plugs[target] = (source, At(doc, ("plugs", i)))
        for i, key in enumerate(data.get("record", [])):
            if key in self.records:
                raise At(doc, ("record", i)).error(f"{key} is already recorded ({self.records[key].where()})")
            self.records[key] = At(doc, ("record", i))

    def _define(self, name: str, spec: dict[str, Any], at: At) -> None:
        """Add or replace entity ``name``: the parameters its definition gives win over what the
        files below set on them (the nearest file decides); their other settings stay."""
        self.entities[name] = EntitySpec(spec["type"], dict(spec.get("params") or {}), at)
        for param in self.entities[name].params:
            self.sets.pop(f"{name}.{param}", None)

    def _take(self, key: str, at: At) -> None:
        """Forget what the files below plugged into or set on ``key``: ``at`` replaces it. One
        file may not say it twice."""
        for table, how in ((self.plugs, "plugged"), (self.sets, "set")):
            earlier = table.pop(key, None)
            if earlier is not None and earlier[1].doc is at.doc:
                raise at.error(f"{key} is already {how} by this file ({earlier[1].where()})")

    def _remove(self, remove: dict[str, list[str]], doc: Document) -> None:
        for i, name in enumerate(remove.get("entities", [])):
            self._remove_entity(name, At(doc, ("remove", "entities", i)))
        for i, text in enumerate(remove.get("plugs", [])):
            self._unplug(text, At(doc, ("remove", "plugs", i)))
        for section, table, how in (("set", self.sets, "set"), ("record", self.records, "recorded")):
            for i, key in enumerate(remove.get(section, [])):
                if table.pop(key, None) is None:
                    raise At(doc, ("remove", section, i)).error(
                        f"{key} is not {how} by the files this one extends{suggest(key, table)}")

    def _remove_entity(self, name: str, at: At) -> None:
        """Take out entity ``name`` with every plug, setting and record that names it."""
        if self.entities.pop(name, None) is None:
            raise at.error(f"no entity {name!r} to remove in the files this one extends{suggest(name, self.entities)}")
        self.plugs = {t: (s, a) for t, (s, a) in self.plugs.items() if name not in (owner(t), owner(s))}
        self.sets = {key: v for key, v in self.sets.items() if owner(key) != name}
        self.records = {key: a for key, a in self.records.items() if owner(key) != name}

    def _unplug(self, text: str, at: At) -> None:
        """Take out the plug ``source -> target``, or whatever is plugged into ``target``."""
        source, arrow, target = (part.strip() for part in text.rpartition("->"))
        plugged = self.plugs.get(target)
        if plugged is None or (arrow and plugged[0] != source):
            found = f" ({target} is plugged to {plugged[0]})" if plugged else ""
            raise at.error(f"no plug {text.strip()!r} in the files this one extends{found}")
        del self.plugs[target]

    def declared(self) -> dict[str, EntitySpec]:
        """The entities, with the Recorder that ``record`` stands for."""
        if not self.records:
            return dict(self.entities)
        record = At(list(self.records.values())[-1].doc, ("record",))
        if RECORDER_NAME in self.entities:
            raise latest(record, self.entities[RECORDER_NAME].at).error(
                f"'record' creates an entity named {RECORDER_NAME!r}, which already exists")
        return {**self.entities, RECORDER_NAME: EntitySpec("Recorder", {"signals": list(self.records)}, record)}

    def flat(self) -> dict[str, Any]:
        """The plain data of one file, in the top file's folder, that describes this graph."""
        params, constants = split_settings(self.sets, self.entities)
        data: dict[str, Any] = {key: self.scalars[key][0] for key in SCALARS if key in self.scalars}
        if "robot" in self.scalars:  # a name, or a path: from the top file's folder
            robot, at = self.scalars["robot"]
            data["robot"] = relative(from_file(robot, ROBOT, at.doc), ROBOT, self.top.folder)
        data["entities"] = {name: _flat_entity(spec, params.get(name, {}), self.top.folder)
                            for name, spec in self.entities.items()}
        if self.plugs:
            data["plugs"] = [f"{source} -> {target}" for target, (source, _) in self.plugs.items()]
        if constants:
            data["set"] = {key: value for key, (value, _) in constants.items()}
        if self.records:
            data["record"] = list(self.records)
        return data


def compose(text: str, file: str, command_line: dict[str, Any] | None = None) -> Composition:
    """The graph that the file and the files it extends describe, then the command line's settings."""
    chain = _chain(text, file)
    composition = Composition(chain[-1][1])
    for data, doc in chain:
        composition.apply(data, doc)
    if command_line:
        composition.apply({"set": command_line}, CommandLine())
    return composition


def _decls(spec: EntitySpec | None) -> dict[str, Param]:
    """The parameter declarations of an entity's type (none if the type is unknown)."""
    try:
        return get_type(spec.type)._param_decls if spec is not None else {}
    except DGraphError:
        return {}  # the unknown type is reported where the entity is made


def split_settings(settings: dict[str, Setting], entities: dict[str, EntitySpec]
                   ) -> tuple[dict[str, dict[str, Setting]], dict[str, Setting]]:
    """Sort ``entity.name`` settings into parameters (by entity) and input constants."""
    params: dict[str, dict[str, Setting]] = {}
    constants: dict[str, Setting] = {}
    for key, setting in settings.items():
        entity, _, name = key.partition(".")
        if name in _decls(entities.get(entity)):
            params.setdefault(entity, {})[name] = setting
        else:
            constants[key] = setting
    return params, constants


def _flat_entity(spec: EntitySpec, settings: dict[str, Setting], folder: Path | None) -> dict[str, Any]:
    """An entity's type and parameters (its definition's, then the settings'), paths from ``folder``."""
    decls = _decls(spec)
    params = {key: (value, spec.at.doc) for key, value in spec.params.items()}
    params.update({key: (value, at.doc) for key, (value, at) in settings.items()})
    out: dict[str, Any] = {"type": spec.type}
    if params:
        out["params"] = {key: relative(from_file(value, decls.get(key), doc), decls.get(key), folder)
                         for key, (value, doc) in params.items()}
    return out


def parse(text: str, file: str = "<string>") -> dict[str, Any]:
    """The graph that graph-file text describes, as the plain data of one file without
    ``extends`` (the files it extends composed, parameters given by ``set`` folded into their
    entities, paths (of ``path``, ``name_or_path`` and ``path_list`` parameters, and a ``robot``
    that is one) relative to the file's folder). Its pieces come from several
    files, so it has no line map: errors found later are located by :func:`~dgraph.files.loads`.

    The YAML, the schema and what ``remove`` names are checked here; types, parameters and
    signals when the graph is built (:func:`~dgraph.files.loads`).
    """
    return compose(text, file).flat()


def declared_entities(data: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Entity specs of parsed data (see :func:`parse`), including the Recorder that ``record``
    stands for."""
    entities = dict(data["entities"])
    if "record" in data:
        entities[RECORDER_NAME] = {"type": "Recorder", "params": {"signals": data["record"]}}
    return entities
