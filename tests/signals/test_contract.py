"""The signal contract of docs/design.md, one test (or more) per line of it."""

from __future__ import annotations

import inspect
import sys

import numpy as np
import pytest

import dgraph as dg
from tests.conftest import Clocked, Periodic, Scale, Sum2, Ticker


def test_outputs_are_lazy_and_computed_once_per_tick(graph):
    a = graph.add(Scale("a"))
    a.u.set(3.0)
    assert a.y.count == 0 and a.y.value is None and a.y.time is None
    assert a.y(0) == 6.0
    assert a.y(0) == 6.0
    assert a.y.count == 1 and a.y.time == 0 and a.y.value == 6.0


def test_diamond_computes_its_top_once_per_tick(graph):
    dev = graph.add(Ticker("dev"))
    top = graph.add(Scale("top"))
    left, _right = graph.add(Scale("left"), Scale("right"))
    bottom = graph.add(Sum2("bottom"))
    graph.plug("dev.x", "top.u")
    graph.plug("top.y", "left.u")
    graph.plug("top.y", "right.u")
    graph.plug("left.y", "bottom.a")
    graph.plug("right.y", "bottom.b")
    for t in range(5):
        assert bottom.s(t) == 8.0 * dev.x(t)
        dev.increment()
    assert top.y.count == 5 and left.y.count == 5 and bottom.s.count == 5


def test_constant_only_chain_computes_once_until_a_constant_changes(graph):
    a, b = graph.add(Scale("a"), Scale("b"))
    graph.plug("a.y", "b.u")
    a.u.set(1.0)
    for t in range(10):
        assert b.y(t) == 4.0
    assert (a.y.count, b.y.count) == (1, 1)
    a.u.set(2.0)
    for t in range(10, 20):
        assert b.y(t) == 8.0
    assert (a.y.count, b.y.count) == (2, 2)


def test_setting_an_undeclared_input_does_not_invalidate(graph):
    a = graph.add(Scale("a"))
    a.u.set(1.0)
    a.y(0)
    a.unused.set(5.0)  # y declares depends=("u",)
    a.y(1)
    assert a.y.count == 1


def test_no_declaration_means_depending_on_every_input(graph):
    s = graph.add(Sum2("s"))
    s.a.set(1.0)
    s.s(0)
    s.b.set(2.0)
    assert s.s(0) == 3.0 and s.s.count == 2


def test_output_to_output_dependency_inside_an_entity(graph):
    a = graph.add(Scale("a"))
    a.u.set(1.0)
    assert a.z(0) == 3.0
    a.u.set(2.0)
    assert a.z(0) == 5.0 and a.z.count == 2 and a.y.count == 2


def test_device_state_changes_every_tick_and_triggers_recomputation(graph):
    dev = graph.add(Ticker("dev", x0=10.0))
    a = graph.add(Scale("a"))
    graph.plug("dev.x", "a.u")
    values = []
    for _ in range(4):
        values.append(a.y(graph.t))
        graph.step()
    assert values == [20.0, 22.0, 24.0, 26.0]
    assert a.y.count == 4
    assert dev.x.time == 4 and dev.x.value == 14.0


def test_state_is_stamped_t_plus_one_after_control_at_t(graph):
    dev = graph.add(Ticker("dev"))
    assert dev.x.time == 0
    dev.increment()
    assert dev.x.time == 1 and graph.t == 1


def test_time_varying_output_recomputes_at_each_new_tick_only(graph):
    c = graph.add(Clocked("c"))
    for t in range(3):
        assert c.now(t) == t
        assert c.now(t) == t
    assert c.now.count == 3
    downstream = graph.add(Scale("d"))
    graph.plug("c.now", "d.u")
    assert downstream.y(7) == 14.0 and downstream.y(8) == 16.0


