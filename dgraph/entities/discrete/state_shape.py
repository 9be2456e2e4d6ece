"""Shape and initial value shared by the discrete-state entities."""

from __future__ import annotations

from typing import Any

import numpy as np

from dgraph.errors import ParamError


def state_shape(entity: Any) -> tuple[int, ...]:
    """``()`` for a scalar state (``size`` None), else ``(size,)``."""
    return () if entity.size is None else (entity.size,)


def initial_state(entity: Any) -> Any:
    """The ``initial`` parameter broadcast to the state shape (zeros by default)."""
    shape = state_shape(entity)
    value = np.zeros(shape) if entity.initial is None else entity.initial
    try:
        value = np.broadcast_to(value, shape).copy()
    except ValueError:
        raise ParamError(f"{entity.name}: initial value of shape {np.shape(entity.initial)} "
                         f"does not fit size {entity.size}", entity=entity.name) from None
    return float(value) if shape == () else value
