"""The sweep's description: grid axes read as --set reads values, the cells in order, mistakes refused."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.files import command_line_value
from dgraph.sweep.spec import Bisection, Sweep, SweepError, bisection_option, grid_axes, grid_axis, setting_text


def test_a_grid_axis_is_a_comma_list_or_a_flow_list_of_yaml_values():
    assert grid_axis("push.gain=0.5,1,2e3") == ("push.gain", [0.5, 1, 2000.0])
    assert grid_axis("fault.kind=[jump, inf]") == ("fault.kind", ["jump", "inf"])
    assert grid_axis("robot.q0=[1,0,0],[0,1,0]") == ("robot.q0", [[1, 0, 0], [0, 1, 0]])
    assert grid_axis("robot.q0=[[1,0,0]]") == ("robot.q0", [[1, 0, 0]])
    assert grid_axis("device.flag=true") == ("device.flag", [True])


@pytest.mark.parametrize("item", ["push.gain", "push=1,2", "push.gain=", "a.b.c=1", "push.gain=[1,"])
def test_a_bad_grid_option_is_refused_naming_it(item):
    with pytest.raises(SweepError, match="--grid"):
        grid_axis(item)


def test_an_axis_given_twice_is_refused():
    assert list(grid_axes(["a.b=1,2", "c.d=3"])) == ["a.b", "c.d"]
    with pytest.raises(SweepError, match="a.b: given twice"):
        grid_axes(["a.b=1,2", "a.b=3"])


def test_cells_are_every_file_times_every_combination_first_axis_slowest():
    sweep = Sweep(["f1.yaml", "f2.yaml"], settings={"k.fixed": 1}, grid={"a.x": [1, 2], "b.y": ["u", "v", "w"]})
    cells = sweep.cells()
    assert len(cells) == 12
    assert cells[0] == ("f1.yaml", {"k.fixed": 1, "a.x": 1, "b.y": "u"})
    assert cells[1] == ("f1.yaml", {"k.fixed": 1, "a.x": 1, "b.y": "v"})
    assert cells[3] == ("f1.yaml", {"k.fixed": 1, "a.x": 2, "b.y": "u"})
    assert cells[6][0] == "f2.yaml"
    assert Sweep(["f.yaml"]).cells() == [("f.yaml", {})]
    assert sweep.setting_keys == ["k.fixed", "a.x", "b.y"]


def test_numpy_values_become_plain_data():
    sweep = Sweep(["f.yaml"], settings={"a.v": np.array([1.0, 2.0])}, grid={"a.x": np.arange(2)})
    assert sweep.settings == {"a.v": [1.0, 2.0]} and sweep.grid == {"a.x": [0, 1]}
    assert type(sweep.grid["a.x"][0]) is int


@pytest.mark.parametrize("value", [0.1, 1e-17, 3, -2.5, True, "abc", "true", "1.5", [0, 0.05, 0], float("inf"),
                                   [[1, 0], [0, 1]]])
def test_a_setting_text_reads_back_as_the_same_value(value):
    assert command_line_value("a.b", setting_text(value)) == value


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"files": []}, "no graph file"),
    ({"settings": {"a.x": 1}, "grid": {"a.x": [1, 2]}}, "a.x: set more than once"),
    ({"grid": {"a.x": [1]}, "bisection": Bisection("a.x", 0, 1)}, "a.x: set more than once"),
    ({"grid": {"a.x": []}}, "a.x: no value"),
    ({"grid": {"a.x": [0.3, 1, 0.3]}}, r"--grid a.x: 0.3 given more than once"),
    ({"grid": {"a.v": [[1, 0], np.array([1, 0])]}}, r"--grid a.v: \[1, 0\] given more than once"),
    ({"settings": {"nodot": 1}}, "--set 'nodot'"),
    ({"duration": -1.0}, "--duration"),
    ({"timeout": 0.0}, "--timeout"),
    ({"grid": {"a.x": [1]}, "measures": ["a.x"]}, "constant in every run"),
])
def test_a_sweep_that_cannot_be_run_is_refused(kwargs, message):
    with pytest.raises(SweepError, match=message):
        Sweep(**{"files": ["f.yaml"], **kwargs})


def test_a_value_that_is_not_plain_data_is_refused_naming_its_option():
    with pytest.raises(dg.GraphError, match="--grid a.x: a object cannot be written"):
        Sweep(["f.yaml"], grid={"a.x": [object()]})


def test_a_bisection_reads_key_low_high_and_checks_them():
    assert bisection_option("push.gain=0:2.5", 0.1) == Bisection("push.gain", 0.0, 2.5, 0.1)
    for item in ("push.gain=2", "push.gain=a:b", "push.gain=3:1", "push.gain=-1:1", "push.gain=0:.inf"):
        with pytest.raises(SweepError, match="--bisect"):
            bisection_option(item, 0.05)
    with pytest.raises(SweepError, match="--tolerance"):
        Bisection("push.gain", 0.0, 1.0, 1.5)
