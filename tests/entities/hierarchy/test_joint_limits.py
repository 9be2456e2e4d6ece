"""JointLimits: velocity bounds from position and velocity limits; the IK never leaves the joint range."""

from __future__ import annotations

import numpy as np
from talos_ik import build, half_sitting

from dgraph.entities.robot import load_model


def test_bounds_are_the_position_limits_over_dt_clipped_by_the_velocity_limits():
    model = load_model("talos")
    q = half_sitting()
    j = 3  # leg_left_4 (knee): q index 7 + 3, v index 6 + 3
    q[7 + j] = model.upperPositionLimit[7 + j] - 1e-4  # 0.1 rad/s of room at dt = 1 ms
    g = build(q)
    rows = g["limits"].rows(0)
    assert rows.inequality_matrix.shape == (32, 38)
    assert abs(rows.upper[j] - 0.1) < 1e-9
    assert rows.lower[j] == -model.velocityLimit[6 + j]  # far from the lower limit: the velocity limit
    beyond = q.copy()
    beyond[7 + j] = model.upperPositionLimit[7 + j] + 1.0  # outside: back at most at v_max, bounds ordered
    rows = build(beyond)["limits"].rows(0)
    assert rows.lower[j] == rows.upper[j] == -model.velocityLimit[6 + j]


def test_a_posture_beyond_the_limits_is_followed_only_up_to_them():
    g = build()
    model = g["robot"].pin_model
    reference = model.upperPositionLimit[7:] + 0.5  # every joint asked past its upper limit
    g["posture_feature"].reference.set(reference)
    g.run(ticks=300)
    q = g["device"].q.value
    assert (q[7:] <= model.upperPositionLimit[7:] + 1e-8).all()
    assert (np.abs(g["device"].v.value[6:]) <= model.velocityLimit[6:] + 1e-8).all()
    assert g["solver"].solution.value.status == 0
