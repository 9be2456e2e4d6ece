"""KinematicDevice: vector state and free-flyer base through pinocchio.integrate."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.devices import KinematicDevice


def test_velocity_control_vector_state():
    g = dg.Graph(dt=0.001)
    dev = g.add(KinematicDevice("dev", size=3, q0=[0.0, 1.0, 2.0]))
    dev.control.set([1.0, 0.0, -1.0])
    g.run(ticks=1000)
    assert np.allclose(dev.q.value, [1.0, 1.0, 1.0]) and np.allclose(dev.v.value, [1.0, 0.0, -1.0])


def test_acceleration_control_is_semi_implicit_euler():
    g = dg.Graph(dt=0.01)
    dev = g.add(KinematicDevice("dev", size=1, control_mode="acceleration"))
    dev.control.set([2.0])
    n = 100
    g.run(ticks=n)
    assert dev.v.value[0] == pytest.approx(2.0 * n * 0.01)
    assert dev.q.value[0] == pytest.approx(2.0 * 0.01**2 * n * (n + 1) / 2)


def test_free_flyer_integrates_on_se3():
    model = pin.buildSampleModelHumanoidRandom()
    g = dg.Graph(dt=0.001)
    dev = g.add(KinematicDevice("dev", model=model))
    assert dev.q.spec.shape == (model.nq,) and dev.control.spec.shape == (model.nv,)
    v = np.zeros(model.nv)
    v[:6] = [0.1, 0.0, 0.0, 0.0, 0.0, 1.0]  # constant body twist: forward while turning
    v[6:] = 0.3
    dev.control.set(v)
    g.run(ticks=1000)
    expected = pin.integrate(model, pin.neutral(model), v * 1.0)
    assert np.allclose(dev.q.value, expected, atol=1e-9)
    assert np.linalg.norm(dev.q.value[3:7]) == pytest.approx(1.0)


def test_talos_by_name_from_example_robot_data():
    dev = KinematicDevice("talos", model="talos")
    assert (dev.nq, dev.nv) == (39, 38)


def test_needs_size_or_model():
    with pytest.raises(dg.ParamError, match="size or a model"):
        KinematicDevice("dev")
    with pytest.raises(dg.ParamError, match="robot name or a pinocchio.Model"):
        KinematicDevice("dev", model=3)
