"""Recorder: .npz columns and a Rerun .rrd with readable series, without changing the run."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.recording import Recorder, read_series
from dgraph.entities.recording.recorder import component_names
from dgraph.entities.references import Sinusoid
from tests.conftest import Scale, Ticker


def build(tmp_path: Path, rerun: str = "save") -> dg.Graph:
    g = dg.Graph(dt=0.01, name="rec_test")
    g.add(Ticker("dev"))
    g.add(Sinusoid("ref", amplitude=[1.0, 2.0, 0.0], frequency=1.0))
    g.add(Scale("a"))
    g.plug("dev.x", "a.u")
    g.add(Recorder("rec", signals=["dev.x", "a.y", "ref.output"], rerun=rerun,
                   rrd_path=str(tmp_path / "run.rrd"), npz_path=str(tmp_path / "run.npz"), flush_every=7))
    return g


def test_npz_and_rrd_hold_the_expected_series(tmp_path):
    g = build(tmp_path)
    g.run(ticks=50)
    g.close()
    data = np.load(tmp_path / "run.npz")
    assert np.array_equal(data["tick"], np.arange(50)) and np.allclose(data["time"], np.arange(50) * 0.01)
    assert np.array_equal(data["dev.x"], np.arange(50.0))
    assert np.array_equal(data["a.y"], 2 * np.arange(50.0))
    assert data["ref.output"].shape == (50, 3)
    assert np.allclose(data["ref.output"][:, 1], 2.0 * np.sin(2 * np.pi * np.arange(50) * 0.01))

    series = read_series(str(tmp_path / "run.rrd"))
    assert set(series) == {"/signals/dev/x", "/signals/a/y", "/signals/ref/output"}
    ticks, values = series["/signals/ref/output"]
    assert np.array_equal(ticks, np.arange(50)) and values.shape == (50, 3)
    assert np.allclose(values, data["ref.output"])


def test_rrd_passes_rerun_verify(tmp_path):
    g = build(tmp_path)
    g.run(ticks=20)
    g.close()
    rerun_cli = Path(sys.executable).with_name("rerun")
    result = subprocess.run([str(rerun_cli), "rrd", "verify", str(tmp_path / "run.rrd")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr


def test_recording_does_not_change_what_is_computed(tmp_path):
    recorded = build(tmp_path)
    plain = dg.Graph(dt=0.01)
    plain.add(Ticker("dev"))
    a = plain.add(Scale("a"))
    plain.plug("dev.x", "a.u")
    recorded.run(ticks=30)
    plain.run(ticks=30)
    recorded.close()
    # the recorder reads a.y once per tick, exactly as a controller would
    assert recorded["a.y"].count == 30 and recorded["a.y"].value == 2 * 29
    assert a.y.count == 0  # nothing pulls it in the plain graph


def test_component_names_use_labels_or_indices():
    class Labelled(dg.Entity):
        @dg.output(shape=(3,), labels=("x", "y", "z"), depends=())
        def com(self, t):
            return np.zeros(3)

    e = Labelled("e")
    assert component_names(e.com, (3,)) == ["com.x", "com.y", "com.z"]
    assert component_names(Scale("s").y, ()) == ["y"]
    assert component_names(Ticker("d").x, (2, 2)) == ["x[0,0]", "x[0,1]", "x[1,0]", "x[1,1]"]


def test_unknown_recorded_signal_is_reported(tmp_path):
    g = dg.Graph()
    g.add(Ticker("dev"))
    g.add(Recorder("rec", signals=["dev.nope"]))
    with pytest.raises(dg.GraphError, match=r"recorded signal 'dev\.nope'"):
        g.validate()
    with pytest.raises(dg.GraphError, match="has no signal 'nope'"):
        g.step()


def test_a_recorder_writes_nothing_unless_asked(tmp_path):
    g = dg.Graph(name="defaults")
    g.add(Ticker("dev"))
    rec = g.add(Recorder("rec", signals=["dev.x"]))
    g.run(ticks=3)
    g.close()
    assert rec.rerun == "off" and list(tmp_path.iterdir()) == []  # the test runs in tmp_path
    assert rec.data()["dev.x"].tolist() == [0.0, 1.0, 2.0]  # recorded in memory all the same


def test_save_defaults_to_an_rrd_file_named_after_the_graph_and_a_path_asks_for_save(tmp_path):
    g = dg.Graph(name="defaults")
    g.add(Ticker("dev"))
    g.add(Recorder("rec", signals=["dev.x"], rerun="save"))
    g.add(Recorder("named", signals=["dev.x"], rrd_path="named.rrd"))
    g.run(ticks=3)
    g.close()
    assert g["named"].rerun == "save"
    assert (tmp_path / "out" / "defaults.rrd").stat().st_size > 0 and (tmp_path / "named.rrd").stat().st_size > 0


def test_the_session_default_applies_to_recorders_that_do_not_choose(tmp_path):
    from dgraph.entities.recording.rerun_stream import recording_by_default

    with recording_by_default("save"):
        assert Recorder("a", signals=["dev.x"]).rerun == "save"
        assert Recorder("b", signals=["dev.x"], rerun="off").rerun == "off"
    assert Recorder("c", signals=["dev.x"]).rerun == "off"
    with pytest.raises(dg.GraphError, match="Rerun sink 'disk'"), recording_by_default("disk"):
        pass
    with pytest.raises(dg.ParamError, match="decimation"):
        Recorder("bad", signals=["dev.x"], decimation=0)


def test_sends_are_buffered_longer_to_a_file_than_to_a_viewer():
    assert Recorder("file", signals=["dev.x"]).flush_every == 1000
    assert Recorder("live", signals=["dev.x"], rerun="serve").flush_every == 200
    assert Recorder("set", signals=["dev.x"], rerun="spawn", flush_every=5).flush_every == 5


def test_close_is_idempotent_and_in_memory_data(tmp_path):
    g = build(tmp_path, rerun="off")
    g.run(ticks=5)
    rec = g["rec"]
    assert rec.data()["dev.x"].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]
    g.close()
    g.close()
    assert not (tmp_path / "run.rrd").exists() and (tmp_path / "run.npz").exists()


def test_graph_as_context_manager_flushes_on_error(tmp_path):
    g = build(tmp_path)
    with pytest.raises(dg.HookError), g:
        g.run(ticks=10)
        g["dev"].before.add(g.add(Scale("dangling")).y)  # its input is unplugged: the hook fails
        g.run(ticks=5)
    assert np.load(tmp_path / "run.npz")["tick"].tolist() == list(range(10))
    assert read_series(str(tmp_path / "run.rrd"))["/signals/dev/x"][0].tolist() == list(range(10))


def test_columns_stay_aligned_after_a_failed_read_and_duplicates_are_refused(tmp_path):
    g = dg.Graph(name="../../escape")
    g.add(Ticker("dev"))
    g.add(Scale("a"))
    rec = g.add(Recorder("rec", signals=["dev.x", "a.y"], rerun="save"))
    with pytest.raises(dg.UnpluggedInputError):
        g.step()  # a.u is unplugged: nothing recorded for that tick
    g.plug("dev.x", "a.u")
    g.run(ticks=2)
    g.close()
    data = rec.data()
    assert data["tick"].tolist() == [0, 1] and data["dev.x"].tolist() == [0.0, 1.0] and len(data["a.y"]) == 2
    assert rec.rrd_path == "out/_.._escape.rrd" and (tmp_path / "out" / "_.._escape.rrd").exists()
    with pytest.raises(dg.ParamError, match=r"recorded twice: dev\.x"):
        Recorder("dup", signals=["dev.x", "a.y", "dev.x"])


def test_a_value_that_changes_shape_fails_its_tick_before_anything_commits(tmp_path):
    class Growing(dg.Entity):
        u = dg.Input()

        @dg.output()
        def y(self, t: int) -> np.ndarray:
            return np.zeros(2 if self.u(t) < 3 else 3)

    g = dg.Graph(dt=0.01, name="rec_shape")
    g.add(Ticker("dev"), Growing("grow"))
    g.plug("dev.x", "grow.u")
    recorder = g.add(Recorder("rec", signals=["dev.x", "grow.y"], rerun="off"))
    expected = r"rec: grow\.y at tick 3 has shape \(3,\), its first recorded value had \(2,\)"
    with pytest.raises(dg.SpecError, match=expected):
        g.run(ticks=10)
    assert g.t == 3 and g["dev"].x.time == 3  # the failed tick committed nothing: the loop can resume
    assert recorder.data()["dev.x"].tolist() == [0.0, 1.0, 2.0]  # and the rows before it are all there


# -- faults -------------------------------------------------------------------------------------

class Flaky(dg.Entity):
    """y = u, except at tick 2, where y had bad data: 0 is used instead and a fault reported."""

    u = dg.Input(shape=())

    @dg.output(shape=(), depends=("u", "t"))
    def y(self, t):
        if t == 2:
            self.report_fault(t, "y", "NaN", "replaced by 0", "nan")
            return 0.0
        return self.u(t)


def faulty_graph(tmp_path: Path, rerun: str = "off") -> dg.Graph:
    g = dg.Graph(dt=0.01, name="rec_faults")
    g.add(Ticker("dev"), Flaky("flaky"))
    g.plug("dev.x", "flaky.u")
    g.add(Recorder("rec", signals=["dev.x", "flaky.y"], rerun=rerun, rrd_path=str(tmp_path / "faults.rrd"),
                   npz_path=str(tmp_path / "faults.npz")))
    return g


FAULT_ARRAYS = {"fault_tick": [2], "fault_signal": ["flaky.y"], "fault_cause": ["NaN"],
                "fault_action": ["replaced by 0"], "fault_detail": ["nan"]}


def test_the_faults_of_the_recorded_ticks_are_in_the_data(tmp_path):
    g = faulty_graph(tmp_path)
    g.run(ticks=5)
    data = g["rec"].data()
    assert data["flaky.y"].tolist() == [0.0, 1.0, 0.0, 3.0, 4.0]
    assert data["degraded"].dtype == bool and data["degraded"].tolist() == [False, False, True, False, False]
    for key, value in FAULT_ARRAYS.items():
        assert data[key].tolist() == value, key
    assert data["fault_tick"].dtype == np.int64


def test_the_npz_holds_the_faults_and_loads_without_pickle(tmp_path):
    g = faulty_graph(tmp_path)
    g.run(ticks=5)
    g.close()
    with np.load(tmp_path / "faults.npz") as data:  # allow_pickle=False: plain string arrays
        assert data["degraded"].tolist() == [False, False, True, False, False]
        for key, value in FAULT_ARRAYS.items():
            assert data[key].tolist() == value, key
        assert data["fault_signal"].dtype.kind == "U"


def test_a_run_without_fault_records_empty_fault_arrays(tmp_path):
    g = build(tmp_path, rerun="off")
    g.run(ticks=4)
    g.close()
    with np.load(tmp_path / "run.npz") as data:
        assert data["degraded"].tolist() == [False] * 4
        assert all(data[key].shape == (0,) for key in FAULT_ARRAYS)


def test_a_failed_tick_leaves_no_fault_and_its_retry_records_it_once(tmp_path):
    class Bomb(dg.Entity):
        observes = True  # observes after the recorder: the tick fails once its row is read

        def setup(self):
            self.armed = True

        def observe(self, t):
            if t == 2 and self.armed:
                self.armed = False
                raise RuntimeError("boom")

    g = faulty_graph(tmp_path)
    g.add(Bomb("bomb"))
    g.run(ticks=2)
    with pytest.raises(RuntimeError, match="boom"):
        g.step()
    data = g["rec"].data()
    assert data["tick"].tolist() == [0, 1] and not data["degraded"].any() and data["fault_tick"].size == 0
    g.run(ticks=3)
    data = g["rec"].data()
    assert data["tick"].tolist() == [0, 1, 2, 3, 4] and data["degraded"].tolist() == [False, False, True, False, False]
    assert data["fault_tick"].tolist() == [2] and g.fault_log.degraded_ticks == 1


def logged_faults(rrd: Path) -> list[tuple[int, list[str], list[str]]]:
    """``(tick, texts, levels)`` of the ``faults`` text log of an .rrd file."""
    import rerun.chunk as chunk

    logged = []
    for ch in chunk.RrdReader(str(rrd)).stream():
        batch = ch.to_record_batch()
        if str(ch.entity_path) == "/faults" and "TextLog:text" in batch.schema.names:
            logged += zip(batch.column("tick").to_pylist(), batch.column("TextLog:text").to_pylist(),
                          batch.column("TextLog:level").to_pylist(), strict=True)
    return logged


def test_the_rrd_has_the_faults_text_log(tmp_path):
    g = faulty_graph(tmp_path, rerun="save")
    g.run(ticks=5)
    g.close()
    assert (tmp_path / "faults.rrd").stat().st_size > 0
    assert logged_faults(tmp_path / "faults.rrd") == [(2, ["tick 2: flaky.y: NaN (nan); replaced by 0"], ["WARN"])]
    ticks, values = read_series(str(tmp_path / "faults.rrd"))["/signals/flaky/y"]
    assert ticks.tolist() == [0, 1, 2, 3, 4] and values.ravel().tolist() == [0.0, 1.0, 0.0, 3.0, 4.0]


class Dead(dg.Entity):
    """y = u, with a fault at every tick (a sensor dead for good)."""

    u = dg.Input(shape=())

    @dg.output(shape=(), depends=("u", "t"))
    def y(self, t):
        self.report_fault(t, "y", "NaN", "replaced by 0")
        return 0.0


def test_a_recording_keeps_what_the_fault_log_keeps_and_marks_every_degraded_tick(tmp_path, monkeypatch):
    """A sensor dead for minutes must not fill the memory or the viewer: past KEPT_FAULTS the
    faults are no longer kept, the degraded ticks still are."""
    import dgraph.faults as faults_module

    monkeypatch.setattr(faults_module, "KEPT_FAULTS", 2)
    g = dg.Graph(dt=0.01, name="dead")
    g.add(Ticker("dev"), Dead("dead"))
    g.plug("dev.x", "dead.u")
    g.add(Recorder("rec", signals=["dead.y"], rerun="off"))
    g.run(ticks=4)
    data = g["rec"].data()
    assert data["fault_tick"].tolist() == [0, 1] and data["degraded"].tolist() == [True] * 4
    assert g.fault_log.degraded == [0, 1, 2, 3] and g.fault_log.counts == {("dead.y", "NaN"): 4}


def test_two_recorders_of_one_recording_log_each_fault_once(tmp_path):
    g = faulty_graph(tmp_path, rerun="save")
    g.add(Recorder("rec2", signals=["dev.x"], rerun="save", rrd_path=str(tmp_path / "faults.rrd"), flush_every=2))
    g.run(ticks=5)
    g.close()
    assert logged_faults(tmp_path / "faults.rrd") == [(2, ["tick 2: flaky.y: NaN (nan); replaced by 0"], ["WARN"])]
