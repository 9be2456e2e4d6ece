"""``path`` parameters: read from the folder of the file that wrote them, written relative to
the folder of the file they go to."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dgraph.files.source import Document
from dgraph.params import Param


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
