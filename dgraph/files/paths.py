"""Paths in parameters: read from the folder of the file that wrote them, written relative to
the folder of the file they go to, and checked to name a regular file of a bounded size before
the entity that reads them is built.

Three parameter kinds hold paths: ``path`` (a file), ``name_or_path`` (a name, or a file's path:
see :func:`names_a_path`) and ``path_list`` (paths, folders as well as files, never checked).
The graph's ``robot`` key is a ``name_or_path`` (:data:`ROBOT`), whatever the ``model``
parameters it is given to declare.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dgraph.files.source import At, Document, Unreadable, check_regular
from dgraph.params import Param

MAX_DATA_BYTES = 256 * 1024 * 1024
"""Largest data file (a trajectory CSV or .npz) a graph file may name."""
ROBOT = Param(kind="name_or_path", doc="the graph's robot: a name, or the path of its model file")
"""The declaration of a graph file's ``robot`` key."""


def names_a_path(value: str, folder: Path | str | None = None) -> bool:
    """True if ``value``, of a ``name_or_path`` parameter, is a path, not a name: it has a folder
    separator or a suffix (``arm.urdf``), or names a file from ``folder`` (default: the working
    directory)."""
    return ("/" in value or os.sep in value or bool(Path(value).suffix)
            or os.path.isfile(os.path.join(folder or os.curdir, value)))


def _paths(value: Any, decl: Param | None, folder: Path | str | None) -> list[str] | None:
    """The paths that ``value`` holds for ``decl``'s kind, read from ``folder`` (None: it holds none)."""
    kind = decl.kind if decl is not None else None
    if kind == "path" and isinstance(value, str):
        return [value]
    if kind == "name_or_path" and isinstance(value, str) and value and names_a_path(value, folder):
        return [value]
    return None


def _map(value: Any, decl: Param | None, folder: Path | str | None, change: Any) -> Any:
    """``value`` with ``change`` applied to each path it holds (each string of a ``path_list``)."""
    if decl is not None and decl.kind == "path_list" and isinstance(value, list):
        return [change(v) if isinstance(v, str) and v else v for v in value]
    return change(value) if _paths(value, decl, folder) else value


def from_file(value: Any, decl: Param | None, doc: Document) -> Any:
    """A parameter's value with its paths taken from the folder of the file that wrote it."""
    folder = doc.folder
    if folder is None:
        return value
    return _map(value, decl, folder, lambda v: v if Path(v).is_absolute() else os.path.normpath(folder / v))


def relative(value: Any, decl: Param | None, folder: Path | None) -> Any:
    """A parameter's value with its paths relative to ``folder`` (default: the working directory)."""
    return _map(value, decl, None, lambda v: os.path.relpath(v, folder or os.curdir))


def check_data_file(value: Any, decl: Param | None, at: At) -> None:
    """Refuse, at ``at``, a ``path`` (or the path of a ``name_or_path``) that does not name a
    non-empty regular file of at most ``MAX_DATA_BYTES``: the file is looked at, never opened,
    so a FIFO, a device such as ``/dev/zero``, a directory, a socket or a ``/proc`` file (of
    size 0, which may never end) cannot hang the entity that would read it."""
    if not _paths(value, decl, None):
        return
    try:
        status = check_regular(value, MAX_DATA_BYTES, "a data file")
    except Unreadable as exc:
        raise at.error(f"cannot read data file {value!r}: {exc.reason}") from exc
    if status.st_size == 0:
        raise at.error(f"cannot read data file {value!r}: it is empty (size 0, as /proc files say)")
