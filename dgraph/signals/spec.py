"""Signal specifications: the declared shape, dtype and component labels of a signal.

A :class:`Spec` is declared on a port (possibly with a shape that depends on the entity's
parameters) and resolved to concrete dimensions when the entity is built. It coerces values
that are set, checks values that are computed, and decides whether two ports may be plugged.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from dgraph.errors import NonFiniteError, SpecError
from dgraph.signals.value_types import VALUE_TYPES

ShapeDecl = tuple[int | str | None, ...] | str | Callable[[Any], Any] | None
"""A declared shape: a tuple of ints (``None`` = any size, ``str`` = name of an entity
attribute giving the size), a callable of the entity returning a shape, or ``None`` (any)."""

DTYPES = ("float", "int", "bool", "object")

DType = str | type
"""A declared dtype: one of :data:`DTYPES`, or a class (a structured value type)."""


class Spec:
    """Resolved shape and dtype of a signal.

    ``shape`` is ``None`` (any shape) or a tuple whose entries are ints or ``None`` (any size
    along that axis). ``dtype`` is one of ``float``, ``int``, ``bool``, ``object`` (anything,
    unchecked), or a class registered with :func:`~dgraph.signals.value_types.value_type`: a
    **structured** signal, whose values are instances of that class (a task equation, a contact
    constraint, a robot state...) and which plugs only into an input of the same class or a base
    class of it. ``labels`` optionally names the components of a
    vector (used by recorders and plots).

    ``finite`` (float signals): with ``True`` (the default) NaN and infinities are refused where
    computed values are checked (``check_values``) and where states are staged; a port whose
    values may legitimately be infinite (an unbounded bound, the residual of an invalid level)
    declares ``finite=False`` (NaN still refused); ``None`` refuses nothing, computed, staged or
    set: a raw reading that its readers check themselves (a device's sensors, a fault
    injector's output). A constant set on an input of a finite spec may be infinite (a
    saturation without a bound), never NaN.

    ``minimum`` (numeric signals): the smallest value a set value may hold, element by element
    (a gain, a weight: ``0.0``); :meth:`coerce` refuses a value below it. It is checked where
    values are set (constants, defaults), not on computed values.
    """

    __slots__ = ("dtype", "exact", "finite", "labels", "minimum", "shape", "structured")

    def __init__(self, shape: tuple[int | None, ...] | None = None, dtype: DType = "float",
                 labels: Sequence[str] | None = None, finite: bool | None = True,
                 minimum: float | None = None):
        self.structured = isinstance(dtype, type)
        if not self.structured and dtype not in DTYPES:
            raise SpecError(f"unknown dtype {dtype!r}; expected one of {DTYPES} or a class")
        if self.structured and shape is not None:
            raise SpecError(f"a structured signal ({dtype.__name__}) has no shape, got {shape!r}")
        if self.structured and VALUE_TYPES.get(dtype.__name__) is not dtype:
            raise SpecError(f"{dtype.__module__}.{dtype.__qualname__} is not a structured value type: "
                            "register it with @dg.value_type to use it as a dtype")
        self.shape = None if shape is None else tuple(shape)
        self.dtype = dtype
        self.labels = tuple(labels) if labels is not None else None
        self.finite = None if finite is None else bool(finite)
        if minimum is not None and (self.structured or dtype in ("bool", "object")):
            raise SpecError(f"a minimum needs a numeric dtype, got {self.type_name}")
        self.minimum = minimum
        self.exact = self.shape is not None and all(d is not None for d in self.shape)

    @property
    def type_name(self) -> str:
        """The dtype as written in messages: ``float``... or the structured class's name."""
        return self.dtype.__name__ if self.structured else self.dtype

    def __repr__(self) -> str:
        if self.structured:
            return self.type_name
        shape = "any" if self.shape is None else "(" + ", ".join(
            "*" if d is None else str(d) for d in self.shape) + ("," if len(self.shape) == 1 else "") + ")"
        return f"{self.dtype}{shape}"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Spec) and (self.shape, self.dtype) == (other.shape, other.dtype)

    def __hash__(self) -> int:
        return hash((self.shape, self.dtype))

    # -- plugging -------------------------------------------------------------------------
    def accepts(self, source: Spec) -> bool:
        """True if a signal of spec ``source`` may feed an input of this spec: an ``object``
        input takes anything; a structured input takes a source of its class or a subclass of
        it; a numeric input a numeric source of its dtype (or an int or bool into a float) whose
        shape fits. An untyped ``object`` source feeds only an ``object`` input: the core could
        not check it."""
        if self.dtype == "object":
            return True
        if self.structured or source.structured:
            return self.structured and source.structured and issubclass(source.dtype, self.dtype)
        if source.dtype == "object":
            return False
        if self.dtype != source.dtype and not (self.dtype == "float" and source.dtype in ("int", "bool")):
            return False
        if self.shape is None or source.shape is None:
            return True
        if len(self.shape) != len(source.shape):
            return False
        return all(a is None or b is None or a == b for a, b in zip(self.shape, source.shape, strict=False))

    # -- values ---------------------------------------------------------------------------
    def _shape_ok(self, shape: tuple[int, ...]) -> bool:
        if self.shape is None:
            return True
        if len(shape) != len(self.shape):
            return False
        return all(d is None or d == s for d, s in zip(self.shape, shape, strict=False))

    def coerce(self, value: Any, where: str) -> Any:
        """Return ``value`` converted to this spec (a float, int, bool or a fresh array).

        Raises :class:`SpecError` naming ``where`` on a wrong shape, a wrong type or NaN. A
        structured value is returned as it is if it is an instance of the class; plain data (from
        a graph file, ``--set``) is converted by the class's ``from_plain`` if it has one.
        """
        if self.dtype == "object":
            return value
        if self.structured:
            return self._coerce_structured(value, where)
        try:
            if self.shape == () or (self.shape is None and np.ndim(value) == 0):
                return self._at_least_minimum(self._coerce_scalar(value, where), where)
            if type(value) is np.ndarray and value.dtype == _NUMPY[self.dtype]:
                array = value.copy()
            else:
                array = np.array(value, dtype=_NUMPY[self.dtype])
        except SpecError:
            raise
        except (TypeError, ValueError, OverflowError) as exc:
            raise SpecError(f"{where}: cannot convert {_short(value)} to {self!r}: {exc}") from None
        if not self._shape_ok(array.shape):
            raise SpecError(f"{where}: value of shape {array.shape} does not match {self!r}")
        if self.dtype == "float" and self.finite is not None and has_nan(array):
            raise NonFiniteError(f"{where}: value contains NaN: {_short(value)}")
        return self._at_least_minimum(array, where)

    def _at_least_minimum(self, value: Any, where: str) -> Any:
        """``value`` (a coerced number or array) if no element is below :attr:`minimum`; else
        :class:`SpecError` naming ``where``, the bound and the value."""
        if self.minimum is not None and np.any(np.asarray(value) < self.minimum):
            raise SpecError(f"{where}: must be >= {self.minimum:g}, got {_short(value)}")
        return value

    def _coerce_structured(self, value: Any, where: str) -> Any:
        if isinstance(value, self.dtype):
            return value
        from_plain = getattr(self.dtype, "from_plain", None)
        if from_plain is not None:
            try:
                return from_plain(value)
            except (TypeError, ValueError) as exc:
                raise SpecError(f"{where}: cannot make a {self.dtype.__name__} of {_short(value)}: {exc}") from None
        raise SpecError(f"{where}: expected a {self.dtype.__name__}, got {_short(value)}")

    def _coerce_scalar(self, value: Any, where: str) -> Any:
        if np.ndim(value) != 0:
            raise SpecError(f"{where}: expected a scalar {self.dtype}, got shape {np.shape(value)}")
        if isinstance(value, str) or value is None:
            raise SpecError(f"{where}: expected a scalar {self.dtype}, got {_short(value)}")
        if self.dtype == "float":
            out = float(value)
            if math.isnan(out) and self.finite is not None:
                raise SpecError(f"{where}: value is NaN")
            return out
        if self.dtype == "int":
            if not isinstance(value, (int, float, np.integer, np.floating)) or not math.isfinite(value):
                raise SpecError(f"{where}: expected an int, got {_short(value)}")
            out = int(value)
            if out != value or isinstance(value, bool):
                raise SpecError(f"{where}: expected an int, got {_short(value)}")
            return out
        if value not in (0, 1) or not isinstance(value, (bool, int, np.bool_, np.integer)):
            raise SpecError(f"{where}: expected a bool, got {_short(value)}")
        return bool(value)

    def _non_finite(self, array: np.ndarray) -> str | None:
        """``computed a value containing NaN`` (or ``inf``, if ``finite``), or None."""
        if self.finite is None or not (non_finite(array) if self.finite else has_nan(array)):
            return None
        return f"computed a value containing {'NaN' if has_nan(array) else 'inf'}"

    def problem(self, value: Any) -> str | None:
        """What is wrong with a computed value (type, shape, NaN, and inf unless ``finite`` is
        false), or None. Cheap when fine."""
        if self.dtype == "object":
            return None
        if self.structured:
            return None if isinstance(value, self.dtype) else \
                f"computed a {type(value).__name__}, declared {self.dtype.__name__}"
        if (type(value) is np.ndarray and value.dtype is _FLOAT64 and value.shape == self.shape
                and self.dtype == "float"):  # the common case: the general path below, in short
            return self._non_finite(value)
        if type(value) is float and self.dtype == "float":
            if value != value and self.finite is not None:
                return "computed NaN"
            if self.finite and value in (math.inf, -math.inf):
                return f"computed {value}"
            if self.shape is not None and self.shape != ():
                return f"computed a scalar, declared {self!r}"
            return None
        if isinstance(value, np.ndarray):
            if not self._shape_ok(value.shape):
                return f"computed shape {value.shape}, declared {self!r}"
            if value.dtype.kind == "f" and self._non_finite(value):
                return self._non_finite(value)
            if value.dtype.kind != _KIND[self.dtype] and not (self.dtype == "float" and value.dtype.kind in "iub"):
                return f"computed an array of {value.dtype}, declared {self!r}"
            return None
        if np.ndim(value) != 0 or isinstance(value, (list, tuple)):
            return f"computed a {type(value).__name__}, declared {self!r}: return a numpy array or a scalar"
        try:
            self._coerce_scalar(value, "value")
        except SpecError:
            return f"computed {_short(value)}, declared {self!r}"
        return None


