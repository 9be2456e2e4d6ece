"""Checks of input constants beyond their specs, shared by the entity families: a constant that
is a scalar or one value per row (a gain, a weight), and the lines :meth:`Entity.check` reports
for the constants an entity holds (see :meth:`Entity.constant_problem <dgraph.Entity.constant_problem>`)."""

from __future__ import annotations

from typing import Any

import numpy as np

import dgraph as dg


def per_row_problem(value: Any, rows: int | None, each: str) -> str | None:
    """What is wrong with the constant ``value`` of an input that takes a scalar or ``rows``
    values (``each`` names one of them, e.g. ``"row of its feature posture.feature"``), or None;
    None too when ``rows`` is not known (nothing plugged yet)."""
    shape = np.shape(value)
    if rows is None or shape in ((), (rows,)):
        return None
    got = f"{shape[0]} values" if len(shape) == 1 else f"shape {shape}"
    return f"expected a scalar or {rows} values, one per {each}, got {got}"


def constant_problems(entity: dg.Entity) -> list[str]:
    """What ``entity.constant_problem`` says of the constant each of its unplugged inputs holds
    now (set or default), one line per input, for :meth:`Entity.check`: a constant set before
    what its length depends on was plugged is reported when the graph is validated."""
    found = []
    for inp in entity.inputs.values():
        if inp.source is None and (inp.is_set or inp.has_default):
            problem = entity.constant_problem(inp.name, inp.value)
            if problem is not None:
                found.append(f"input {inp.name}: {problem}")
    return found
