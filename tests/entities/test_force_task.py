"""ForceTask: PI+ force law, forward-Euler integral, anti-windup, reset while inactive, gains."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.operators import Constant
from dgraph.entities.references import Sinusoid
from dgraph.entities.tasks import ForceTask

DT = 0.01


def task_graph(**params):
    g = dg.Graph(dt=DT, name="force_task_test")
    task = g.add(ForceTask("ft", **params))
    return g, task


def test_output_is_reference_plus_p_error_plus_i_forward_euler_integral():
    g, task = task_graph(integral_limit=1e6)
    reference = np.array([1.0, -2.0, 10.0])
    task.reference.set(reference)
    g.add(Sinusoid("measured", amplitude=[3.0, 1.0, 4.0], frequency=0.7, offset=[0.0, 0.0, 5.0]))
    g.plug("measured.output", "ft.measured")
    p, i = np.array([0.5, 1.0, 2.0]), 4.0
    task.p_gain.set(p)
    task.i_gain.set(i)
    integral = np.zeros(3)
    for t in range(200):
        error = reference - g["measured"].output(t)
        np.testing.assert_allclose(task.error(t), error, atol=1e-12)
        np.testing.assert_allclose(task.integral.value, integral, atol=1e-12)
        np.testing.assert_allclose(task.force(t), reference + p * error + i * integral, atol=1e-12)
        integral = integral + DT * error  # forward Euler: e(t) enters the integral at t + 1
        g.step()
    assert np.abs(integral).max() > 1.0  # the integral term matters in this test


def test_anti_windup_clamps_the_integral_term_per_axis():
    g, task = task_graph(integral_limit=20.0)
    task.reference.set([30.0, -30.0, 30.0])
    task.measured.set(np.zeros(3))
    task.p_gain.set(0.0)
    task.i_gain.set([5.0, 2.0, 0.0])
    g.run(ticks=50)  # 0.5 s at e = 30 N: 15 N s unclamped
    # axis 0: 5 * 15 = 75 > 20, clamped at 20 / 5; axis 1: 2 * 15 = 30 > 20, clamped at -20 / 2 (negative
    # error); axis 2: no integral gain, no limit (the term stays 0)
    np.testing.assert_allclose(task.integral.value, [4.0, -10.0, 15.0], atol=1e-9)
    np.testing.assert_allclose(task.force(g.t), [30.0 + 20.0, -30.0 - 20.0, 30.0], atol=1e-9)
    # the clamp does not hold the integral once the error reverses: it unwinds from the limit at once
    task.measured.set([40.0, -40.0, 40.0])  # e = -10, +10, -10
    g.step()
    np.testing.assert_allclose(task.integral.value, [4.0 - 0.1, -10.0 + 0.1, 15.0 - 0.1], atol=1e-9)


def test_the_clamp_follows_the_integral_gain_when_it_changes():
    g, task = task_graph(integral_limit=20.0)
    task.reference.set([30.0, 0.0, 0.0])
    task.measured.set(np.zeros(3))
    task.i_gain.set(5.0)
    g.run(ticks=50)
    assert task.integral.value[0] == pytest.approx(4.0)
    task.i_gain.set(10.0)
    g.step()
    assert task.integral.value[0] == pytest.approx(2.0)
    assert abs(10.0 * task.integral.value[0]) <= 20.0 + 1e-9


def test_inactive_resets_the_integral_and_outputs_the_reference():
    g, task = task_graph()
    task.reference.set([0.0, 0.0, 10.0])
    task.measured.set([0.0, 0.0, 4.0])
    task.p_gain.set(1.0)
    task.i_gain.set(1.0)
    g.run(ticks=10)
    np.testing.assert_allclose(task.integral.value, [0.0, 0.0, 0.6], atol=1e-12)
    task.active.set(False)
    np.testing.assert_array_equal(task.force(g.t), [0.0, 0.0, 10.0])
    g.step()
    np.testing.assert_array_equal(task.integral.value, np.zeros(3))
    g.run(ticks=5)
    np.testing.assert_array_equal(task.integral.value, np.zeros(3))
    task.active.set(True)
    np.testing.assert_allclose(task.force(g.t), [0.0, 0.0, 16.0])  # P only: the integral restarts at 0
    g.step()
    np.testing.assert_allclose(task.integral.value, [0.0, 0.0, 0.06], atol=1e-12)


def test_wrench_size_and_vector_gains():
    g, task = task_graph(size=6, integral_limit=100.0)
    task.reference.set(np.arange(6.0))
    task.measured.set(np.zeros(6))
    task.p_gain.set([1.0, 0.0, 2.0, 0.0, 0.5, 0.0])
    np.testing.assert_allclose(task.force(0), np.arange(6.0) * [2.0, 1.0, 3.0, 1.0, 1.5, 1.0])
    with pytest.raises(dg.SpecError, match=r"ft\.p_gain: expected a scalar or 6 values, one per axis of the force, "
                                           r"got 3 values"):
        task.p_gain.set([1.0, 2.0, 3.0])  # 3 gains for a wrench, refused where they are set
    g.add(Constant("three", value=[1.0, 2.0, 3.0]))
    g.plug("three.output", "ft.p_gain")  # through a plug: checked at each tick
    with pytest.raises(dg.SpecError, match=r"ft\.p_gain at tick 0: expected a scalar or 6 values"):
        task.force(0)


@pytest.mark.parametrize("gain", ["p_gain", "i_gain"])
def test_a_negative_gain_names_the_entity_and_signal(gain):
    g, task = task_graph()
    task.reference.set(np.zeros(3))
    task.measured.set(np.zeros(3))
    with pytest.raises(dg.SpecError, match=rf"ft\.{gain}: must be >= 0") as info:
        getattr(task, gain).set([1.0, -0.1, 1.0])  # a constant: where it is set
    assert info.value.entity == "ft" and info.value.signal == gain
    g.add(Constant("negative", value=[1.0, -0.1, 1.0]))
    g.plug("negative.output", f"ft.{gain}")  # through a plug: at the tick
    with pytest.raises(dg.SpecError, match=rf"ft\.{gain} must be >= 0") as info:
        g.step() if gain == "i_gain" else task.force(0)
    assert info.value.entity == "ft" and info.value.signal == gain
    assert g.t == 0


def test_parameters_are_checked():
    with pytest.raises(dg.ParamError):
        ForceTask("ft", size=7)
    with pytest.raises(dg.ParamError):
        ForceTask("ft", integral_limit=-1.0)


def test_an_inactive_task_needs_no_measurement():
    """While inactive the force is the reference alone: the measured force (read only while
    active, on demand) is not computed, and may be unplugged."""
    _, task = task_graph()
    task.reference.set(np.array([0.0, 0.0, 10.0]))
    task.active.set(False)
    assert task.force(0).tolist() == [0.0, 0.0, 10.0] and task.error.count == 0
