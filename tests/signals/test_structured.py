"""Structured signals: a port typed by a class plugs only into an input of that class (or a base).

Every pair of the structured value types the package registers is tried at plug time.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pytest

import dgraph as dg
from dgraph.registry import entity_types
from dgraph.signals.spec import Spec
from dgraph.signals.value_types import VALUE_TYPES, value_type

ENTITY_TYPES = entity_types()  # imports every family, which registers its value types

PACKAGE_TYPES = ("PriorityStack", "NextState", "RobotState", "FeatureValue", "TaskEquation", "ContactConstraint",
                 "RowBlock", "QPSolution", "Passivity", "CascadeSolution", "EnergyBudget", "Estimate")


def typed_pair(source_type: type | str, target_type: type | str) -> tuple[dg.Entity, dg.Entity]:
    """A producer whose ``out`` carries ``source_type`` and a consumer whose ``inp`` takes
    ``target_type``, in one graph."""
    producer = type("Producer", (dg.Entity,), {"out": dg.Output(lambda self, t: None, dtype=source_type)})
    consumer = type("Consumer", (dg.Entity,), {"inp": dg.Input(dtype=target_type)})
    pair = producer("producer"), consumer("consumer")
    dg.Graph().add(*pair)
    return pair


def test_the_package_registers_its_structured_types():
    assert set(PACKAGE_TYPES) <= set(VALUE_TYPES)
    assert all(isinstance(cls, type) and cls.__name__ == name for name, cls in VALUE_TYPES.items())


@pytest.mark.parametrize(("source", "target"), list(itertools.permutations(sorted(VALUE_TYPES), 2)))
def test_every_pair_of_different_structured_types_is_refused_at_plug_time(source, target):
    producer, consumer = typed_pair(VALUE_TYPES[source], VALUE_TYPES[target])
    graph = producer.graph
    if issubclass(VALUE_TYPES[source], VALUE_TYPES[target]):
        graph.plug("producer.out", "consumer.inp")
        return
    with pytest.raises(dg.PlugError, match=f"producer.out {source} into consumer.inp {target}") as info:
        graph.plug("producer.out", "consumer.inp")
    assert (info.value.entity, info.value.signal) == ("consumer", "inp")
    assert consumer.inp.source is None


@pytest.mark.parametrize("name", sorted(VALUE_TYPES))
def test_a_structured_type_plugs_into_its_own_kind(name):
    producer, consumer = typed_pair(VALUE_TYPES[name], VALUE_TYPES[name])
    dg.plug(producer.out, consumer.inp)
    assert consumer.inp.source is producer.out


@pytest.mark.parametrize("numeric", ["float", "int", "bool"])
def test_numbers_and_structures_do_not_mix(numeric):
    task_equation = VALUE_TYPES["TaskEquation"]
    for source, target in ((numeric, task_equation), (task_equation, numeric)):
        producer, consumer = typed_pair(source, target)
        with pytest.raises(dg.PlugError, match="a different type"):
            dg.plug(producer.out, consumer.inp)


def test_an_untyped_source_cannot_feed_a_structured_input_but_an_untyped_input_takes_anything():
    producer, consumer = typed_pair("object", VALUE_TYPES["RobotState"])
    with pytest.raises(dg.PlugError, match="producer.out objectany into consumer.inp RobotState"):
        dg.plug(producer.out, consumer.inp)
    producer, consumer = typed_pair(VALUE_TYPES["RobotState"], "object")
    dg.plug(producer.out, consumer.inp)


def test_a_subclass_plugs_into_its_base_and_not_the_other_way():
    @value_type
    @dataclass
    class Base:
        x: float

    @value_type
    @dataclass
    class Derived(Base):
        y: float

    try:
        producer, consumer = typed_pair(Derived, Base)
        dg.plug(producer.out, consumer.inp)
        producer, consumer = typed_pair(Base, Derived)
        with pytest.raises(dg.PlugError):
            dg.plug(producer.out, consumer.inp)
    finally:
        del VALUE_TYPES["Base"], VALUE_TYPES["Derived"]


@pytest.mark.parametrize("cls", [tuple, dict, list, np.ndarray])
def test_only_a_registered_value_type_can_be_a_dtype(cls):
    """A builtin container as a dtype would let any tuple (a pair of gains) into any tuple input
    (a priority stack): the class must be registered, so that it says what it carries."""
    with pytest.raises(dg.SpecError, match=f"{cls.__qualname__} is not a structured value type"):
        Spec(dtype=cls)


def test_plain_data_from_a_file_becomes_the_value_type_that_says_how():
    stack_type = VALUE_TYPES["PriorityStack"]
    spec = Spec(dtype=stack_type)
    stack = spec.coerce([["contacts"], ["com", "waist"]], "solver.stack")
    assert type(stack) is stack_type and stack == (("contacts",), ("com", "waist"))
    for bad in ("com", ["com"], [[1]], 3.0):
        with pytest.raises(dg.SpecError, match="solver.stack: cannot make a PriorityStack of"):
            spec.coerce(bad, "solver.stack")
    with pytest.raises(dg.SpecError, match="expected a Passivity, got"):
        Spec(dtype=VALUE_TYPES["Passivity"]).coerce([1.0], "solver.passivity")  # no from_plain: no conversion


def test_a_set_value_and_a_computed_value_are_checked_against_the_class():
    spec = Spec(dtype=VALUE_TYPES["Passivity"])
    with pytest.raises(dg.SpecError, match="where: expected a Passivity, got 3.0"):
        spec.coerce(3.0, "where")
    assert spec.problem(np.zeros(3)) == "computed a ndarray, declared Passivity"
    assert repr(spec) == "Passivity" and spec.type_name == "Passivity"
    with pytest.raises(dg.SpecError, match="has no shape"):
        Spec((3,), dtype=VALUE_TYPES["Passivity"])


def test_value_type_names_are_unique_across_modules():
    first = type("Twin", (), {"__module__": "first_module"})
    second = type("Twin", (), {"__module__": "second_module"})
    value_type(first)
    try:
        with pytest.raises(dg.RegistryError, match="two structured value types are named 'Twin'"):
            value_type(second)
    finally:
        VALUE_TYPES.pop("Twin")


def test_no_port_of_the_package_is_declared_untyped():
    untyped = [f"{cls.type_name}.{name}" for cls in ENTITY_TYPES.values() if cls.__module__.startswith("dgraph.")
               for name, port in cls._port_templates.items()
               if port._dtype == "object" and not isinstance(port, dg.State)]
    assert untyped == []


def test_an_untyped_source_feeds_only_an_untyped_input():
    for target in ("float", "int", "bool"):
        producer, consumer = typed_pair("object", target)
        with pytest.raises(dg.PlugError, match=f"producer.out objectany into consumer.inp {target}"):
            dg.plug(producer.out, consumer.inp)
