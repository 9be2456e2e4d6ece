"""The source of a graph file: its text read safely, converted to plain data, and the places
(file, line, key) in it that errors point at.

The YAML is composed with the safe loader and converted node by node; only plain scalars, lists
and mappings are accepted (no tags, anchors, aliases or merge keys), so a file can never
construct objects or run code. Only regular files are read, to a bounded size, and composing
stops past a bounded depth and number of values, so a hostile file is refused soon.
"""

from __future__ import annotations

import math
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from dgraph.errors import DGraphError, GraphFileError

MAX_BYTES = 4 * 1024 * 1024
"""Largest graph file read (a 10,000-entity chain is 0.9 MB, the shipped files under 6 KB)."""
MAX_DEPTH = 64
"""Deepest nesting of lists and mappings in a graph file (the top mapping is 1 deep)."""
MAX_NODES = 500_000
"""Most values (scalars, lists, mappings) in one graph file, which bounds the time spent on one
(a 10,000-entity chain has 110,000 and loads in 2 s, the shipped files have under 300)."""
MAX_NUMBER_CHARS = 64
COMMAND_LINE = "<command line>"

_INT, _FLOAT = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"
_PLAIN_TAGS = {
    "tag:yaml.org,2002:str", "tag:yaml.org,2002:int", "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:bool", "tag:yaml.org,2002:null",
}


class _LimitExceeded(Exception):
    """A graph file past :data:`MAX_DEPTH` or :data:`MAX_NODES`, seen while it is composed."""

    def __init__(self, message: str, line: int | None):
        super().__init__(message)
        self.line = line


def _too_deep() -> str:
    return f"lists and mappings nested more than {MAX_DEPTH} deep"


def _too_many() -> str:
    return f"more than {MAX_NODES} values in one file"


class PythonLoader(yaml.SafeLoader):
    """PyYAML's safe loader, stopped past :data:`MAX_DEPTH` levels or :data:`MAX_NODES` nodes
    as it composes: a pathological file is refused after a bounded amount of work."""

    _nodes = 0
    _depth = 0

    def compose_node(self, parent: Any, index: Any) -> yaml.Node:
        """One node of PyYAML's recursive composer, counted (a mapping's key, composed with
        ``index`` None, is as deep as its value, which is refused in its place)."""
        self._nodes += 1
        self._depth += 1
        try:
            if self._nodes > MAX_NODES or (self._depth > MAX_DEPTH and (parent is None or index is not None)):
                line = self.peek_event().start_mark.line + 1
                raise _LimitExceeded(_too_many() if self._nodes > MAX_NODES else _too_deep(), line)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def fetch_flow_collection_start(self, token_class: type) -> None:
        """PyYAML's scanner at ``[`` or ``{``, refused past ``MAX_DEPTH`` flow levels: it reads
        up to 1024 characters ahead of the composer, in time quadratic in the depth."""
        super().fetch_flow_collection_start(token_class)
        if self.flow_level > MAX_DEPTH:
            raise _LimitExceeded(_too_deep(), self.line + 1)


_YAML12_FLOAT = re.compile(r"^[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)[eE][-+]?[0-9]+$")
"""A YAML 1.2 core-schema float with an exponent (``1e3``, ``2.5e1``, ``-1E-2``, ``.5e1``): YAML 1.1,
which PyYAML reads, requires a dot and a signed exponent, and resolves these as strings."""


def _read_yaml12_floats(loader: type) -> None:
    """Resolve :data:`_YAML12_FLOAT` scalars as floats with ``loader`` (the resolver is Python
    code in libyaml's loader too); the other YAML 1.1 resolvers stay."""
    loader.add_implicit_resolver(_FLOAT, _YAML12_FLOAT, list("-+0123456789."))


_read_yaml12_floats(PythonLoader)

_SAFE_LOADER: type = PythonLoader
"""libyaml's safe loader when PyYAML was built with it (10x faster on large files), else PyYAML's."""
if getattr(yaml, "__with_libyaml__", False):
    class LibyamlLoader(yaml.CSafeLoader):
        """libyaml's safe loader, stopped past :data:`MAX_NODES` nodes without an explicit tag
        as it composes (each costs a call of :meth:`resolve`; the others cost no Python, and
        :func:`plain_data` counts them). libyaml stops at 1000 levels itself, and
        :func:`plain_data` refuses what is deeper than :data:`MAX_DEPTH`."""

        _nodes = 0

        def resolve(self, kind: type, value: Any, implicit: Any) -> str:
            """The tag of a node without an explicit one; counts the nodes."""
            self._nodes += 1
            if self._nodes > MAX_NODES:
                raise _LimitExceeded(_too_many(), None)
            return super().resolve(kind, value, implicit)

    _read_yaml12_floats(LibyamlLoader)
    _SAFE_LOADER = LibyamlLoader


def key_of(path: tuple[Any, ...]) -> str:
    """The dotted key of ``path`` (empty for the whole file)."""
    return ".".join(map(str, path))


class Document:
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
        return GraphFileError(message, file=self.file, line=self.line(path), key=key_of(path) or None,
                              entity=cause.entity if cause else None, signal=cause.signal if cause else None)