_NUMPY = {"float": np.float64, "int": np.int64, "bool": np.bool_}
_KIND = {"float": "f", "int": "i", "bool": "b"}
_FLOAT64 = np.dtype(np.float64)


def exact_float_copy(spec: Spec, value: Any, copy: bool = True, nan_checked: bool = False,
                     refuse_inf: bool = False) -> np.ndarray | None:
    """The fast path that signals take before :meth:`Spec.coerce`: a float64 array of exactly
    the declared (non-scalar) shape of a float spec, without NaN, gives a copy (or itself, with
    ``copy=False``); anything else (even an equivalent value) gives None, and the general path
    converts it or raises. ``nan_checked``: the caller has checked ``value`` (for NaN, and for
    inf with ``refuse_inf``). ``refuse_inf`` (a state of a ``finite`` spec): an infinity also
    takes the general path."""
    if (type(value) is np.ndarray and value.dtype is _FLOAT64 and value.shape == spec.shape
            and spec.dtype == "float" and value.ndim):
        array = value.copy() if copy else value
        if nan_checked or not (non_finite(array) if refuse_inf else has_nan(array)):
            return array
    return None


def has_nan(array: np.ndarray) -> bool:
    """True if a float array holds a NaN: its sum of squares is NaN exactly then (infinities
    square to +inf), and one BLAS dot is cheaper than ``np.isnan(array).any()``."""
    total = np.vdot(array, array)
    return total != total


def non_finite(array: np.ndarray) -> bool:
    """True if a float array holds a NaN or an infinity. One BLAS dot decides when the array is
    finite and not huge (the sum of squares is then finite); only a sum that overflows (a NaN,
    an inf, or values beyond about 1e154) is looked at element by element."""
    total = np.vdot(array, array)
    return not math.isfinite(total) and not bool(np.isfinite(array).all())


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def resolve_shape(shape: ShapeDecl, owner: Any) -> tuple[int | None, ...] | None:
    """Turn a declared shape into concrete dimensions using the owning entity's attributes."""
    if shape is None:
        return None
    if callable(shape):
        shape = shape(owner)
        if shape is None:
            return None
    if isinstance(shape, (str, int)):
        shape = (shape,)
    dims: list[int | None] = []
    for dim in shape:
        if isinstance(dim, str):
            dim = getattr(owner, dim)
        if dim is not None and (not isinstance(dim, (int, np.integer)) or dim < 0):
            raise SpecError(f"invalid dimension {dim!r} in shape {shape!r}")
        dims.append(None if dim is None else int(dim))
    return tuple(dims)
