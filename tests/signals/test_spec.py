"""Spec: coercion of set values, checks of computed values, plug compatibility."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.errors import SpecError
from dgraph.signals.spec import Spec, resolve_shape


def test_scalar_float_coercion():
    spec = Spec((), "float")
    assert spec.coerce(3, "x") == 3.0 and type(spec.coerce(np.float32(1.5), "x")) is float
    for bad in ("1", None, [1.0], float("nan")):
        with pytest.raises(SpecError, match="x"):
            spec.coerce(bad, "x")


def test_vector_coercion_copies_and_checks_shape():
    spec = Spec((3,), "float")
    src = np.zeros(3)
    out = spec.coerce(src, "v")
    src[0] = 1.0
    assert out[0] == 0.0
    with pytest.raises(SpecError, match=r"shape \(2,\)"):
        spec.coerce([1.0, 2.0], "v")
    with pytest.raises(SpecError, match="NaN"):
        spec.coerce([1.0, np.nan, 0.0], "v")


def test_wildcard_dimensions_and_any_shape():
    assert Spec((None, 2)).coerce(np.zeros((5, 2)), "m").shape == (5, 2)
    assert Spec(None).coerce(2, "s") == 2.0
    assert Spec(None).coerce([[1, 2]], "s").shape == (1, 2)


def test_int_and_bool():
    assert Spec((), "int").coerce(3.0, "i") == 3
    with pytest.raises(SpecError):
        Spec((), "int").coerce(3.5, "i")
    with pytest.raises(SpecError):
        Spec((), "int").coerce(True, "i")
    assert Spec((), "bool").coerce(True, "b") is True
    with pytest.raises(SpecError):
        Spec((), "bool").coerce(2, "b")


def test_plug_compatibility():
    assert Spec((3,)).accepts(Spec((3,)))
    assert not Spec((3,)).accepts(Spec((4,)))
    assert not Spec((3,)).accepts(Spec(()))
    assert Spec((None,)).accepts(Spec((7,)))
    assert Spec(None).accepts(Spec((2, 2)))
    assert Spec((), "float").accepts(Spec((), "int"))
    assert not Spec((), "int").accepts(Spec((), "float"))
    assert Spec((3,), "object").accepts(Spec((3,), "float"))


def test_problems_of_computed_values():
    assert Spec((2,)).problem(np.zeros(2)) is None
    assert "computed shape (3,)" in Spec((2,)).problem(np.zeros(3))
    assert "computed a scalar" in Spec((2,)).problem(1.0)
    assert Spec(()).problem(float("nan")) == "computed NaN"
    assert "NaN" in Spec((2,)).problem(np.array([0.0, np.nan]))
    assert "return a numpy array" in Spec((2,)).problem([1.0, 2.0])
    assert "declared int()" in Spec((), "int").problem(1.5)
    assert "int64" in Spec((2,), "bool").problem(np.zeros(2, dtype=int))
    assert Spec((), "object").problem(object()) is None


def test_resolve_shape_from_owner_attributes():
    class Owner:
        n = 4

    assert resolve_shape(("n", 3), Owner()) == (4, 3)
    assert resolve_shape("n", Owner()) == (4,)
    assert resolve_shape(lambda o: (o.n,), Owner()) == (4,)
    assert resolve_shape(None, Owner()) is None
    with pytest.raises(SpecError):
        resolve_shape((-1,), Owner())


def test_unknown_dtype():
    with pytest.raises(SpecError):
        Spec((), "complex")


def test_repr():
    assert repr(Spec((3,))) == "float(3,)" and repr(Spec((None, 2), "int")) == "int(*, 2)"


def test_infinities_are_constants_not_computed_values_and_nan_is_found_behind_them():
    spec = Spec((3,))
    value = spec.coerce(np.array([np.inf, -np.inf, 1.0]), "x")  # the sum is NaN, but no entry is
    assert np.isinf(value[:2]).all()  # a constant may be unbounded (a saturation's bound)
    assert spec.problem(np.array([np.inf, -np.inf, 1.0])) == "computed a value containing inf"
    assert spec.problem(np.array([1e200, -1e200, 1.0])) is None  # huge is not infinite
    assert Spec(()).problem(3.0) is None and Spec(()).problem(-np.inf) == "computed -inf"
    assert Spec((3,), finite=False).problem(np.array([np.inf, -np.inf, 1.0])) is None
    assert "NaN" in Spec((3,), finite=False).problem(np.array([np.inf, np.nan, 1.0]))
    assert "NaN" in spec.problem(np.array([1.0, np.nan, 2.0]))
    with pytest.raises(SpecError, match="NaN"):
        spec.coerce(np.array([np.inf, np.nan, 0.0]), "x")


def test_a_minimum_refuses_smaller_set_values_element_by_element():
    scalar, vector = Spec((), minimum=0.0), Spec(None, minimum=0.0)
    assert scalar.coerce(0, "w") == 0.0 and vector.coerce([0.0, 2.0], "k").tolist() == [0.0, 2.0]
    with pytest.raises(SpecError, match=r"w: must be >= 0, got -1\.0"):
        scalar.coerce(-1.0, "w")
    with pytest.raises(SpecError, match=r"k: must be >= 0, got array\(\[ 1\., -2\.\]\)"):
        vector.coerce(np.array([1.0, -2.0]), "k")
    assert Spec((), "int", minimum=1).coerce(3, "n") == 3
    with pytest.raises(SpecError, match="minimum needs a numeric dtype"):
        Spec((), "bool", minimum=0.0)
    assert Spec((2,)).problem(np.array([-1.0, 0.0])) is None  # computed values are not bounded