@dataclass(frozen=True)
class At:
    """Where a piece of the graph was written: a file and the path of its key."""

    doc: Document
    path: tuple[Any, ...]

    def error(self, message: str, cause: DGraphError | None = None) -> GraphFileError:
        """A :class:`GraphFileError` located here."""
        return self.doc.error(message, self.path, cause)

    def where(self) -> str:
        """``file:line [key]``, for messages that point at a second place."""
        line = self.doc.line(self.path)
        return f"{self.doc.file}{f':{line}' if line else ''} [{key_of(self.path)}]"

    def within(self, *keys: Any) -> At:
        """The place of ``keys`` under this one."""
        return At(self.doc, (*self.path, *keys))


def latest(first: At, *others: At) -> At:
    """The place written by the nearest file of the chain (``first`` on a tie)."""
    return max((first, *others), key=lambda at: at.doc.layer)


class Unreadable(GraphFileError):
    """A file that is not read: not a regular file, larger than its limit, or a path that names
    nothing; ``reason`` says why, without the file (a caller that points elsewhere uses it)."""

    def __init__(self, reason: str, file: str):
        super().__init__(f"cannot read: {reason}", file=file)
        self.reason = reason


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))


def _refused(status: os.stat_result, path: str, limit: int, what: str) -> None:
    """Refuse (:class:`Unreadable`) what is not a regular file of at most ``limit`` bytes."""
    if not stat.S_ISREG(status.st_mode):
        kind = next((name for test, name in _KINDS if test(status.st_mode)), "another kind of file")
        raise Unreadable(f"not a regular file ({kind})", path)
    if status.st_size > limit:
        raise Unreadable(f"{status.st_size} bytes: larger than {limit} bytes, the limit of {what}", path)


def _os_reason(exc: OSError | ValueError) -> str:
    if isinstance(exc, ValueError):  # os functions refuse a path with a NUL byte so
        return "the path holds a NUL byte" if "null" in str(exc) else str(exc)
    return exc.strerror or str(exc)


def check_regular(path: str | Path, limit: int, what: str = "a graph file") -> os.stat_result:
    """The status of ``path``, a regular file of at most ``limit`` bytes; else :class:`Unreadable`.
    Only looked at: a FIFO, a device, a directory or a socket is never opened."""
    try:
        status = os.stat(path)
    except (OSError, ValueError) as exc:
        raise Unreadable(_os_reason(exc), str(path)) from exc
    _refused(status, str(path), limit, what)
    return status


def read_bytes(path: str | Path, limit: int, what: str = "a graph file") -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes (:class:`Unreadable`
    if not). Checked before it is opened, opened without blocking (a FIFO swapped in after the
    check is not waited for) and checked again, read to at most ``limit`` bytes. A file of size
    0 is not read: it is empty, or a ``/proc`` file that may never end (``/proc/kmsg``)."""
    check_regular(path, limit, what)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except (OSError, ValueError) as exc:
        raise Unreadable(_os_reason(exc), str(path)) from exc
    with os.fdopen(fd, "rb") as f:
        status = os.fstat(fd)
        _refused(status, str(path), limit, what)
        try:
            data = f.read(limit + 1) if status.st_size else b""
        except OSError as exc:
            raise Unreadable(_os_reason(exc), str(path)) from exc
    if len(data) > limit:  # it grew since it was looked at
        raise Unreadable(f"larger than {limit} bytes, the limit of {what}", str(path))
    return data


def read_text(path: str | Path) -> str:
    """The text of a graph file (:class:`GraphFileError` if not a regular file of at most
    ``MAX_BYTES``, or not UTF-8): a device such as ``/dev/zero`` or a FIFO is never read."""
    data = read_bytes(path, MAX_BYTES)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise GraphFileError(f"not UTF-8 text: {exc.reason}", file=str(path)) from exc


def plain_data(text: str, file: str) -> tuple[Any, Document]:
    """The plain data of one file's YAML text, and its line map; the text refused if larger
    than ``MAX_BYTES``, nested deeper than ``MAX_DEPTH`` or holding more than ``MAX_NODES``
    values."""
    doc = Document(file)
    if len(text) > MAX_BYTES:
        raise GraphFileError(f"larger than {MAX_BYTES} bytes, the limit of a graph file", file=file)
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
        if "maximum nesting depth" in problem:  # libyaml's own limit, past MAX_DEPTH
            raise GraphFileError(_too_deep(), file=file, line=mark.line + 1 if mark else None) from exc
        raise GraphFileError(_yaml_reason(exc, problem, one_line=file == COMMAND_LINE), file=file,
                             line=mark.line + 1 if mark else None) from exc
    except _LimitExceeded as exc:
        raise GraphFileError(str(exc), file=file, line=exc.line) from exc
    except RecursionError as exc:
        raise GraphFileError(_too_deep(), file=file) from exc
    finally:
        if loader is not None:
            loader.dispose()
    return data, doc


_TOKEN_WORDS = (("'<stream end>'", "the end of the file"), ("<block end>", "the end of the block"),
                ("'<block mapping start>'", "a more indented key"))
"""PyYAML's names of tokens, in words."""


