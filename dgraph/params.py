"""Typed entity parameters, fixed at construction (``Gain("k", size=3)``).

A :class:`Param` declared as a class attribute validates and converts the keyword given to the
constructor. Parameters are construction-time configuration (sizes, modes, file names);
anything that changes while the graph runs is an input signal instead.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from dgraph.errors import ParamError

REQUIRED = object()
MAX_SIZE = 1_000_000
"""Largest vector size a parameter may ask for."""
MAX_PORTS = 256
"""Largest number of per-instance ports (variadic inputs) a parameter may ask for."""


def _to_float(v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise TypeError(f"expected a number, got {type(v).__name__}")
    if v != v:
        raise TypeError("expected a number, got NaN")
    return float(v)


def _to_int(v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
        raise TypeError(f"expected an int, got {type(v).__name__}")
    return int(v)


def _to_bool(v: Any) -> bool:
    if not isinstance(v, (bool, np.bool_)):
        raise TypeError(f"expected true or false, got {type(v).__name__}")
    return bool(v)


def _to_str(v: Any) -> str:
    if not isinstance(v, str):
        raise TypeError(f"expected a string, got {type(v).__name__}")
    return v


def _to_vector(v: Any) -> np.ndarray:
    if isinstance(v, (str, bytes, dict)):
        raise TypeError(f"expected a list of numbers, got {type(v).__name__}")
    arr = np.array(v, dtype=float)
    if arr.ndim > 2:
        raise TypeError(f"expected a vector or matrix, got {arr.ndim} dimensions")
    if np.isnan(arr).any():
        raise TypeError("contains NaN")
    return arr


def _to_str_list(v: Any) -> list[str]:
    if isinstance(v, str) or not isinstance(v, Sequence):
        raise TypeError(f"expected a list of strings, got {type(v).__name__}")
    if not all(isinstance(x, str) for x in v):
        raise TypeError("expected a list of strings")
    return list(v)


def _to_name_or_path(v: Any) -> Any:
    if isinstance(v, bytes):
        raise TypeError("expected a name or a path, got bytes")
    return v  # a string; or an object built in Python (a pinocchio.Model), for the entity to check


def _to_int_list(v: Any) -> list[int]:
    if isinstance(v, str) or not isinstance(v, (Sequence, np.ndarray)):
        raise TypeError(f"expected a list of ints, got {type(v).__name__}")
    return [_to_int(x) for x in v]


KINDS: dict[str, Callable[[Any], Any]] = {
    "float": _to_float, "int": _to_int, "bool": _to_bool, "str": _to_str, "path": _to_str,
    "name_or_path": _to_name_or_path, "vector": _to_vector, "str_list": _to_str_list, "path_list": _to_str_list,
    "int_list": _to_int_list, "object": lambda v: v,
}


class Param:
    """A typed constructor parameter.

    Args:
        default: value when not given (omit for a required parameter).
        kind: ``float``, ``int``, ``bool``, ``str``, ``path`` (an input file: a relative path
            in a graph file is taken from the file's folder, and written relative to the folder
            of the file a graph is saved to; in Python, from the working directory),
            ``name_or_path`` (a name, or the path of a file, taken as ``path``'s: a string with
            a folder separator or a suffix such as ``.urdf``, or naming a file, is a path; any
            other string a name, kept as it is; a value built in Python that is not a string,
            such as a ``pinocchio.Model``, is passed as it is for the entity to check),
            ``vector`` (numbers -> ndarray), ``str_list``, ``path_list`` (strings, each a path
            taken as ``path``'s, a folder as well as a file), ``int_list`` or ``object``
            (anything; not saveable to a graph file unless it is plain data).
        doc: one line shown by ``dgraph entities``.
        choices: allowed values.
        optional: ``None`` is accepted in addition to ``kind``.
        minimum, maximum: bounds of a number, or of every element of a ``vector`` or an
            ``int_list`` (sizes are bounded so that a file cannot ask for a graph that exhausts
            the machine).
    """

    __slots__ = ("choices", "default", "doc", "kind", "maximum", "minimum", "name", "optional")

    def __init__(self, default: Any = REQUIRED, kind: str = "float", doc: str = "",
                 choices: Sequence[Any] | None = None, optional: bool = False,
                 minimum: float | None = None, maximum: float | None = None):
        if kind not in KINDS:
            raise ParamError(f"unknown parameter kind {kind!r}; expected one of {sorted(KINDS)}")
        self.default = default
        self.kind = kind
        self.doc = doc
        self.choices = tuple(choices) if choices is not None else None
        self.optional = optional or default is None
        self.minimum = minimum
        self.maximum = maximum
        self.name = ""

    @property
    def required(self) -> bool:
        """True if the constructor must be given this parameter."""
        return self.default is REQUIRED

    def convert(self, value: Any, entity: str) -> Any:
        """Validate and convert ``value``; raises :class:`ParamError` naming the entity."""
        if value is None and self.optional:
            return None
        try:
            out = KINDS[self.kind](value)
        except (TypeError, ValueError) as exc:
            raise ParamError(f"{entity}: parameter {self.name!r}: {exc}", entity=entity) from None
        if self.choices is not None and out not in self.choices:
            raise ParamError(f"{entity}: parameter {self.name!r} must be one of {list(self.choices)}, "
                             f"got {value!r}", entity=entity)
        if self._out_of_bounds(out):
            raise ParamError(f"{entity}: parameter {self.name!r} must be within [{self.minimum}, {self.maximum}], "
                             f"got {value!r}", entity=entity)
        return out

    def _out_of_bounds(self, value: Any) -> bool:
        """True if the number ``value``, or an element of a vector or list of numbers, lies
        outside ``[minimum, maximum]``."""
        if self.minimum is None and self.maximum is None:
            return False
        values = np.asarray(value, dtype=float)
        return bool((self.minimum is not None and (values < self.minimum).any())
                    or (self.maximum is not None and (values > self.maximum).any()))

    def describe(self) -> str:
        """``name: kind = default -- doc`` for listings."""
        default = "required" if self.required else repr(self.default)
        return f"{self.name}: {self.kind} = {default}" + (f"  -- {self.doc}" if self.doc else "")
