"""Typed parameters: kinds, bounds, choices, optional values."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.params import Param


def make(name: str, **kw) -> Param:
    p = Param(**kw)
    p.name = name
    return p


@pytest.mark.parametrize(("kind", "good", "converted", "bad"), [
    ("float", 2, 2.0, "2"),
    ("int", np.int64(3), 3, 3.5),
    ("bool", True, True, 1),
    ("str", "a", "a", 1),
    ("vector", [1, 2], [1.0, 2.0], "12"),
    ("str_list", ("a", "b"), ["a", "b"], "ab"),
    ("int_list", [1, 2], [1, 2], [1.5]),
])
def test_kinds_convert_or_refuse(kind, good, converted, bad):
    p = make("x", kind=kind)
    assert np.array_equal(p.convert(good, "e"), converted)
    with pytest.raises(dg.ParamError, match=r"e: parameter 'x'"):
        p.convert(bad, "e")


def test_bool_is_not_a_number():
    with pytest.raises(dg.ParamError):
        make("x", kind="int").convert(True, "e")
    with pytest.raises(dg.ParamError):
        make("x", kind="float").convert(False, "e")


def test_vector_refuses_nan_and_high_rank():
    with pytest.raises(dg.ParamError, match="NaN"):
        make("x", kind="vector").convert([1.0, float("nan")], "e")
    with pytest.raises(dg.ParamError, match="dimensions"):
        make("x", kind="vector").convert(np.zeros((2, 2, 2)), "e")


def test_bounds_choices_optional():
    p = make("n", kind="int", minimum=1, maximum=4)
    assert p.convert(4, "e") == 4
    with pytest.raises(dg.ParamError, match=r"within \[1, 4\]"):
        p.convert(5, "e")
    c = make("mode", kind="str", choices=("a", "b"))
    with pytest.raises(dg.ParamError, match="must be one of"):
        c.convert("c", "e")
    assert make("o", kind="int", default=None).convert(None, "e") is None
    with pytest.raises(dg.ParamError):
        make("r", kind="int").convert(None, "e")


def test_unknown_kind_and_describe():
    with pytest.raises(dg.ParamError, match="unknown parameter kind"):
        Param(kind="complex")
    assert make("size", kind="int", default=3, doc="the size").describe() == "size: int = 3  -- the size"
    assert make("value", kind="vector").describe() == "value: vector = required"


def test_nan_is_never_a_float_parameter():
    class Timed(dg.Entity):
        """A float parameter, unbounded."""

        delay = dg.Param(0.0, kind="float")

    with pytest.raises(dg.ParamError, match="NaN"):
        Timed("t", delay=float("nan"))
    assert Timed("t", delay=float("inf")).delay == float("inf")  # infinity can mean something (a cutoff)


def test_bounds_apply_to_every_element_of_a_vector_or_a_list():
    gains = make("kp", kind="vector", minimum=0.0)
    assert gains.convert([0.0, 3.0], "e").tolist() == [0.0, 3.0] and gains.convert(2.0, "e") == 2.0
    for bad in (-1.0, [1.0, -1.0], [[1.0], [-2.0]]):
        with pytest.raises(dg.ParamError, match=r"e: parameter 'kp' must be within \[0.0, None\]"):
            gains.convert(bad, "e")
    with pytest.raises(dg.ParamError, match=r"within \[0, 9\]"):
        make("i", kind="int_list", minimum=0, maximum=9).convert([3, 10], "e")


@pytest.mark.parametrize("type_name", sorted(n for n, cls in dg.entity_types().items() if "dt" in cls._param_decls))
def test_every_dt_parameter_is_a_positive_period(type_name):
    decl = dg.get_type(type_name)._param_decls["dt"]
    assert decl.convert(None, "e") is None and decl.convert(0.002, "e") == 0.002  # None: the graph's dt
    for bad in (0.0, -0.001):
        with pytest.raises(dg.ParamError, match=r"e: parameter 'dt' must be within \[1e-06, "):
            decl.convert(bad, "e")
