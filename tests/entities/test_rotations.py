"""The Python-float rotation helpers of dgraph.entities.robot.rotations against numpy and Pinocchio
(the logarithm is tested with the contacts that use it, tests/entities/test_contact6d.py)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from dgraph.entities.robot.rotations import cross, matrix_to_quat, quat_to_matrix, quat_to_rows


def test_quaternion_helpers_round_trip():
    rng = np.random.default_rng(0)
    for _ in range(50):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        r = quat_to_matrix(quat)
        assert np.allclose(r, pin.Quaternion(quat).toRotationMatrix())
        back = matrix_to_quat(r)
        assert np.allclose(back, quat if quat[3] >= 0 else -quat)


def test_quaternion_of_a_matrix_in_every_branch_of_shepperds_method():
    # trace > 0, then the largest diagonal entry first, second, third (rotations by pi about x, y, z)
    for axis in (np.zeros(3), [np.pi, 0.0, 0.0], [0.0, np.pi, 0.0], [0.0, 0.0, np.pi]):
        r = pin.exp3(np.asarray(axis, dtype=float) + 0.1 * np.array([0.3, -0.2, 0.1]))
        quat = np.array(matrix_to_quat(r))
        assert quat[3] >= 0 and np.linalg.norm(quat) == pytest.approx(1.0, abs=1e-15)
        np.testing.assert_allclose(quat_to_matrix(quat), r, atol=1e-14)
        assert np.array_equal(matrix_to_quat(r.tolist()), matrix_to_quat(r))  # rows or an array


def test_rows_of_a_quaternion_normalise_it_and_cross_products_match_numpy():
    rng = np.random.default_rng(1)
    for _ in range(20):
        quat = rng.normal(size=4)
        np.testing.assert_allclose(quat_to_rows((3.0 * quat).tolist()), quat_to_matrix(quat), atol=1e-15)
        a, b = rng.normal(size=3), rng.normal(size=3)
        np.testing.assert_allclose(cross(a.tolist(), b.tolist()), np.cross(a, b), rtol=1e-15, atol=1e-15)