def test_period_n_recomputes_at_most_every_n_ticks_and_releases_downstream(graph):
    graph.add(Ticker("dev"))
    p = graph.add(Periodic("p", every=5))
    d = graph.add(Scale("d"))
    graph.plug("dev.x", "p.u")
    graph.plug("p.y", "d.u")
    seen = []
    for _ in range(12):
        seen.append(d.y(graph.t))
        graph.step()
    # p samples the ticker at 0, 5 and 10 and holds in between; d follows each new sample
    assert seen == [0.0] * 5 + [10.0] * 5 + [20.0] * 2
    assert p.y.count == 3
    assert d.y.count == 3


def test_period_hold_is_released_even_if_nothing_else_pulls(graph):
    graph.add(Ticker("dev"))
    graph.add(Periodic("p", every=3))
    graph.plug("dev.x", "p.u")
    d = graph.add(Scale("d"))
    graph.plug("p.y", "d.u")
    d.y(0)
    for _ in range(3):
        graph.step()
    # at t=3 the hold has expired: the new value is computed on read
    assert d.y(3) == 6.0


def test_invalid_period_is_refused():
    with pytest.raises(dg.SpecError):
        dg.Output(lambda e, t: 0.0, period=0)


def test_reading_at_an_earlier_tick_recomputes(graph):
    c = graph.add(Clocked("c"))
    assert c.now(5) == 5.0
    assert c.now(2) == 2.0


def test_a_past_read_never_moves_a_stamp_back(graph):
    """y(5), a change, y(4): refused, naming y and both ticks; nothing is recomputed."""
    a = graph.add(Scale("a"))
    a.u.set(1.0)
    assert a.y(5) == 2.0
    a.u.set(3.0)
    with pytest.raises(dg.DGraphError, match=r"a\.y was read at tick 4, but it is stamped 5") as err:
        a.y(4)
    assert (err.value.entity, err.value.signal) == ("a", "y")
    assert (a.y.time, a.y.value, a.y.count) == (5, 2.0, 1)
    assert a.y(5) == 6.0 and a.y(6) == 6.0 and (a.y.time, a.y.count) == (5, 2)  # forward as ever


def test_a_past_read_is_refused_for_an_upstream_output_stamped_later(graph):
    a, b = graph.add(Scale("a"), Scale("b"))
    graph.plug("a.y", "b.u")
    a.u.set(1.0)
    assert b.y(3) == 4.0
    a.u.set(2.0)
    assert a.y(5) == 4.0  # a is stamped 5, b (stale) still 3
    a.u.set(3.0)
    with pytest.raises(dg.DGraphError, match=r"a\.y was read at tick 4, but it is stamped 5"):
        b.y(4)
    assert (a.y.time, a.y.count, b.y.time, b.y.count) == (5, 2, 3, 1)
    assert b.y(5) == 12.0 and (a.y.time, b.y.time) == (5, 5)


def test_a_past_read_of_a_fresh_output_is_served_from_its_cache(graph):
    a = graph.add(Scale("a"))
    a.u.set(1.0)
    assert a.y(5) == 2.0
    assert a.y(4) == 2.0 and (a.y.time, a.y.count) == (5, 1)


def test_a_time_varying_output_is_evaluated_at_an_earlier_tick_but_not_what_reads_it(graph):
    """A function of the tick is sampled anywhere, without moving its stamp back; an output
    computed from it keeps its stamp."""
    c, d = graph.add(Clocked("c"), Scale("d"))
    graph.plug("c.now", "d.u")
    assert d.y(5) == 10.0
    assert c.now(3) == 3.0 and (c.now.time, c.now.value) == (5, 5.0)
    assert c.now(5) == 5.0 and c.now.time == 5
    assert c.now(7) == 7.0 and c.now.time == 7
    with pytest.raises(dg.DGraphError, match=r"d\.y was read at tick 3, but it is stamped 5"):
        d.y(3)
    assert (d.y.time, d.y.value) == (5, 10.0)


def test_plug_and_unplug_invalidate_and_unplug_falls_back_to_default(graph):
    a, s = graph.add(Scale("a"), Sum2("s"))
    a.u.set(1.0)
    s.a.set(1.0)
    graph.plug("a.y", "s.b")
    assert s.s(0) == 3.0
    graph.unplug("s.b")
    assert s.b.source is None
    assert s.s(0) == 1.0


