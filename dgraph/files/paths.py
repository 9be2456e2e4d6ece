"""``path`` parameters: read from the folder of the file that wrote them, written relative to
the folder of the file they go to, and checked to name a regular file of a bounded size before
the entity that reads them is built."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dgraph.files.source import At, Document, Unreadable, check_regular
from dgraph.params import Param

MAX_DATA_BYTES = 256 * 1024 * 1024
"""Largest data file (a trajectory CSV or .npz) a graph file may name."""


def _is_path(decl: Param | None, value: Any) -> bool:
    return decl is not None and decl.kind == "path" and isinstance(value, str)


def from_file(value: Any, decl: Param | None, doc: Document) -> Any:
    """A ``path`` parameter's value, taken from the folder of the file that wrote it."""
    if not _is_path(decl, value) or doc.folder is None or Path(value).is_absolute():
        return value
    return os.path.normpath(doc.folder / value)


def relative(value: Any, decl: Param | None, folder: Path | None) -> Any:
    """A ``path`` parameter's value relative to ``folder`` (default: the working directory)."""
    if not _is_path(decl, value):
        return value
    return os.path.relpath(value, folder or os.curdir)


def check_data_file(value: Any, decl: Param | None, at: At) -> None:
    """Refuse, at ``at``, a ``path`` parameter that does not name a non-empty regular file of
    at most ``MAX_DATA_BYTES``: the file is looked at, never opened, so a FIFO, a device such as
    ``/dev/zero``, a directory, a socket or a ``/proc`` file (of size 0, which may never end)
    cannot hang the entity that would read it."""
    if not _is_path(decl, value):
        return
    try:
        status = check_regular(value, MAX_DATA_BYTES, "a data file")
    except Unreadable as exc:
        raise at.error(f"cannot read data file {value!r}: {exc.reason}") from exc
    if status.st_size == 0:
        raise at.error(f"cannot read data file {value!r}: it is empty (size 0, as /proc files say)")
