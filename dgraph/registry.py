"""The entity-type registry: type name -> entity class.

Built-in families and plugins register through the ``dgraph.entities`` entry-point group
(each entry point names a module whose import registers its classes with :func:`register`).
Graph files can only create types found here: nothing is imported by a name read from a file.

Each plugin loads on its own: one that fails to import (a missing dependency, a bug) is recorded
with its own error (:func:`plugin_errors`) and named in the error of any type that is not found,
while every other family loads normally.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable
from importlib.metadata import entry_points
from typing import TYPE_CHECKING, TypeVar, overload

from dgraph.errors import RegistryError

if TYPE_CHECKING:
    from dgraph.entity import Entity

E = TypeVar("E", bound="type[Entity]")

ENTRY_POINT_GROUP = "dgraph.entities"
_TYPES: dict[str, type[Entity]] = {}
_plugins_loaded = False
_TRIED: set[tuple[str, str]] = set()
"""The ``(name, module)`` of every entry point whose import was attempted (once each)."""
_FAILED: dict[str, tuple[str, Exception]] = {}
"""Each plugin that failed to load, by entry-point name: what to report, and its own exception."""


@overload
def register(cls: E, *, name: str | None = None) -> E: ...


@overload
def register(cls: None = None, *, name: str | None = None) -> Callable[[E], E]: ...


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
    """Import every module advertised in the ``dgraph.entities`` entry-point group, each once
    and on its own: a plugin that fails is recorded (:func:`plugin_errors`), the next ones load."""
    global _plugins_loaded
    if _plugins_loaded:
        return
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        key = (ep.name, ep.value)
        if key in _TRIED:  # loaded or failed already (or being loaded: a plugin asking for a type)
            continue
        _TRIED.add(key)
        try:
            ep.load()
        except Exception as exc:  # a broken plugin must not hide the others
            _FAILED[ep.name] = (f"entity plugin {ep.name!r} ({ep.value}) failed to load: "
                                f"{type(exc).__name__}: {exc}", exc)
    _plugins_loaded = True


def plugin_errors() -> dict[str, str]:
    """The plugins that failed to load (after :func:`load_plugins`): name -> what went wrong."""
    return {name: message for name, (message, _) in _FAILED.items()}


def get_type(type_name: str) -> type[Entity]:
    """The entity class registered as ``type_name`` (loads plugins on first use)."""
    if type_name not in _TYPES:
        load_plugins()
    try:
        return _TYPES[type_name]
    except KeyError:
        first_failure = next(iter(_FAILED.values()), (None, None))[1]
        raise _unknown(type_name) from first_failure


def _unknown(type_name: str) -> RegistryError:
    """The error of an unknown type: close names, and the plugins that failed to load (it may be
    one of theirs)."""
    close = difflib.get_close_matches(str(type_name), _TYPES, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    if _FAILED:
        hint += "; it may come from a plugin that failed to load: " + "; ".join(plugin_errors().values())
    return RegistryError(f"unknown entity type {type_name!r}{hint}")


def entity_types() -> dict[str, type[Entity]]:
    """All registered entity types, plugins included, sorted by name (without those of plugins
    that failed to load: :func:`plugin_errors`)."""
    load_plugins()
    return dict(sorted(_TYPES.items()))