def test_constant_overrides_plug_and_plug_overrides_constant(graph):
    a, b = graph.add(Scale("a"), Scale("b"))
    a.u.set(1.0)
    graph.plug("a.y", "b.u")
    b.u.set(10.0)
    assert b.u.source is None and b.y(0) == 20.0
    graph.plug("a.y", "b.u")
    assert not b.u.is_set and b.y(0) == 4.0


def test_cache_disabled_recomputes_every_read(graph):
    a = graph.add(Scale("a"))
    a.u.set(1.0)
    graph.cache_enabled = False
    a.y(0)
    a.y(0)
    assert a.y.count == 2
    graph.cache_enabled = True
    a.y(0)
    a.y(0)
    assert a.y.count == 3


def test_unplugged_input_error_names_the_signal(graph):
    a = graph.add(Scale("a"))
    with pytest.raises(dg.UnpluggedInputError, match=r"a\.u") as info:
        a.y(0)
    assert info.value.entity == "a" and info.value.signal == "u"


def test_set_checks_shape_dtype_and_nan(graph):
    a = graph.add(Scale("a"))
    with pytest.raises(dg.SpecError, match=r"a\.u"):
        a.u.set([1.0, 2.0])
    with pytest.raises(dg.SpecError, match="NaN"):
        a.u.set(float("nan"))
    with pytest.raises(dg.SpecError):
        a.u.set("text")
    assert a.u.value is None  # nothing half-set


def test_computed_nan_and_wrong_shape_are_reported_with_the_signal(graph):
    class Bad(dg.Entity):
        mode = dg.Param("nan", kind="str")

        @dg.output(shape=(2,), depends=())
        def y(self, t):
            return np.array([np.nan, 0.0]) if self.mode == "nan" else np.zeros(3)

    assert not graph.check_values  # off by default: the hot path does not check computed values
    assert graph.add(Bad("unchecked", mode="shape")).y(0).shape == (3,)
    graph.check_values = True  # the debug switch checks every computed value
    with pytest.raises(dg.SpecError, match=r"bad\.y at tick 0: computed a value containing NaN"):
        graph.add(Bad("bad")).y(0)
    with pytest.raises(dg.SpecError, match=r"shape \(3,\)"):
        graph.add(Bad("bad2", mode="shape")).y(0)
    graph.check_values = False
    assert graph["bad2.y"](1).shape == (3,)


def test_compute_exceptions_are_wrapped_with_entity_and_signal(graph):
    class Boom(dg.Entity):
        @dg.output(shape=(), depends=())
        def y(self, t):
            raise ZeroDivisionError("nope")

    b = graph.add(Boom("boom"))
    with pytest.raises(dg.ComputeError, match=r"boom\.y failed at tick 3: ZeroDivisionError") as info:
        b.y(3)
    assert isinstance(info.value.__cause__, ZeroDivisionError)
    assert info.value.signal == "y"


def test_reentrant_read_is_reported(graph):
    class Loop(dg.Entity):
        @dg.output(shape=(), depends=())
        def y(self, t):
            return self.y(t)

    with pytest.raises(dg.ComputeError, match="during its own computation"):
        graph.add(Loop("loop")).y(0)


def test_value_and_time_never_compute(graph):
    a = graph.add(Scale("a"))
    a.u.set(1.0)
    assert a.y.value is None
    a.y(4)
    a.u.set(3.0)
    assert a.y.value == 2.0 and a.y.time == 4 and a.y.stale
    assert a.u.value == 3.0


def test_class_level_template_cannot_be_read():
    with pytest.raises(dg.DGraphError, match="class-level"):
        Scale.u(0)


def test_invalidation_has_no_recursion_limit(graph):
    dev = graph.add(Ticker("dev"))
    prev = dev.x
    for i in range(3000):
        e = graph.add(Scale(f"s{i}", k=1.0))
        graph.plug(prev, e.u)
        prev = e.y
    dev.increment()  # invalidates a 3000-long chain iteratively
    assert prev.stale


