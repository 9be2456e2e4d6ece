"""VelocityTask: the law J v = x_dot* - lambda e, the reference velocity from the feature, the adaptive gain."""

from __future__ import annotations

import numpy as np
import pytest
from talos_ik import build, half_sitting

import dgraph as dg
from dgraph.entities.hierarchy import VelocityTask
from dgraph.entities.hierarchy.adaptive_gain import adaptive_gain


def test_adaptive_gain_goes_from_l0_to_linf_with_the_given_slope():
    assert adaptive_gain(0.0, 10.0, 1.0, 5.0) == 10.0
    assert adaptive_gain(1e6, 10.0, 1.0, 5.0) == pytest.approx(1.0)
    h = 1e-7
    assert (adaptive_gain(h, 10.0, 1.0, 5.0) - 10.0) / h == pytest.approx(-5.0, rel=1e-5)
    assert adaptive_gain(3.0, 4.0, 4.0, 2.0) == 4.0  # l0 = linf: a constant


def test_rows_impose_the_first_order_law_with_the_reference_velocity_as_feed_forward():
    rng = np.random.default_rng(1)
    q = half_sitting()
    q[7:] += 0.05 * rng.normal(size=32)
    g = build(q)
    v = 0.3 * rng.normal(size=38)
    g["robot"].v.set(v)  # the feature reads this velocity: J v - e_dot must give back c_dot*
    feature, task = g["com_xy_feature"], g["com_xy"]
    feature.reference_velocity.set(np.array([0.2, -0.1, 0.0]))
    feature.reference_position.set(feature.reference_position(0) + np.array([0.01, 0.02, 0.0]))
    task.gain.set(np.array([3.0, 5.0]))
    rows, f = task.rows(0), feature.feature(0)
    np.testing.assert_allclose(rows.equality_matrix, f.jacobian)
    np.testing.assert_allclose(rows.equality_vector, np.array([0.2, -0.1]) - np.array([3.0, 5.0]) * f.error,
                               atol=1e-12)
    task.deactivate()
    assert not task.rows(0).active


def test_adaptive_task_uses_the_gain_of_the_error_norm():
    g = build()
    feature = g["com_xy_feature"]
    task = g.add(VelocityTask("adaptive_task", adaptive=True))
    g.plug("robot.state", "adaptive_task.robot")
    g.plug("com_xy_feature.feature", "adaptive_task.feature")
    task.gain_at_zero.set(8.0)
    task.gain_at_infinity.set(2.0)
    task.gain_slope.set(30.0)
    feature.reference_position.set(feature.reference_position(0) + np.array([0.03, 0.04, 0.0]))
    expected = adaptive_gain(0.05, 8.0, 2.0, 30.0)
    np.testing.assert_allclose(task.gain_value(0), [expected, expected], rtol=1e-9)
    task.gain_at_infinity.set(9.0)  # linf > l0: a relation of two constants, reported by the graph's check
    assert g.problems() == ["adaptive_task: the adaptive gain needs gain_at_zero >= gain_at_infinity, got 8.0 < 9.0"]
    with pytest.raises(dg.SpecError, match="adaptive_task"):  # and refused at the tick
        task.gain_value(0)
    with pytest.raises(dg.SpecError, match=r"adaptive_task\.gain_slope: must be >= 0"):
        task.gain_slope.set(-1.0)


def test_a_constant_gain_is_checked_against_the_rows_of_the_feature_where_it_is_set():
    g = build()
    task = g["com_xy"]
    with pytest.raises(dg.SpecError, match=r"com_xy\.gain: expected a scalar or 2 values, one per row of its feature "
                                           r"com_xy_feature\.feature, got 3 values"):
        task.gain.set([1.0, 2.0, 3.0])
    with pytest.raises(dg.SpecError, match=r"com_xy\.gain: must be >= 0"):
        task.gain.set(-1.0)
    g.unplug("com_xy.feature")
    task.gain.set([1.0, 2.0, 3.0])  # no feature plugged: its rows are not known yet
    g.plug("com_xy_feature.feature", "com_xy.feature")
    assert g.problems() == ["com_xy: input gain: expected a scalar or 2 values, one per row of its feature "
                            "com_xy_feature.feature, got 3 values"]


def test_a_wrong_feature_input_names_the_task():
    g = build()
    with pytest.raises(dg.SpecError, match=r"waist\.feature: expected a FeatureValue, got 3.0") as info:
        g["waist"].feature.set(3.0)
    assert (info.value.entity, info.value.signal) == ("waist", "feature")
