"""Structured value types: the classes that structured signals carry between entities.

A class decorated with :func:`value_type` can be a port's ``dtype`` (no other class can):
plugging then checks that the output's class is the input's class or a subclass of it (see
:meth:`Spec.accepts`). A class that can be written in a graph file (a priority stack, later a
footstep plan) defines a class method ``from_plain(value)`` that builds it from plain data
(lists, numbers, strings), raising ``TypeError`` or ``ValueError`` on what it cannot take. The
registry lets tools list the vocabulary of a graph (``dgraph check``, the tests that try every
pair of types) without building any entity. The core knows the classes only by this registry:
they are defined next to the entities that make them.
"""

from __future__ import annotations

from typing import TypeVar

from dgraph.errors import RegistryError

T = TypeVar("T", bound=type)

VALUE_TYPES: dict[str, type] = {}
"""Every registered structured value type, by class name."""


def value_type(cls: T) -> T:
    """Register ``cls`` as a structured value type (a class decorator); names are unique."""
    known = VALUE_TYPES.get(cls.__name__)
    if known is not None and known.__module__ != cls.__module__:  # a reload replaces its own
        raise RegistryError(f"two structured value types are named {cls.__name__!r}: "
                            f"{known.__module__} and {cls.__module__}")
    VALUE_TYPES[cls.__name__] = cls
    return cls
