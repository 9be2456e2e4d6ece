"""Delay, Integrator and Sinusoid."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.discrete import Delay, Integrator
from dgraph.entities.references import Sinusoid
from tests.conftest import Ticker


def test_delay_outputs_the_previous_input(graph):
    dev = graph.add(Ticker("dev", x0=5.0))
    d = graph.add(Delay("d", initial=-1.0))
    graph.plug("dev.x", "d.input")
    seen = []
    for _ in range(4):
        seen.append((dev.x(graph.t), d.output(graph.t)))
        graph.step()
    assert seen == [(5.0, -1.0), (6.0, 5.0), (7.0, 6.0), (8.0, 7.0)]


def test_delay_initial_value_must_fit():
    with pytest.raises(dg.ParamError, match="does not fit size 3"):
        Delay("d", size=3, initial=[1.0, 2.0])


def test_integrator_forward_euler(graph):
    graph.add(Ticker("dev"))
    i = graph.add(Integrator("i", size=2, initial=[1.0, 0.0]))
    i.input.set([1.0, -2.0])
    graph.run(ticks=100)  # dt = 0.01 -> 1 s
    assert np.allclose(i.output.value, [2.0, -2.0])
    assert i.output.time == 100


def test_sinusoid_and_derivatives(graph):
    s = graph.add(Sinusoid("s", amplitude=[0.0, 0.05, 0.0], frequency=0.5, offset=[0.1, 0.0, 0.9]))
    t = 50  # 0.5 s at dt = 0.01
    w = 2 * np.pi * 0.5
    assert np.allclose(s.output(t), [0.1, 0.05 * np.sin(w * 0.5), 0.9])
    assert np.allclose(s.velocity(t), [0.0, 0.05 * w * np.cos(w * 0.5), 0.0])
    assert np.allclose(s.acceleration(t), [0.0, -0.05 * w**2 * np.sin(w * 0.5), 0.0])
    # finite differences agree with the analytic velocity
    fd = (s.output(t + 1) - s.output(t - 1)) / (2 * graph.dt)
    assert np.allclose(fd, s.velocity(t), atol=1e-5)
    scalar = graph.add(Sinusoid("x", amplitude=2.0, frequency=1.0, phase=np.pi / 2))
    assert scalar.output(0) == pytest.approx(2.0) and isinstance(scalar.output(0), float)


def test_sinusoid_fade_in_starts_at_rest_and_its_derivatives_are_exact():
    graph = dg.Graph(dt=0.001)
    s = graph.add(Sinusoid("s", amplitude=[0.0, 0.05, 0.0], frequency=0.5, offset=[0.0, 0.0, 0.9], ramp=1.0))
    assert np.allclose(s.output(0), [0.0, 0.0, 0.9]) and np.allclose(s.velocity(0), 0.0)
    assert np.allclose(s.acceleration(0), 0.0)
    for t in (300, 999, 1000, 1500):  # inside, at the end of, and after the fade-in
        h = 1e-3
        assert np.allclose((s.output(t + 1) - s.output(t - 1)) / (2 * h), s.velocity(t), atol=1e-6)
        assert np.allclose((s.velocity(t + 1) - s.velocity(t - 1)) / (2 * h), s.acceleration(t), atol=1e-4)
    plain = graph.add(Sinusoid("plain", amplitude=[0.0, 0.05, 0.0], frequency=0.5, offset=[0.0, 0.0, 0.9]))
    assert np.allclose(s.output(1200), plain.output(1200)) and not np.allclose(s.output(500), plain.output(500))


def test_sinusoid_with_a_frequency_and_a_phase_per_component():
    graph = dg.Graph(dt=0.001)
    s = graph.add(Sinusoid("s", amplitude=[0.1, 0.2], frequency=[0.5, 2.0], phase=[0.0, 1.0], offset=[1.0, 0.0],
                           ramp=0.5))
    w, phase = 2 * np.pi * np.array([0.5, 2.0]), np.array([0.0, 1.0])
    assert np.allclose(s.output(700), [1.0, 0.0] + np.array([0.1, 0.2]) * np.sin(w * 0.7 + phase), rtol=0, atol=1e-15)
    for t in (200, 700):  # inside and after the fade-in (truncation: h^2 / 6 times A w^3 ~ 7e-5, A w^4 ~ 1e-3)
        h = 1e-3
        assert np.allclose((s.output(t + 1) - s.output(t - 1)) / (2 * h), s.velocity(t), atol=2e-4)
        assert np.allclose((s.velocity(t + 1) - s.velocity(t - 1)) / (2 * h), s.acceleration(t), atol=3e-3)
    uniform = graph.add(Sinusoid("u", amplitude=[0.1, 0.2], frequency=[2.0, 2.0], phase=1.0, ramp=0.5))
    mixed = graph.add(Sinusoid("m", amplitude=[0.1, 0.2], frequency=[2.0, 2.0], phase=[1.0, 1.0 + 1e-12], ramp=0.5))
    for t in (200, 700):  # one sine for both components, or one each: the same waves
        for name in ("output", "velocity", "acceleration"):
            assert np.allclose(uniform.signal(name)(t), mixed.signal(name)(t), rtol=1e-10, atol=1e-12)
