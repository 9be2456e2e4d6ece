"""Graph: names, plugs, cycle refusal, validation, drawings, explain, profile."""

from __future__ import annotations

import networkx as nx
import pytest

import dgraph as dg
from dgraph.entities.discrete import Delay
from dgraph.entities.operators import Add, Constant, Gain
from tests.conftest import Scale, Sum2, Ticker


def test_unique_names_and_lookup(graph):
    a = graph.add(Scale("a"))
    with pytest.raises(dg.GraphError, match="already in the graph"):
        graph.add(Scale("a"))
    assert graph["a"] is a and graph["a.y"] is a.y and "a" in graph and len(graph) == 1
    with pytest.raises(dg.GraphError, match="no entity named 'b'"):
        graph["b.y"]
    with pytest.raises(dg.DGraphError, match="has no signal 'w'.*it has: u, unused, y, z"):
        graph["a.w"]
    other = dg.Graph()
    with pytest.raises(dg.GraphError, match="already belongs"):
        other.add(a)


def test_plug_refuses_shape_mismatch_at_plug_time(graph):
    graph.add(Gain("v3", size=3), Gain("v2", size=2))
    with pytest.raises(dg.PlugError, match=r"v3\.output float\(3,\) into v2\.input float\(2,\)") as info:
        graph.plug("v3.output", "v2.input")
    assert info.value.entity == "v2" and info.value.signal == "input"
    assert graph["v2.input"].source is None


def test_plug_direction_and_graph_membership(graph):
    a, b = graph.add(Scale("a"), Scale("b"))
    with pytest.raises(dg.PlugError, match="it is an input"):
        graph.plug("a.u", "b.u")
    with pytest.raises(dg.PlugError, match="it is an output"):
        graph.plug("a.y", "b.y")
    stranger = Scale("stranger")
    with pytest.raises(dg.PlugError, match="same graph"):
        dg.plug(stranger.y, a.u)
    dg.plug(a.y, b.u)
    assert graph.plugs() == [("a.y", "b.u")]


def test_cycle_is_refused_and_listed(graph):
    a, _b, _c = graph.add(Scale("a"), Scale("b"), Scale("c"))
    graph.plug("a.y", "b.u")
    graph.plug("b.y", "c.u")
    with pytest.raises(dg.CycleError) as info:
        graph.plug("c.y", "a.u")
    assert info.value.cycle == ["c.y", "a.u", "a.y", "b.u", "b.y", "c.u", "c.y"]
    assert "c.y -> a.u -> a.y -> b.u -> b.y -> c.u -> c.y" in str(info.value)
    assert a.u.source is None
    with pytest.raises(dg.CycleError):
        graph.plug("a.z", "a.u")  # a loop inside one entity through its own dependency


def test_delay_closes_a_loop_legally(graph):
    graph.add(Ticker("dev"))  # something to step the loop
    delay = graph.add(Delay("memory", initial=0.0))
    half = graph.add(Gain("half"))
    plus_one = graph.add(Add("plus_one"))
    half.gain.set(0.5)
    plus_one.in1.set(1.0)
    graph.plug("memory.output", "half.input")
    graph.plug("half.output", "plus_one.in0")
    graph.plug("plus_one.output", "memory.input")  # x(t+1) = 0.5 x(t) + 1 -> 2
    graph.validate()
    graph.run(ticks=60)
    assert delay.output.value == pytest.approx(2.0, abs=1e-12)
    assert nx.is_directed_acyclic_graph(graph.signal_graph())


def test_validate_lists_every_problem(graph):
    graph.add(Scale("a"), Sum2("s"))
    with pytest.raises(dg.GraphError) as info:
        graph.validate()
    text = str(info.value)
    assert "input a.u is not plugged" in text and "input s.a is not plugged" in text
    assert "a.unused" not in text and "s.b" not in text  # those have defaults
    graph["a.u"].set(1.0)
    graph.plug("a.y", "s.a")
    graph.validate()


def test_remove_unplugs(graph):
    graph.add(Scale("a"), Scale("b"))
    graph.plug("a.y", "b.u")
    removed = graph.remove("a")
    assert removed.graph is None and graph["b.u"].source is None and "a" not in graph


def test_exports_name_every_entity_and_plug(graph):
    graph.add(Constant("ref", value=[1.0, 2.0]), Gain("k", size=2))
    graph.plug("ref.output", "k.input")
    dot = graph.to_dot()
    assert 'n_ref -> n_k [label="output -> input"]' in dot and "(Constant)" in dot
    dot_signals = graph.to_dot(signals=True)
    assert "cluster_k" in dot_signals and "n_ref_output -> n_k_input;" in dot_signals
    assert "n_k_gain -> n_k_output [style=dashed]" in dot_signals
    mermaid = graph.to_mermaid()
    assert mermaid.startswith("flowchart LR") and 'n_ref -- "output -> input" --> n_k' in mermaid
    assert "n_ref_output --> n_k_input" in graph.to_mermaid(signals=True)


def test_explain_says_why(graph):
    graph.add(Ticker("dev"))
    _a, b = graph.add(Scale("a"), Scale("b"))
    graph.plug("dev.x", "a.u")
    b.u.set(1.0)
    b.y(0)
    text_a = graph.explain("a.y")
    assert "will recompute at the next tick" in text_a and "dev.x is the state of dev" in text_a
    text_b = graph.explain("b.y")
    assert "will NOT recompute" in text_b and "b.u" in text_b and "fresh" in text_b
    assert "UNPLUGGED" in graph.explain(graph.add(Sum2("s")).a)


def test_profile_counts_recomputations_per_tick(graph):
    graph.add(Ticker("dev"))
    a, b = graph.add(Scale("a"), Scale("b"))
    graph.plug("dev.x", "a.u")
    b.u.set(1.0)
    dev = graph["dev"]
    dev.before.add(a.y)
    dev.before.add(b.y)
    prof = graph.profile(ticks=50)
    rows = {e.name: e for e in prof.entities}
    assert rows["a"].computations_per_tick == 1.0
    assert rows["b"].computations_per_tick <= 1 / 50
    assert prof.us_per_tick > 0 and "us/tick" in str(prof)


def test_removed_entity_keeps_working_on_its_own_clock(graph):
    from dgraph.entities.references import Sinusoid

    s = graph.add(Sinusoid("s", amplitude=1.0, frequency=1.0, dt=0.25))
    assert s.output(1) == pytest.approx(1.0)
    graph.remove("s")
    assert s.output not in graph.clock.time_varying and s.output._clock is not graph.clock
    assert s.output(2) == pytest.approx(0.0, abs=1e-12) and s.output(3) == pytest.approx(-1.0)


def test_close_closes_every_entity_and_names_the_first_failure(tmp_path):
    from dgraph.entities.recording import Recorder

    class Leaky(dg.Entity):
        """An entity whose close fails."""

        def close(self):
            raise OSError("disk full")

    g = dg.Graph(dt=0.001)
    g.add(Leaky("leaky"))
    g.add(Ticker("clock"))
    g.add(Scale("s"))
    g.plug("clock.x", "s.u")
    recorder = g.add(Recorder("rec", signals=["s.y"], rerun="off", npz_path=str(tmp_path / "r.npz")))
    g.run(ticks=3, progress=False)
    with pytest.raises(dg.GraphError, match="closing leaky failed: OSError: disk full") as err:
        g.close()
    assert err.value.entity == "leaky"
    assert recorder.closed and (tmp_path / "r.npz").is_file()  # closed after the failure all the same
