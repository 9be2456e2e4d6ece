"""One run in this process: ended by its fall signal, a divergence or an error as an outcome, its
measures read at its last tick, nothing written by its recorder."""

from __future__ import annotations

import types
from pathlib import Path

import numpy as np
import pytest
from rising_graph import DT, FALL, expected

import dgraph as dg
from dgraph.sweep.outcome import Run, measure_parts, quiet_overrides, run_graph
from dgraph.sweep.outcome import _failure as failure


def rising_run(file: str, push: float, height: float = 0.45, kind: str = "jump", **kwargs) -> Run:
    settings = {"push.gain": push, "height.on_force": height, "fault.kind": kind}
    return Run(file, settings, kwargs.pop("duration", 1.0), FALL, **kwargs)


@pytest.mark.parametrize(("push", "height", "kind"), [(0.3, 0.45, "jump"), (1.1, 0.45, "jump"), (2.3, 0.95, "jump"),
                                                      (0.7, 0.45, "inf"), (2.3, 0.45, "inf")])
def test_a_run_ends_ok_fallen_or_diverged_at_the_tick_expected(rising, push, height, kind):
    outcome = run_graph(rising_run(rising, push, height, kind))
    status, fall_time, simulated = expected(push, height, kind)
    assert (outcome.status, outcome.fall_time) == (status, pytest.approx(fall_time) if fall_time else None)
    assert outcome.simulated_time == pytest.approx(simulated)
    assert outcome.survived == (status == "ok") and 0.0 < outcome.wall_time < 10.0
    assert ("contains inf" in outcome.message) == (status == "diverged")


def test_the_measures_are_the_final_values_a_component_or_a_norm(rising):
    measures = ("body.q[2]", "body.q", "body.v[0]", "height.in_contact", "push.output[7]")
    outcome = run_graph(rising_run(rising, 1.1, measures=measures))
    assert outcome.fall_time == pytest.approx(0.42)
    assert outcome.measures["body.q[2]"] == pytest.approx(1.1 * 0.42) == outcome.measures["body.q"]
    assert outcome.measures["body.v[0]"] == 0.0 and outcome.measures["height.in_contact"] == 1.0
    assert np.isnan(outcome.measures["push.output[7]"])  # no such component: no value, the run is not an error
    assert outcome.status == "fell"
    assert outcome.row()["body.q"] == outcome.measures["body.q"] and outcome.row()["push.gain"] == 1.1


def test_without_a_fall_signal_the_run_lasts_its_duration(rising):
    outcome = run_graph(Run(rising, {"push.gain": 2.3}, 0.5, None, ("body.q[2]",)))
    assert (outcome.status, outcome.simulated_time) == ("ok", 0.5)
    assert outcome.measures["body.q[2]"] == pytest.approx(2.3 * 0.5)


def test_recorders_write_nothing(rising):
    assert quiet_overrides(rising) == {"recorder.rerun": "off", "recorder.npz_path": None}
    run_graph(rising_run(rising, 0.3))
    assert not list(Path(rising).parent.glob("*.npz")) and not Path("recorded.npz").exists()
    dg.load(rising).close()  # as the file says, it would write one
    assert Path(rising).with_name("recorded.npz").exists() or Path("recorded.npz").exists()


def test_a_run_that_cannot_load_is_an_error_with_its_message(tmp_path):
    outcome = run_graph(Run(str(tmp_path / "missing.yaml"), {}, 1.0, None, ("body.q",)))
    assert outcome.status == "error" and "missing.yaml" in outcome.message and "\n" not in outcome.message
    assert "cannot read" in outcome.message and np.isnan(outcome.measures["body.q"])
    assert outcome.simulated_time == 0.0


def test_an_error_raised_on_the_fall_signal_is_a_fall_at_the_end_of_its_tick():
    graph = types.SimpleNamespace(t=41, dt=DT)
    run = Run("g.yaml", {}, 1.0, "device.fallen")
    fell = dg.DGraphError("device: the robot fell during tick 41", entity="device", signal="fallen")
    assert failure(fell, run, graph) == ("fell", pytest.approx(0.42), "DGraphError: device: the robot fell during "
                                                                      "tick 41")
    assert failure(dg.DivergenceError("MuJoCo simulation diverged at tick 3"), run, graph)[0] == "diverged"
    assert failure(dg.NonFiniteError("x.y: value contains NaN: array([nan])"), run, graph)[0] == "diverged"
    try:  # an output that failed on a NaN: the error it raised from says so
        try:
            raise dg.NonFiniteError("x.y: value contains NaN")
        except dg.NonFiniteError as nan:
            raise dg.ComputeError("x.z: computing failed") from nan
    except dg.ComputeError as wrapped:
        assert failure(wrapped, run, graph)[0] == "diverged"
    assert failure(dg.DGraphError("the word diverged in a message"), run, graph)[0] == "error"  # a type, not words
    assert failure(dg.ComputeError("the QP failed\nmore detail"), run, graph) == ("error", None,
                                                                                  "ComputeError: the QP failed")
    assert failure(ZeroDivisionError("division by zero"), run, graph)[0] == "error"


def test_a_measure_is_a_signal_or_one_of_its_components():
    assert measure_parts("body.q") == ("body.q", None) and measure_parts("body.q[12]") == ("body.q", 12)
    for bad in ("body.q[", "body.q[x]", "body.q[-1]"):
        with pytest.raises(ValueError, match="expected entity.signal"):
            measure_parts(bad)
