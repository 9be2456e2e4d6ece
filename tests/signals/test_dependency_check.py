"""The dependency-check mode's check of the time: an output that reads ``t`` without declaring it
is caught when its cache would serve it at a later tick, and nothing else is (docs/design.md rule 5)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.signals.dependency_check import _TimeCheck, differs
from dgraph.signals.value_types import value_type
from tests.conftest import Clocked, Periodic, Scale, Ticker

ROOT = Path(__file__).resolve().parents[2]


class Sloppy(dg.Entity):
    """``y = u + t`` declaring only ``u``: computed once, then served from the cache."""

    u = dg.Input(shape=(), default=1.0)

    @dg.output(shape=(), depends=("u",))
    def y(self, t):
        return self.u(t) + t

    @dg.output(shape=(), depends=("y",))
    def z(self, t):
        return 2.0 * self.y(t)


@value_type
@dataclass
class Reading:
    """A structured value: an array, a number and an object nobody compares."""

    values: np.ndarray
    scale: float
    handle: object = None


class StructuredSloppy(dg.Entity):
    """A structured output whose array reads ``t`` undeclared (``depends=()``)."""

    @dg.output(dtype=Reading, depends=())
    def reading(self, t):
        return Reading(np.array([1.0, float(t > 2)]), 1.0, object())


def test_an_output_reading_the_time_undeclared_is_caught_when_its_cache_would_serve_it(graph):
    e = graph.add(Sloppy("e"))
    assert e.z(0) == 2.0 and e.z(1) == 2.0  # unnoticed without the check: y(1) is y(0)
    graph.check_dependencies = True
    e.u.set(2.0)
    assert e.z(2) == 8.0  # computed at 2 (u changed): nothing to compare yet
    with pytest.raises(dg.DependencyError) as caught:
        e.z(3)
    assert str(caught.value) == ("e.y would be served from its cache at tick 3 (nothing it depends on changed "
                                 "since tick 2), but computed again at tick 3 it differs from its value of tick 2: its "
                                 "method reads the time; declare it: depends=('u', 't')")
    assert (caught.value.entity, caught.value.signal) == ("e", "y")
    assert e.y.value == 4.0 and e.y.time == 2 and e.y.count == 2 and not e.y.stale  # the cache is left as it was


def test_a_structured_value_is_compared_by_its_arrays_and_numbers(graph):
    e = graph.add(StructuredSloppy("e"))
    graph.check_dependencies = True
    e.reading(0)
    for t in (1, 2):  # the handle is a new object at each computation: not compared
        assert e.reading(t).values.tolist() == [1.0, 0.0]
    with pytest.raises(dg.DependencyError, match=r"e\.reading would be served from its cache at tick 3 .* "
                                                 r"declare it: depends=\('t',\)"):
        e.reading(3)


class Stopwatch(dg.Entity):
    """An output that never computes the same value twice (a wall-clock time, a warm-started solve)."""

    def configure(self):
        self.computations = 0

    @dg.output(shape=(), depends=())
    def elapsed(self, t):
        self.computations += 1
        return float(self.computations)


def test_an_output_that_does_not_compute_the_same_value_twice_is_left_alone(graph):
    watch = graph.add(Stopwatch("watch"))
    graph.check_dependencies = True
    assert [watch.elapsed(t) for t in range(4)] == [1.0] * 4  # the cache serves the first value, as without the check
    assert watch.computations == 7  # computed twice more at each later tick: they differ, nothing to judge


def test_a_run_in_check_mode_stops_at_the_tick_an_undeclared_time_shows(graph):
    dev = graph.add(Ticker("dev"))
    _, s = graph.add(Sloppy("e"), Scale("s"))
    graph.plug("e.z", "s.u")
    dev.before.add(s.z)  # read at every tick
    graph.plug("dev.x", "e.u")  # y changes at every tick: its reading of t is hidden...
    graph.check_dependencies = True
    graph.run(ticks=5)
    graph.unplug("e.u")  # ...until its input holds still
    with pytest.raises(dg.HookError, match=r"before hook s\.z of device dev failed at tick 6: DependencyError: e\.y "
                                           r"would be served from its cache at tick 6 \(nothing it depends on changed "
                                           r"since tick 5\)"):  # the hook's read is the first at tick 6
        graph.run(ticks=5, progress=False)
    assert graph.t == 6 and dev.x(6) == 6.0  # the failing tick was not committed


def test_correct_declarations_raise_nothing_and_cost_nothing_when_the_mode_is_off(graph):
    graph.add(Ticker("dev"))
    clocked, _, held = graph.add(Clocked("clock"), Periodic("p", every=3), Scale("held"))
    const = graph.add(Scale("const"))
    graph.plug("dev.x", "p.u")
    graph.plug("p.y", "held.u")
    const.u.set(4.0)
    assert not any(isinstance(o, _TimeCheck) for o in graph.clock.time_varying)  # off: nothing watches
    graph.check_dependencies = True
    counts = []
    for _ in range(10):
        graph.step()
        t = graph.t
        counts.append((const.z(t), clocked.now(t), held.z(t)))
    assert const.y.count == 1 and const.z.count == 1  # checked at each tick, never recomputed for good
    assert held.y.count == 4  # once per window of p (ticks 1, 3, 6, 9)
    assert counts[-1] == (9.0, 10.0, 2 * 9.0 + 1)  # p holds x(9) in its window [9, 12)
    graph.check_dependencies = False
    assert not any(isinstance(o, _TimeCheck) for o in graph.clock.time_varying)


def test_entities_joining_or_leaving_are_watched_or_forgotten(graph):
    graph.check_dependencies = True
    e = graph.add(Sloppy("e"))
    e.y(0)
    with pytest.raises(dg.DependencyError, match=r"e\.y"):
        e.y(1)
    graph.remove("e")
    assert not any(isinstance(o, _TimeCheck) for o in graph.clock.time_varying)
    assert e.y(5) == 6.0  # outside the graph: its own clock, no check


def test_differs_compares_arrays_numbers_and_the_attributes_of_structures():
    nan = np.array([1.0, np.nan])
    assert not differs(nan, nan.copy()) and differs(nan, np.array([1.0, 2.0])) and differs(nan, nan[:1])
    assert differs(np.zeros(2), np.zeros(2, dtype=int)) and differs(1.0, np.ones(1))
    assert not differs(float("nan"), float("nan")) and differs(1.0, 1.0 + 1e-16 * 3) and not differs(2, 2.0)
    assert differs("a", "b") and not differs(("a", ("b",)), ("a", ("b",))) and differs([1.0], [1.0, 2.0])
    assert differs(None, 1.0) and differs(Reading(np.zeros(1), 1.0), None)
    assert not differs(Reading(np.zeros(1), 1.0, object()), Reading(np.zeros(1), 1.0, object()))
    assert differs(Reading(np.zeros(1), 1.0), Reading(np.zeros(1), 2.0))
    assert not differs({"a": 1}, {"a": 2})  # what is not compared counts as the same

    class Lazy:
        def __init__(self, q):
            self.q = q

    first, second = Lazy(np.zeros(2)), Lazy(np.zeros(2))
    first.cached = np.ones(3)  # computed on one of them only: skipped
    assert not differs(first, second) and differs(first, Lazy(np.ones(2)))


def test_the_pd_double_integrator_runs_in_check_mode_without_a_false_alarm_and_as_without_it():
    runs = []
    for checked in (False, True):
        with dg.load(ROOT / "graphs" / "pd_double_integrator.yaml", {"recorder.rerun": "off"}) as graph:
            graph.check_values = graph.check_dependencies = checked
            graph.run(ticks=500, progress=False)
            runs.append(graph["recorder"].data())
    for key, values in runs[0].items():
        np.testing.assert_array_equal(values, runs[1][key], err_msg=key)
