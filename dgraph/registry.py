"""The entity-type registry: type name -> entity class.

Built-in families and plugins register through the ``dgraph.entities`` entry-point group
(each entry point names a module whose import registers its classes with :func:`register`).
Graph files can only create types found here: nothing is imported by a name read from a file.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable
from importlib.metadata import entry_points
from typing import TYPE_CHECKING, TypeVar

from dgraph.errors import RegistryError

if TYPE_CHECKING:
    from dgraph.entity import Entity

E = TypeVar("E", bound="type[Entity]")

ENTRY_POINT_GROUP = "dgraph.entities"
_TYPES: dict[str, type[Entity]] = {}
_plugins_loaded = False


def register(cls: E | None = None, *, name: str | None = None) -> E | Callable[[E], E]:
    """Class decorator registering an entity type under ``name`` (default: the class name).

    Usable as ``@register`` or ``@register(name="Alias")``.
    """

    def wrap(klass: E) -> E:
        type_name = name or klass.__name__
        known = _TYPES.get(type_name)
        if known is not None and known is not klass and known.__qualname__ != klass.__qualname__:
            raise RegistryError(f"entity type {type_name!r} is already registered by "
                                f"{known.__module__}.{known.__qualname__}")
        klass.type_name = type_name
        _TYPES[type_name] = klass
        return klass

    return wrap(cls) if cls is not None else wrap


def load_plugins() -> None:
    """Import every module advertised in the ``dgraph.entities`` entry-point group (once)."""
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        try:
            ep.load()
        except Exception as exc:  # a broken plugin must not hide the others
            raise RegistryError(f"entity plugin {ep.name!r} ({ep.value}) failed to load: {exc}") from exc


def get_type(type_name: str) -> type[Entity]:
    """The entity class registered as ``type_name`` (loads plugins on first use)."""
    if type_name not in _TYPES:
        load_plugins()
    try:
        return _TYPES[type_name]
    except KeyError:
        close = difflib.get_close_matches(str(type_name), _TYPES, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise RegistryError(f"unknown entity type {type_name!r}{hint}") from None


def entity_types() -> dict[str, type[Entity]]:
    """All registered entity types, plugins included, sorted by name."""
    load_plugins()
    return dict(sorted(_TYPES.items()))
