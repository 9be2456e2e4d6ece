"""The ``size`` convention shared by the operators: ``None`` for scalars, ``n`` for n-vectors."""

from __future__ import annotations

from typing import Any


def vector_shape(entity: Any) -> tuple[int, ...]:
    """``()`` when the entity's ``size`` parameter is None, else ``(size,)``."""
    return () if entity.size is None else (entity.size,)
