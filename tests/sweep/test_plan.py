"""The runs checked before any starts: a bad file, key, value, measure or fall signal stops the
sweep with a clear error; each file's duration and fall signal resolved."""

from __future__ import annotations

from pathlib import Path

import pytest
from rising_graph import FALL

from dgraph.sweep.outcome import Run
from dgraph.sweep.plan import planned_runs
from dgraph.sweep.spec import Bisection, Sweep, SweepError

ROOT = Path(__file__).resolve().parents[2]


def test_the_runs_of_a_grid_carry_the_files_duration_and_fall_signal(rising):
    runs = planned_runs(Sweep([rising], settings={"height.on_force": 0.95}, grid={"push.gain": [0.3, 2.3]},
                              fall_signal=FALL, measures=["body.q[2]"]))
    assert runs == [Run(rising, {"height.on_force": 0.95, "push.gain": gain}, 1.0, FALL, ("body.q[2]",))
                    for gain in (0.3, 2.3)]
    assert planned_runs(Sweep([rising], duration=0.25))[0].duration == 0.25
    assert planned_runs(Sweep([rising]))[0].fall_signal is None  # auto: the graph has no device.fallen


def test_the_default_fall_signal_of_a_talos_graph_is_device_fallen():
    run, = planned_runs(Sweep([str(ROOT / "graphs" / "talos_standing.yaml")]))
    assert (run.fall_signal, run.duration) == ("device.fallen", 10.0)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"grid": {"push.gian": [1.0]}}, r"push.gian=1.0: .*no signal 'gian'.*did you mean 'gain'"),
    ({"grid": {"fault.kind": ["jump", "bogus"]}}, r"fault.kind='?bogus'?: .*jump"),
    ({"settings": {"hieght.on_force": 1.0}}, "no entity 'hieght'.*did you mean 'height'"),
    ({"bisection": Bisection("height.off_force", 0.0, 1.0)}, "height.off_force=1.0: .*off_force must be below"),
    ({"measures": ["body.w"]}, "--measure body.w: .*no signal"),
    ({"measures": ["body.q[3]"]}, r"--measure body.q\[3\]: body.q has 3 component"),
    ({"measures": ["body.q[x]"]}, "--measure .*expected entity.signal"),
    ({"fall_signal": "body.q"}, "--fall-signal body.q: expected a bool scalar signal"),
    ({"fall_signal": "body.fallen"}, "--fall-signal body.fallen"),
])
def test_a_run_that_cannot_be_made_stops_the_sweep_before_it_starts(rising, kwargs, message):
    with pytest.raises(SweepError, match=message):
        planned_runs(Sweep([rising], **kwargs))


def test_a_missing_file_or_length_is_refused(rising, tmp_path):
    with pytest.raises(SweepError, match="missing.yaml"):
        planned_runs(Sweep([rising, str(tmp_path / "missing.yaml")]))
    endless = tmp_path / "endless.yaml"
    endless.write_text(Path(rising).read_text().replace("duration: 1.0\n", ""))
    with pytest.raises(SweepError, match="no run length"):
        planned_runs(Sweep([str(endless)]))
    assert planned_runs(Sweep([str(endless)], duration=2.0))[0].duration == 2.0
