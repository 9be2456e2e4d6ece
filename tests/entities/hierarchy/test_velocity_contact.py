"""VelocityContact: J_c v = -kp e against the anchor, in the contact's local frame."""

from __future__ import annotations

import numpy as np
from talos_ik import build, half_sitting


def test_rows_correct_the_placement_error_against_the_anchor():
    g = build()
    foot = g["left_foot"]
    g.run(ticks=1)  # anchored at tick 0
    moved = half_sitting()
    moved[0] += 0.01  # the whole robot 1 cm forward: the foot is 1 cm from its anchor
    g["robot"].q.set(moved)
    g["robot"].v.set(np.zeros(38))
    t = g.t
    rows, contact = foot.rows(t), foot.contact(t)
    np.testing.assert_allclose(rows.equality_matrix, contact.jacobian)
    np.testing.assert_allclose(rows.equality_vector, -1000.0 * contact.error)
    assert abs(np.linalg.norm(contact.error[:3]) - 0.01) < 1e-9
    foot.deactivate()
    assert not foot.rows(t).active


def test_a_contact_at_zero_gain_is_the_plain_constraint():
    g = build()
    g["left_foot"].kp.set(0.0)
    np.testing.assert_array_equal(g["left_foot"].rows(0).equality_vector, np.zeros(6))