def test_check_dependencies_catches_undeclared_reads(graph):
    class Sloppy(dg.Entity):
        a = dg.Input(shape=())
        b = dg.Input(shape=(), default=1.0)

        @dg.output(shape=(), depends=("a",))
        def y(self, t):
            return self.a(t) + self.b(t)  # b is read but not declared

        @dg.output(shape=(), depends=("y",))
        def z(self, t):
            return self.y(t)  # y itself reads a (and b): checked with y's own declaration

    s = graph.add(Sloppy("s"))
    s.a.set(1.0)
    assert s.z(0) == 2.0  # unnoticed without the check
    graph.check_dependencies = True
    s.a.set(2.0)
    with pytest.raises(dg.DependencyError, match=r"s\.y read s\.b at tick 1 but does not declare it"):
        s.z(1)
    late = graph.add(Sloppy("late"))  # entities added later are checked too
    late.a.set(0.0)
    with pytest.raises(dg.DependencyError, match=r"late\.y read late\.b"):
        late.y(2)
    graph.check_dependencies = False
    assert s.z(3) == 3.0 and isinstance(s.b, dg.Input)  # ports restored after the failure


def test_check_dependencies_passes_for_correct_declarations(graph):
    graph.check_dependencies = True
    graph.add(Ticker("dev"))
    _a, b = graph.add(Scale("a"), Scale("b"))
    graph.plug("dev.x", "a.u")
    graph.plug("a.z", "b.u")
    graph.run(ticks=3)
    assert b.z(graph.t) == 2 * (2 * 3 + 1) + 1


class HeldTimesTen(dg.Entity):
    u = dg.Input(shape=())

    @dg.output(shape=(), depends=("u",), period=3)
    def p(self, t):
        return self.u(t)

    @dg.output(shape=(), depends=("p",))
    def z(self, t):
        return 10 * self.p(t)


def test_a_hold_survives_leaving_or_joining_a_graph(graph):
    e = graph.add(HeldTimesTen("e"))
    e.u.set(1.0)
    assert e.z(0) == 10.0
    e.u.set(2.0)
    assert e.z(1) == 10.0  # held within the period
    graph.remove("e")
    assert e.z(5) == 20.0
    f = HeldTimesTen("f")
    f.u.set(1.0)
    f.z(0)
    f.u.set(2.0)
    f.z(1)
    graph.add(f)
    assert f.z(5) == 20.0


def test_periodic_outputs_are_sampled_by_the_loop_whoever_reads(graph):
    """Period windows start at multiples of N; what a window holds does not depend on reads."""

    def trace(cache: bool, read_every_tick: bool) -> list[float]:
        g = dg.Graph()
        g.cache_enabled = cache
        g.add(Ticker("dev"))
        e = g.add(HeldTimesTen("e"))
        e.u.set(1.0)
        out = []
        for t in range(12):
            if t == 4:
                e.u.set(2.0)
            if read_every_tick or t % 5 == 0:
                out.append(e.z(g.t))
            g.step()
        out.append(e.z(g.t))
        return out

    reference = trace(True, True)
    assert reference == [10.0] * 6 + [20.0] * 7  # sampled at 0, 3 (u=1), 6 (u=2), 9, 12
    assert trace(False, True) == reference
    sparse = trace(True, False)
    assert sparse == [reference[0], reference[5], reference[10], reference[12]]
    assert trace(False, False) == sparse


def test_a_bad_next_state_fails_before_anything_is_committed(graph):
    from dgraph.entities.discrete import Delay, Integrator

    d = graph.add(Delay("d"))
    i = graph.add(Integrator("i", dt=0.5))
    d.input.set(1.0)
    i.input.set(1.0)
    graph.step()
    d.input.set(2.0)
    i.input.set(float("-inf"))  # a state is finite: 0.5 + 0.5 * -inf is refused where it is staged
    with pytest.raises(dg.SpecError, match="inf") as info:
        graph.step()
    assert (info.value.entity, info.value.signal) == ("i", "output")
    assert graph.t == 1 and d.output.time == 1 and d.output.value == 1.0 and i.output.time == 1


