"""The device loop: hook order, failures that leave the state consistent, run lengths."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from tests.conftest import Follower, Scale, Ticker


def test_tick_order_before_control_commit_after(graph):
    events = []
    dev = graph.add(Ticker("dev"))
    a = graph.add(Scale("a"))
    graph.plug("dev.x", "a.u")

    class Spy(dg.Entity):
        observes = True

        def observe(self, t):
            events.append(("observe", t, dev.x.time))

    graph.add(Spy("spy"))
    dev.before.add(lambda t: events.append(("before", t, dev.x.time)))
    dev.after.add(lambda t: events.append(("after", t, dev.x.time)))
    dev.after.add(a.y)  # a signal hook is pulled at t + 1
    graph.step()
    assert events == [("before", 0, 0), ("observe", 0, 0), ("after", 1, 1)]
    assert a.y.time == 1 and a.y.value == 2.0


def test_hooks_keep_explicit_order(graph):
    dev = graph.add(Ticker("dev"))
    order = []
    dev.before.add(lambda t: order.append("b"))
    dev.before.add(lambda t: order.append("a"), index=0)
    dev.before.add(lambda t: order.append("c"))
    graph.step()
    assert order == ["a", "b", "c"] and len(dev.before) == 3


def test_failing_before_hook_leaves_state_untouched_and_names_the_hook(graph):
    dev = graph.add(Ticker("dev", x0=1.0))
    calls = {"n": 0}

    def flaky(t):
        calls["n"] += 1
        if calls["n"] == 2:
            raise RuntimeError("sensor timeout")

    dev.before.add(flaky)
    graph.step()
    with pytest.raises(dg.HookError, match=r"before hook .*flaky of device dev failed at tick 1: RuntimeError") as info:
        graph.step()
    assert isinstance(info.value.__cause__, RuntimeError)
    assert graph.t == 1 and dev.x.value == 2.0 and dev.x.time == 1  # not advanced, not corrupted
    graph.step()  # the loop resumes
    assert graph.t == 2 and dev.x.value == 3.0


def test_failing_signal_hook_names_its_entity(graph):
    dev = graph.add(Ticker("dev"))
    a = graph.add(Scale("a"))  # u unplugged: pulling it fails
    dev.after.add(a.y)
    with pytest.raises(dg.HookError, match=r"after hook a\.y of device dev") as info:
        graph.step()
    assert info.value.entity == "a" and info.value.signal == "y"
    assert graph.t == 1 and dev.x.time == 1  # committed before the after hooks


def test_failure_while_pulling_control_commits_nothing(graph):
    graph.add(Ticker("first"))

    class FollowerDevice(Follower, dg.Device):
        """A device that pulls its unplugged input when it integrates."""

    graph.add(FollowerDevice("second"))
    with pytest.raises(dg.UnpluggedInputError, match=r"second\.u"):
        graph.step()
    assert graph["first.x"].time == 0 and graph.t == 0


def test_standalone_device_increment():
    dev = Ticker("dev")
    order = []
    dev.before.add(lambda t: order.append(t))
    dev.increment()
    dev.increment()
    assert dev.t == 2 and dev.x.value == 2.0 and order == [0, 1]


def test_bad_hook_is_refused(graph):
    dev = graph.add(Ticker("dev"))
    with pytest.raises(dg.HookError, match="must be a signal or a callable"):
        dev.before.add(42)


def test_run_lengths_and_errors(graph):
    graph.add(Ticker("dev"))
    graph.run(ticks=10)
    graph.run(duration=0.05)  # dt = 0.01
    assert graph.t == 15
    with pytest.raises(dg.GraphError, match="exactly one"):
        graph.run()
    with pytest.raises(dg.GraphError, match="exactly one"):
        graph.run(ticks=1, duration=1.0)
    with pytest.raises(dg.GraphError):
        graph.run(ticks=-1)
    with pytest.raises(dg.GraphError, match="no device"):
        dg.Graph().run(ticks=1)


def test_long_run_shows_progress(graph, capsys):
    graph.add(Ticker("dev"))
    graph.run(ticks=300, progress=True)
    assert "tick" in capsys.readouterr().err
    graph.run(ticks=300)  # short: no bar by default
    assert capsys.readouterr().err == ""


def test_ctrl_c_stops_between_ticks_with_every_state_committed(graph):
    import os
    import random
    import signal
    import threading

    from dgraph.entities.discrete import Delay

    graph.add(Ticker("dev"))
    delays = [graph.add(Delay(f"d{i}")) for i in range(100)]
    for d in delays:
        d.input.set(1.0)
    rng = random.Random(0)
    for _ in range(15):
        timer = threading.Timer(rng.uniform(0.001, 0.02), os.kill, (os.getpid(), signal.SIGINT))
        timer.start()
        with pytest.raises(KeyboardInterrupt, match="interrupted at tick"):
            graph.run(ticks=10**7, progress=False)
        timer.join()
        stamps = {graph["dev.x"].time} | {d.output.time for d in delays}
        assert stamps == {graph.t}
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")  # the NaN is the point
def test_a_failed_tick_with_a_periodic_output_can_be_fixed_and_resumed(graph):
    from dgraph.entities.devices import KinematicDevice
    from dgraph.entities.operators import Gain

    class Planner(dg.Entity):
        u = dg.Input(shape=(1,), default=[0.0])

        @dg.output(shape=(1,), depends=("u",), period=4)
        def p(self, t):
            return self.u(t) * 1.0

    planner = graph.add(Planner("planner"))
    k = graph.add(Gain("k", size=1))
    graph.add(KinematicDevice("robot", size=1))
    graph.plug("planner.p", "k.input")
    graph.plug("k.output", "robot.control")
    k.gain.set(0.0)
    graph.run(ticks=4)
    planner.u.set([float("inf")])  # 0 * inf = NaN downstream: the device refuses it as its next state
    with pytest.raises(dg.SpecError, match=r"robot\.q: value contains NaN") as info:
        graph.step()
    assert (info.value.entity, graph.t, graph["robot.q"].time) == ("robot", 4, 4)
    planner.u.set([1.0])
    graph.run(ticks=3)  # the window's sample is taken again with the fixed input
    assert graph.t == 7 and planner.p.value.tolist() == [1.0]


def test_recorders_keep_no_row_of_a_failed_tick(graph):
    from dgraph.entities.discrete import Delay
    from dgraph.entities.operators import Switch
    from dgraph.entities.recording import Recorder

    d = graph.add(Delay("d"))
    d.input.set(1.0)
    sw = graph.add(Switch("sw"))
    sw.in0.set(0.0)
    sw.in1.set(1.0)
    a = graph.add(Recorder("a", signals=["d.output"], rerun="off"))
    b = graph.add(Recorder("b", signals=["sw.output"], rerun="off"))
    graph.run(ticks=2)
    sw.selection.set(1)
    sw.in1.reset()  # b fails after a has read its row: the selected input is neither plugged nor set
    with pytest.raises(dg.UnpluggedInputError):
        graph.step()
    sw.in1.set(1.0)
    graph.run(ticks=2)
    assert a.data()["tick"].tolist() == b.data()["tick"].tolist() == [0, 1, 2, 3]


def test_an_entity_joining_a_graph_recomputes_on_the_graph_time():
    from dgraph.entities.references import Sinusoid

    g = dg.Graph(dt=0.05)
    g.add(Ticker("dev"))
    g["dev"].after.add(g["dev.x"])  # keeps the graph clock at graph.t between ticks
    g.run(ticks=5)
    ref = Sinusoid("ref", amplitude=1.0, frequency=0.7, dt=0.05)
    before = ref.output(5)  # read on its own clock
    g.step()
    g.add(ref)
    assert ref.output(g.t) == pytest.approx(np.sin(2 * np.pi * 0.7 * 6 * 0.05)) != before
