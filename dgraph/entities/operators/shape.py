"""The ``size`` convention shared by the operators: ``None`` for scalars, ``n`` for n-vectors."""

from __future__ import annotations

from typing import Any

import numpy as np


def vector_shape(entity: Any) -> tuple[int, ...]:
    """``()`` when the entity's ``size`` parameter is None, else ``(size,)``."""
    return () if entity.size is None else (entity.size,)


def shape_problem(value: Any, shapes: list[tuple[int, ...]]) -> str | None:
    """``expected a scalar or (3,), got shape (2,)`` when ``value``'s shape is none of ``shapes``
    (a constant's shape that its spec, any shape, does not say), else None."""
    shape = np.shape(value)
    if shape in shapes:
        return None
    names = ["a scalar" if s == () else str(s) for s in shapes]
    return f"expected {', '.join(names[:-1])}{' or ' if len(names) > 1 else ''}{names[-1]}, got shape {shape}"
