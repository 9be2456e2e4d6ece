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


def test_default_is_an_rrd_file_named_after_the_graph(tmp_path):
    g = dg.Graph(name="defaults")
    g.add(Ticker("dev"))
    g.add(Recorder("rec", signals=["dev.x"]))
    g.run(ticks=3)
    g.close()
    assert (tmp_path / "out" / "defaults.rrd").stat().st_size > 0  # the test runs in tmp_path
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
    rec = g.add(Recorder("rec", signals=["dev.x", "a.y"]))
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