def test_reset_forgets_a_constant_and_recomputes(graph):
    s = graph.add(Sum2("s"))
    s.a.set(1.0)
    s.b.set(5.0)
    assert s.s(0) == 6.0
    s.b.reset()
    assert not s.b.is_set and s.b.value == 0.0 and s.s(0) == 1.0 and s.s.count == 2
    s.a.reset()
    with pytest.raises(dg.UnpluggedInputError, match=r"s\.a"):
        s.s(0)


def _chain(graph, length):
    """A Ticker feeding ``length`` Scale entities (k = 1) in series; returns the last output."""
    graph.add(Ticker("dev", x0=1.0))
    prev = graph["dev.x"]
    for i in range(length):
        e = graph.add(Scale(f"s{i}", k=1.0))
        graph.plug(prev, e.u)
        prev = e.y
    return prev


def test_a_10000_deep_chain_runs_under_the_default_recursion_limit(graph):
    assert sys.getrecursionlimit() <= 1000  # the interpreter's default; nothing raised it
    last = _chain(graph, 10_000)
    graph.add(Probe("probe"))
    graph.plug(last, "probe.u")
    graph["dev"].before.add(graph["probe.seen"])  # the loop pulls the end of the chain every tick
    graph.run(ticks=3)
    assert last.value == 3.0 and graph["probe.seen"].value == 3.0
    assert all(graph[f"s{i}"].y.count == 3 for i in range(0, 10_000, 999))  # once per tick each


class Probe(dg.Entity):
    """Records the depth of the Python stack when its output computes."""

    u = dg.Input(shape=())

    def configure(self):
        self.depths = []

    @dg.output(shape=(), depends=("u",))
    def seen(self, t):
        self.depths.append(len(inspect.stack(0)))
        return self.u(t)


def test_evaluation_order_keeps_the_stack_flat_whatever_the_depth():
    depths = {}
    for length in (5, 500):
        g = dg.Graph()
        g.add(Probe("probe"))
        g.plug(_chain(g, length), "probe.u")
        assert g["probe.seen"](0) == 1.0
        depths[length] = g["probe"].depths[-1]
    assert depths[5] == depths[500]  # every upstream output was computed before the probe's method


def test_each_stale_output_is_computed_after_everything_it_reads(graph):
    order = []

    class Logged(dg.Entity):
        a = dg.Input(shape=())
        b = dg.Input(shape=(), default=0.0)

        @dg.output(shape=(), depends=("a", "b"))
        def y(self, t):
            order.append(self.name)
            return self.a(t) + self.b(t)

    graph.add(Ticker("dev"))
    for name in ("top", "left", "right", "bottom", "tail"):
        graph.add(Logged(name))
    for src, dst in [("dev.x", "top.a"), ("top.y", "left.a"), ("top.y", "right.a"), ("left.y", "bottom.a"),
                     ("right.y", "bottom.b"), ("bottom.y", "tail.a"), ("left.y", "tail.b")]:
        graph.plug(src, dst)
    for t in range(3):
        order.clear()
        assert graph["tail.y"](t) == 3.0 * t
        assert order.index("top") < order.index("left") < order.index("bottom") < order.index("tail")
        assert order.index("right") < order.index("bottom") and sorted(order) == sorted(set(order))
        graph.step()


def test_the_cached_evaluation_order_follows_a_replug(graph):
    graph.add(Ticker("dev"))
    old, new, _middle, end = graph.add(Scale("old"), Scale("new"), Scale("middle"), Scale("end"))
    graph.plug("dev.x", "old.u")
    graph.plug("dev.x", "new.u")
    graph.plug("old.y", "middle.u")
    graph.plug("middle.y", "end.u")
    for _ in range(3):
        assert end.y(graph.t) == 8.0 * graph.t
        graph.step()
    graph.plug("new.y", "middle.u")  # upstream of the cached order of end.y, two levels up
    new.u.set(5.0)
    for _ in range(3):
        assert end.y(graph.t) == 40.0
        graph.step()
    assert (old.y.count, new.y.count, end.y.count) == (3, 1, 4)  # the old branch is left out, the new is constant


