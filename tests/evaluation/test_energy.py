"""Mechanical energy and cost of transport (Eq. 4.16) on synthetic series with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.evaluation import cost_of_transport, mechanical_energy, path_length


def test_a_joint_pushing_then_braking():
    """tau = 2 N m, omega = sin(2 pi t) over 1 s: |power| integrates to 2 * 2 / pi, the positive
    half to 2 / pi; a second joint with zero torque adds nothing."""
    dt = 1e-4
    t = np.arange(10_000) * dt
    torque = np.column_stack([np.full_like(t, 2.0), np.zeros_like(t)])
    velocity = np.column_stack([np.sin(2 * np.pi * t), np.ones_like(t)])
    total, positive = mechanical_energy(torque, velocity, dt)
    assert total == pytest.approx(4 / np.pi, rel=1e-6)
    assert positive == pytest.approx(2 / np.pi, rel=1e-6)


def test_cost_of_transport_of_the_thesis_table():
    """Table 4.8, TSID torque 20 cm: E_m = 521.8 J over D = 1.2 m with m = 100 kg -> 0.44."""
    assert cost_of_transport(521.8, 100.0, 1.2) == pytest.approx(0.443, abs=1e-3)
    with pytest.raises(ValueError):
        cost_of_transport(1.0, 100.0, 0.0)


def test_path_length_of_a_square_and_a_circle():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], dtype=float)
    assert path_length(square) == 4.0
    angle = np.linspace(0, 2 * np.pi, 10_001)
    assert path_length(np.column_stack([np.cos(angle), np.sin(angle)])) == pytest.approx(2 * np.pi, rel=1e-7)
