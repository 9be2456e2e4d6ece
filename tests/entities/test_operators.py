"""Glue operators: Constant, Add, Gain, Selector, Replace, Switch, Saturation."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.operators import Add, Constant, Gain, Replace, Saturation, Selector, Switch


def test_constant_scalar_vector_matrix(graph):
    assert graph.add(Constant("s", value=2)).output(0) == 2.0
    v = graph.add(Constant("v", value=[1, 2, 3]))
    assert v.output.spec.shape == (3,) and np.array_equal(v.output(0), [1, 2, 3])
    m = graph.add(Constant("m", value=[[1, 0], [0, 1]]))
    assert m.output.spec.shape == (2, 2)
    for t in range(5):
        v.output(t)
    assert v.output.count == 1


def test_add_weighted_sum(graph):
    a = graph.add(Add("a", n_inputs=3, coefficients=[1, -2, 0.5], size=2))
    a.in0.set([1, 1])
    a.in1.set([1, 0])
    a.in2.set([2, 2])
    assert np.allclose(a.output(0), [0.0, 2.0])
    with pytest.raises(dg.ParamError, match="2 coefficients for 3 inputs"):
        Add("b", n_inputs=3, coefficients=[1, 1])


def test_gain_scalar_diagonal_matrix(graph):
    g = graph.add(Gain("g", size=2))
    g.input.set([1.0, 2.0])
    assert np.allclose(g.output(0), [1.0, 2.0])
    g.gain.set(3.0)
    assert np.allclose(g.output(0), [3.0, 6.0])
    g.gain.set([1.0, -1.0])
    assert np.allclose(g.output(0), [1.0, -2.0])
    g.gain.set([[0.0, 1.0], [1.0, 0.0]])
    assert np.allclose(g.output(0), [2.0, 1.0])
    with pytest.raises(dg.SpecError, match=r"g\.gain: expected a scalar, \(2,\) or \(2, 2\), got shape \(3,\)"):
        g.gain.set([1.0, 2.0, 3.0])  # refused where it is set, not at the tick
    with pytest.raises(dg.SpecError, match=r"x\.gain: expected a scalar, got shape \(2,\)"):
        graph.add(Gain("x")).gain.set([1.0, 2.0])


def test_selector(graph):
    s = graph.add(Selector("s", size=4, indices=[3, 0]))
    s.input.set([10, 11, 12, 13])
    assert np.array_equal(s.output(0), [13, 10]) and s.output.spec.shape == (2,)
    with pytest.raises(dg.ParamError, match="invalid for size 4"):
        Selector("bad", size=4, indices=[4])


def test_replace_overwrites_the_indexed_components_of_a_copy(graph):
    r = graph.add(Replace("r", size=4, indices=[2, -4]))
    source = np.array([10.0, 11.0, 12.0, 13.0])
    r.input.set(source)
    r.values.set([-1.0, -2.0])
    assert np.array_equal(r.output(0), [-2.0, 11.0, -1.0, 13.0]) and r.output.spec.shape == (4,)
    assert np.array_equal(source, [10.0, 11.0, 12.0, 13.0])  # the input is left as it was
    with pytest.raises(dg.SpecError, match=r"r\.values"):
        r.values.set([1.0, 2.0, 3.0])
    with pytest.raises(dg.ParamError, match="invalid for size 4"):
        Replace("bad", size=4, indices=[4])
    with pytest.raises(dg.ParamError, match="twice"):
        Replace("twice", size=4, indices=[1, -3])


def test_switch_evaluates_only_the_selected_input(graph):
    sw = graph.add(Switch("sw"))
    sw.in1.set(5.0)  # in0 is unplugged: fine while not selected
    sw.selection.set(1)
    assert sw.output(0) == 5.0
    sw.selection.set(0)
    with pytest.raises(dg.UnpluggedInputError, match=r"sw\.in0"):
        sw.output(1)
    with pytest.raises(dg.SpecError, match=r"sw\.selection: expected 0\.\.1 \(one of in0\.\.in1\), got 7"):
        sw.selection.set(7)

    class Seven(dg.Entity):
        @dg.output(shape=(), dtype="int", depends=())
        def output(self, t):
            return 7

    graph.add(Seven("seven"))
    graph.plug("seven.output", "sw.selection")  # through a plug: checked at the tick
    with pytest.raises(dg.ComputeError, match="selection = 7"):
        sw.output(2)


def test_saturation(graph):
    s = graph.add(Saturation("s", size=3))
    s.input.set([-5.0, 0.5, 5.0])
    s.lower.set(-1.0)
    s.upper.set([1.0, 0.2, 2.0])
    assert np.allclose(s.output(0), [-1.0, 0.2, 2.0])
    scalar = graph.add(Saturation("x"))
    scalar.input.set(3.0)
    assert scalar.output(0) == 3.0
    scalar.upper.set(1.0)
    assert scalar.output(0) == 1.0
    with pytest.raises(dg.SpecError, match=r"s\.lower: expected a scalar or \(3,\), got shape \(2,\)"):
        s.lower.set([0.0, 0.0])
    scalar.lower.set(2.0)  # above upper: a relation of two constants, reported by the graph's check
    assert graph.problems() == ["x: lower 2.0 is above upper 1.0"]