def test_on_demand_dependencies_are_computed_only_when_read(graph):
    from dgraph.entities.operators import Switch

    graph.add(Ticker("dev"))
    first, second = graph.add(Scale("first"), Scale("second"))
    switch = graph.add(Switch("switch"))
    graph.plug("dev.x", "first.u")
    graph.plug("dev.x", "second.u")
    graph.plug("first.y", "switch.in0")
    graph.plug("second.y", "switch.in1")
    for _ in range(3):
        switch.output(graph.t)
        graph.step()
    assert (first.y.count, second.y.count) == (3, 0)  # the unselected branch is never computed
    switch.selection.set(1)
    assert switch.output(graph.t) == 2.0 * graph.t and second.y.count == 1


def test_a_holding_periodic_output_keeps_its_upstream_idle(graph):
    graph.add(Ticker("dev"))
    upstream = graph.add(Scale("upstream"))
    held = graph.add(Periodic("held", every=5))
    reader = graph.add(Sum2("reader"))
    graph.plug("dev.x", "upstream.u")
    graph.plug("upstream.y", "held.u")
    graph.plug("held.y", "reader.a")
    graph.plug("dev.x", "reader.b")  # the reader is stale every tick, the held output only every 5
    for _ in range(10):
        assert reader.s(graph.t) == 2.0 * (graph.t - graph.t % 5) + graph.t
        graph.step()
    assert reader.s.count == 10 and held.y.count == 2 and upstream.y.count == 2


def test_staging_without_a_copy_keeps_the_array_and_still_refuses_nan(graph):
    class Holder(dg.Entity):
        has_state = True
        x = dg.State(shape=(2,), initial=np.zeros(2))

    x = graph.add(Holder("h")).x
    fresh = np.array([1.0, 2.0])
    x.stage(fresh, copy=False)
    x.commit(1)
    assert x.value is fresh
    x.stage(fresh)
    x.commit(2)
    assert x.value is not fresh and x.value.tolist() == [1.0, 2.0]
    with pytest.raises(dg.SpecError, match="NaN"):
        x.stage(np.array([np.nan, 0.0]), copy=False)


def test_staging_views_of_a_block_checks_the_block_once_and_names_a_state_with_nan(graph):
    class Sensors(dg.Entity):
        has_state = True
        wrench = dg.State(shape=(6,), initial=np.zeros(6))
        force = dg.State(shape=(3,), initial=np.zeros(3))
        torque = dg.State(shape=(3,), initial=np.zeros(3))

    sensors = graph.add(Sensors("ft"))
    parts = [(sensors.wrench, None), (sensors.force, slice(0, 3)), (sensors.torque, slice(3, 6))]
    block = np.arange(6.0)
    dg.stage_views([(block, parts)])
    dg.commit_all([sensors.wrench, sensors.force, sensors.torque], 1)
    assert sensors.wrench.value is block and sensors.force.value.base is block  # no copies
    assert sensors.torque.value.tolist() == [3.0, 4.0, 5.0]
    block = np.array([0.0, 1.0, 2.0, 3.0, np.nan, 5.0])
    with pytest.raises(dg.SpecError, match=r"ft\.wrench.*NaN"):
        dg.stage_views([(block, parts)])
    with pytest.raises(dg.SpecError, match=r"ft\.torque.*NaN"):  # the first view holding the NaN is named
        dg.stage_views([(block, parts[1:])])
    with pytest.raises(dg.SpecError, match=r"ft\.force"):  # a wrong shape is refused as by stage
        dg.stage_views([(np.zeros(4), [(sensors.force, None)])])


