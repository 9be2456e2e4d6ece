"""Entities: construction, parameters, registry, commands, introspection."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.operators import Add, Gain
from tests.conftest import Scale


def test_name_first_and_params_typed():
    e = Scale("s", k=3)
    assert e.name == "s" and e.k == 3.0 and isinstance(e.k, float)
    assert e.params == {"k": 3.0} and e.given_params == {"k": 3.0}
    with pytest.raises(dg.ParamError, match="parameter 'k'"):
        Scale("s", k="three")
    with pytest.raises(dg.ParamError, match="unknown parameter"):
        Scale("s", gain=2.0)
    with pytest.raises(dg.ParamError, match="invalid entity name"):
        Scale("a.b")


def test_required_param_and_choices():
    with pytest.raises(dg.ParamError, match="missing required parameter 'value'"):
        dg.get_type("Constant")("c")
    with pytest.raises(dg.ParamError, match="must be one of"):
        dg.get_type("KinematicDevice")("d", size=2, control_mode="torque")


def test_ports_are_per_instance():
    a, b = Scale("a"), Scale("b")
    assert a.u is not b.u and a.u.entity is a and a.y.full_name == "a.y"
    assert set(a.inputs) == {"u", "unused"} and set(a.outputs) == {"y", "z"}
    assert Scale.u.entity is None  # the class attribute is a template


def test_shapes_from_parameters():
    g = Gain("g", size=4)
    assert g.input.spec.shape == (4,) and g.output.spec.shape == (4,)
    add = Add("a", n_inputs=3)
    assert set(add.inputs) == {"in0", "in1", "in2"}


def test_undeclared_dependency_name_is_refused():
    class Bad(dg.Entity):
        @dg.output(depends=("nothing",))
        def y(self, t):
            return 0.0

    with pytest.raises(dg.DGraphError, match="'nothing'"):
        Bad("b")


def test_port_names_cannot_shadow_entity_api():
    with pytest.raises(dg.DGraphError, match="'inputs' is an Entity attribute"):
        class Bad(dg.Entity):
            inputs = dg.Input()


def test_registry_lookup_plugins_and_errors():
    types = dg.entity_types()
    for name in ("Constant", "Add", "Gain", "Selector", "Switch", "Delay", "Integrator", "Sinusoid",
                 "Saturation", "KinematicDevice", "Recorder"):
        assert name in types
    with pytest.raises(dg.RegistryError, match="did you mean Gain"):
        dg.get_type("Gian")


def test_register_decorator_and_conflicts():
    @dg.register(name="TestOnlyScale")
    class Mine(dg.Entity):
        """Doc."""

    assert dg.get_type("TestOnlyScale") is Mine and Mine.type_name == "TestOnlyScale"

    class Other(dg.Entity):
        pass

    with pytest.raises(dg.RegistryError, match="already registered"):
        dg.register(Other, name="TestOnlyScale")


def test_commands_are_listed_with_docstrings():
    class WithCommand(dg.Entity):
        @dg.command
        def reset_gains(self) -> None:
            """Put the gains back to their defaults."""

    e = WithCommand("w")
    assert e.commands == {"reset_gains": "Put the gains back to their defaults."}
    assert "command reset_gains()" in WithCommand.describe()


def test_repr_shows_values_and_stamps(graph):
    a = graph.add(Scale("a"))
    a.u.set(2.0)
    a.y(5)
    text = repr(a)
    assert "Scale('a')" in text and "t=5" in text and "4.0" in text and "(set)" in text


def test_describe_lists_params_and_ports():
    text = dg.get_type("Gain").describe()
    assert "param   size" in text and "input   gain" in text and "output  output" in text


def test_dt_from_param_or_graph():
    sin = dg.get_type("Sinusoid")
    assert sin("s", amplitude=1.0, frequency=1.0, dt=0.5).dt == 0.5
    g = dg.Graph(dt=0.02)
    assert g.add(sin("s", amplitude=1.0, frequency=1.0)).dt == 0.02
    with pytest.raises(dg.DGraphError, match="no dt"):
        sin("x", amplitude=1.0, frequency=1.0).dt


def test_constant_problem_refuses_a_constant_where_it_is_set():
    class Pair(dg.Entity):
        """``pair`` takes two values or a scalar (a rule its spec, any shape, cannot say)."""

        pair = dg.Input(default=0.0)

        def constant_problem(self, name, value):
            return None if np.shape(value) in ((), (2,)) else f"expected a scalar or 2 values, got {np.shape(value)}"

    e = Pair("e")
    e.pair.set([1.0, 2.0])
    with pytest.raises(dg.SpecError, match=r"^e\.pair: expected a scalar or 2 values, got \(3,\)$") as caught:
        e.pair.set([1.0, 2.0, 3.0])
    assert (caught.value.entity, caught.value.signal) == ("e", "pair") and e.pair.value.tolist() == [1.0, 2.0]


def test_an_entity_signature_shows_its_parameters_as_keyword_arguments():
    """inspect.signature (help(), notebooks, IDEs that ask the runtime) sees every parameter."""
    import inspect

    class Spring(dg.Entity):
        stiffness = dg.Param(kind="float", doc="N/m")
        rest = dg.Param([0.0, 0.0], kind="vector")
        label = dg.Param("spring", kind="str")

    class Custom(Spring):
        def __init__(self, name, extra, **params):
            super().__init__(name, **params)

    signature = inspect.signature(Spring)
    assert list(signature.parameters) == ["name", "stiffness", "rest", "label"]
    stiffness, label = signature.parameters["stiffness"], signature.parameters["label"]
    assert stiffness.kind is inspect.Parameter.KEYWORD_ONLY and stiffness.default is inspect.Parameter.empty
    assert stiffness.annotation is float and label.default == "spring" and label.annotation is str
    signature.bind("s", stiffness=1.0)  # what the constructor takes, it binds
    with pytest.raises(TypeError):
        signature.bind("s", stifness=1.0)
    assert list(inspect.signature(Custom).parameters) == ["name", "extra", "params"]  # its own
