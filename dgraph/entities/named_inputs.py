"""Named, typed inputs: one per task or contact a solver-like entity is configured with."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import dgraph as dg


def declare_named_inputs(entity: dg.Entity, groups: Iterable[tuple[Sequence[str], type, str]],
                         reserved: Sequence[str] = ()) -> None:
    """Declare one input per name, typed by its group: ``groups`` holds ``(names, value type,
    what)`` triples, e.g. ``(entity.tasks, TaskEquation, "equation of task")``. A name must be
    unique across the groups, a Python identifier, and free (not a port, parameter or method
    of the entity's class, not in ``reserved``): ``ParamError`` otherwise."""
    groups = list(groups)
    names = [name for group, _, _ in groups for name in group]
    if len(set(names)) != len(names):
        raise dg.ParamError(f"{entity.name}: input names must be unique: {names}", entity=entity.name)
    for name in names:
        if not name.isidentifier() or hasattr(type(entity), name) or name in reserved:
            raise dg.ParamError(f"{entity.name}: {name!r} cannot name an input of {entity.type_name}",
                                entity=entity.name)
    for group, value_type, what in groups:
        for name in group:
            entity.declare(name, dg.Input(dtype=value_type, doc=f"{what} {name}"))