def test_committing_states_together_invalidates_their_readers_once_and_alike(graph):
    class Pair(dg.Entity):
        has_state = True
        a = dg.State(shape=(), initial=0.0)
        b = dg.State(shape=(), initial=0.0)

    pair = graph.add(Pair("pair"))
    readers = graph.add(Sum2("both"))
    graph.plug("pair.a", "both.a")
    graph.plug("pair.b", "both.b")
    assert readers.s(0) == 0.0
    pair.a.stage(1.0)
    pair.b.stage(2.0)
    dg.commit_all([pair.a, pair.b], 1)
    assert (pair.a.time, pair.b.time, readers.s.stale) == (1, 1, True)
    assert readers.s(1) == 3.0 and readers.s.count == 2
    pair.a.stage(5.0)
    with pytest.raises(dg.DGraphError, match=r"pair\.b: commit at tick 2 without a staged value"):
        dg.commit_all([pair.a, pair.b], 2)
    assert pair.a.value == 1.0 and pair.a.time == 1  # nothing published: the states stay consistent


def test_an_on_demand_name_must_be_a_dependency():
    class Typo(dg.Entity):
        u = dg.Input(shape=())

        @dg.output(shape=(), depends=("u",), on_demand=("uu",))
        def y(self, t):
            return self.u(t)

    with pytest.raises(dg.DGraphError, match=r"typo\.y declares 'uu' on demand"):
        Typo("typo")


def test_an_output_on_another_clock_still_computes_once_per_tick():
    """Entities outside a graph have clocks of their own; plugged by hand, a time-varying source
    is left to its reader's input, which moves the source's clock first."""
    class Shifted(dg.Entity):
        c = dg.Input(shape=(), default=0.0)

        @dg.output(shape=(), depends=("c", "t"))
        def y(self, t):
            return self.c(t) + t

    source, reader = Shifted("source"), Scale("reader")
    reader.u.plug(source.y)
    for t in range(3):
        source.c.set(10.0 * t)  # invalidates the reader too (across clocks, through the plug)
        assert reader.y(t) == 2.0 * (11.0 * t)
    assert source.y.count == 3 and reader.y.count == 3


def test_an_input_minimum_refuses_constants_and_defaults_below_it_where_they_are_set(graph):
    class Weighted(dg.Entity):
        weight = dg.Input(default=1.0, minimum=0.0)
        gain = dg.Input(shape=(2,), default=np.ones(2), minimum=0.0)

        @dg.output(shape=None, depends=("weight", "gain"))
        def y(self, t):
            return self.weight(t) * self.gain(t)

    e = graph.add(Weighted("e"))
    e.weight.set(0.0)
    e.gain.set(np.array([0.0, 3.0]))  # the float fast path of set is taken only without a bound
    with pytest.raises(dg.SpecError, match=r"e\.weight: must be >= 0, got -1\.0") as caught:
        e.weight.set(-1.0)
    assert (caught.value.entity, caught.value.signal) == ("e", "weight")
    with pytest.raises(dg.SpecError, match=r"e\.gain: must be >= 0"):
        e.gain.set(np.array([1.0, -1e-9]))
    assert e.weight.value == 0.0 and e.gain.value.tolist() == [0.0, 3.0]  # the refused values were not kept

    class BadDefault(dg.Entity):
        k = dg.Input(default=-1.0, minimum=0.0)

    with pytest.raises(dg.SpecError, match=r"b\.k: must be >= 0"):
        BadDefault("b")


class RawReadings(dg.Entity):
    """A driver's raw readings (``finite=None``) beside a checked state."""

    has_state = True
    reading = dg.State(shape=(3,), finite=None)
    checked = dg.State(shape=(3,))
    raw_input = dg.Input(shape=(2,), finite=None)


def test_a_raw_state_is_staged_nan_and_all_and_a_checked_one_refuses_it():
    """A device's sensor states are raw (``finite=None``): a NaN reading reaches its readers'
    guard instead of failing the tick; its own state (``finite``, the default) still refuses it."""
    e = RawReadings("e")
    for value in (np.array([np.nan, 0.0, 1.0]), np.array([np.inf, 0.0, 1.0]), [np.nan, 0.0, 1.0]):
        e.reading.set(value, 1)
        assert np.isnan(e.reading.value[0]) or np.isinf(e.reading.value[0])
        with pytest.raises(dg.SpecError, match="NaN|inf"):
            e.checked.stage(value)
    e.raw_input.set([np.nan, 1.0])
    assert np.isnan(e.raw_input(0)[0])
