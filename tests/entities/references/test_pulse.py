"""Pulse: the window in ticks, the value inside it, zeros outside, the impulse, the parameters refused."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.references import Pulse
from dgraph.files import loads
from tests.conftest import Ticker

WRENCH_X = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]


def pulse_graph(dt: float = 0.001, **params) -> Pulse:
    """A pulse in a graph of period ``dt`` (its default ``dt``)."""
    g = dg.Graph(dt=dt)
    g.add(Ticker("dev"))
    return g.add(Pulse("push", **params))


def test_the_pulse_is_on_for_exactly_its_ticks_and_zero_around_them():
    push = pulse_graph(direction=[0.0, 1.0, 0.0, 0.0, 0.0, 0.5], magnitude=40.0, start=1.0, duration=0.3)
    values = np.array([push.value(t) for t in range(1500)])
    on = np.flatnonzero(values.any(axis=1))
    assert push.window == (1000, 1300) and on[0] == 1000 and on[-1] == 1299 and len(on) == 300
    assert np.array_equal(values[1000], [0.0, 40.0, 0.0, 0.0, 0.0, 20.0])
    assert (values[on] == values[1000]).all() and not values[:1000].any() and not values[1300:].any()


def test_the_direction_is_not_normalised_and_the_impulse_is_magnitude_direction_duration():
    push = pulse_graph(dt=0.002, direction=[1.0, 1.0, 0.0], magnitude=10.0, start=0.5, duration=0.3)
    impulse = sum(push.value(t) for t in range(1000)) * 0.002
    assert np.allclose(impulse, [3.0, 3.0, 0.0], rtol=0, atol=1e-12)
    assert np.array_equal(push.value(250), [10.0, 10.0, 0.0])


def test_start_and_duration_round_to_the_nearest_tick_of_its_own_dt():
    push = Pulse("push", direction=WRENCH_X, magnitude=1.0, start=0.0104, duration=0.0206, dt=0.002)
    assert push.window == (5, 15)
    assert push.value(4)[0] == 0.0 and push.value(5)[0] == 1.0 and push.value(14)[0] == 1.0
    assert push.value(15)[0] == 0.0


def test_a_scalar_pulse_is_a_float_and_a_zero_duration_never_fires():
    push = pulse_graph(direction=2.0, magnitude=-3.0, start=0.0, duration=0.002)
    assert push.value(0) == -6.0 and isinstance(push.value(1), float) and push.value(2) == 0.0
    silent = pulse_graph(direction=WRENCH_X, magnitude=5.0, start=0.0, duration=0.0)
    assert not any(silent.value(t).any() for t in range(10))


def test_the_output_cannot_be_changed_by_a_reader():
    push = pulse_graph(direction=WRENCH_X, magnitude=5.0, start=0.0, duration=0.01)
    with pytest.raises(ValueError, match="read-only"):
        push.value(0)[0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        push.value(20)[0] = 1.0


@pytest.mark.parametrize(("params", "match"), [
    ({"magnitude": float("inf")}, "finite"),
    ({"direction": [1.0, float("inf")]}, "finite"),
    ({"start": -0.1}, "start"),
    ({"duration": -0.3}, "duration"),
])
def test_non_finite_values_and_negative_times_are_refused(params, match):
    given = {"direction": WRENCH_X, "magnitude": 1.0, "start": 0.0, "duration": 0.3, **params}
    with pytest.raises(dg.ParamError, match=match):
        Pulse("push", **given)


def test_a_graph_file_plugs_the_pulse_into_a_device_input():
    g = loads("""\
name: pulse_into_an_input
dt: 0.01
entities:
  push: {type: Pulse, params: {direction: [0.0, 0.0, -1.0], magnitude: 9.81, start: 0.05, duration: 0.02}}
  sink: {type: Gain, params: {size: 3}}
plugs:
  - push.value -> sink.input
set:
  sink.gain: 2.0
""")
    assert np.allclose(g["sink.output"](5), [0.0, 0.0, -19.62]) and not g["sink.output"](7).any()