def _yaml_reason(exc: yaml.YAMLError, problem: str, one_line: bool = False) -> str:
    """A YAML syntax error in one line: the column it was found at, PyYAML's or libyaml's
    problem, and the construct it was found in (``the block mapping at line 2, column 3``)
    when that is short; the line is the error's own. A block construct hints at indentation.
    ``one_line`` (a value of the command line) names columns only, or the end of the value."""
    problem = " ".join(problem.split())
    for token, words in _TOKEN_WORDS:
        problem = problem.replace(token, words)
    mark = getattr(exc, "problem_mark", None)
    where = "" if mark is None else f" at column {mark.column + 1}" if not (one_line and mark.line) else " at its end"
    context = " ".join((getattr(exc, "context", None) or "").split())
    context_mark = getattr(exc, "context_mark", None)
    inside = ""
    construct = context.removeprefix("while parsing ").removeprefix("while scanning ")
    if construct.startswith(("a ", "an ")) and len(construct) <= 40:
        inside = f", in {construct}"
        if context_mark is not None and (mark is None or (context_mark.line, context_mark.column)
                                         != (mark.line, mark.column)):
            line = "" if one_line and not context_mark.line else f" line {context_mark.line + 1},"
            inside += f" started at{line} column {context_mark.column + 1}"
        if "block" in construct:
            inside += " (check the indentation)"
    return f"invalid YAML{where}: {problem}{inside}"


def _node_error(doc: Document, message: str, node: yaml.Node, path: tuple[Any, ...]) -> GraphFileError:
    """An error at the line of ``node`` itself (a key, or a scalar not yet in the line map)."""
    return GraphFileError(message, file=doc.file, line=node.start_mark.line + 1, key=key_of(path) or None)


def _convert(doc: Document, node: yaml.Node, path: tuple[Any, ...], seen: set[int],
             loader: yaml.SafeLoader) -> Any:
    if id(node) in seen:
        raise doc.error("anchors and aliases are not allowed in graph files", path)
    if len(path) >= MAX_DEPTH:  # the key: the first 8 of the path's 64
        raise _node_error(doc, _too_deep(), node, path[:8])
    if len(seen) >= MAX_NODES:
        raise _node_error(doc, _too_many(), node, path)
    seen.add(id(node))
    doc.lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        return _mapping(doc, node, path, seen, loader)
    if isinstance(node, yaml.SequenceNode):
        if node.tag != "tag:yaml.org,2002:seq":
            raise doc.error(f"tag {node.tag!r} is not allowed", path)
        return [_convert(doc, item, (*path, i), seen, loader) for i, item in enumerate(node.value)]
    if node.tag not in _PLAIN_TAGS:
        raise doc.error(f"tag {node.tag!r} is not allowed (only plain strings, numbers, booleans, null)", path)
    return _scalar(doc, node, path, loader)


def _mapping(doc: Document, node: yaml.MappingNode, path: tuple[Any, ...], seen: set[int],
             loader: yaml.SafeLoader) -> dict[str, Any]:
    if node.tag != "tag:yaml.org,2002:map":
        raise doc.error(f"tag {node.tag!r} is not allowed", path)
    out: dict[str, Any] = {}
    for key_node, value_node in node.value:
        if not isinstance(key_node, yaml.ScalarNode) or key_node.tag not in _PLAIN_TAGS:
            raise _node_error(doc, "mapping keys must be plain scalars (no merge keys or tags)", key_node, path)
        key = key_node.value  # the text as written: `off:` names 'off', not False
        if key in out:
            raise _node_error(doc, f"duplicate key {key!r}", key_node, (*path, key))
        out[key] = _convert(doc, value_node, (*path, key), seen, loader)
        doc.lines[(*path, key)] = key_node.start_mark.line + 1  # errors point at the key
    return out


def _shortened(text: str) -> str:
    return f"{text[:24]}{'...' if len(text) > 24 else ''}"


def _scalar(doc: Document, node: yaml.Node, path: tuple[Any, ...], loader: yaml.SafeLoader) -> Any:
    """A plain scalar's value; an explicit tag on text that does not parse is a file error."""
    if node.tag in (_INT, _FLOAT) and (":" in node.value or len(node.value) > MAX_NUMBER_CHARS):
        # YAML 1.1 base-60 numbers (1:30) are refused, and so are absurdly long ones: PyYAML
        # converts both in quadratic time
        raise _node_error(doc, f"{_shortened(node.value)} is not a supported number", node, path)
    try:
        value = loader.construct_object(node)
    except (ValueError, KeyError, IndexError, TypeError, OverflowError, yaml.YAMLError) as exc:
        raise _node_error(doc, f"{node.value!r} is not a valid {node.tag.rsplit(':', 1)[-1]}", node, path) from exc
    too_large = (isinstance(value, float) and math.isinf(value) and node.value.lower().lstrip("+-") != ".inf") or (
        isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 2**63)
    if too_large:
        raise _node_error(doc, f"number {_shortened(node.value)} is too large", node, path)
    return value
