"""ConstraintRows: the rows of whole-body inverse dynamics over y = [a, f], against the dynamics
written out from the robot state and the contacts' own data."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.control import TaskEquation
from dgraph.control.inverse_dynamics import ConstraintRows
from tests.entities.talos_graph import CONTACTS, build
from tests.entities.test_inverse_dynamics import perturbed_state


@pytest.fixture(params=["corners", "wrench"])
def problem(request):
    q, v = perturbed_state(3)
    graph = build(q, v, contact_forces=request.param)
    state = graph["robot"].state(0)
    contacts = [graph[name].contact(0) for name in CONTACTS]
    limit = graph["robot"].pin_model.effortLimit[6:]
    rows = ConstraintRows(38, 6, limit, contacts)
    rows.write(state.mass_matrix, state.bias_forces, contacts)
    rows.write_torque_bounds(state.bias_forces)
    return state, contacts, limit, rows


def test_the_rows_are_the_dynamics_the_contacts_and_the_torque_limits(problem):
    state, contacts, limit, rows = problem
    rng = np.random.default_rng(4)
    y = rng.normal(size=rows.n)
    a, forces = y[:38], rows.forces(y)
    generalized = sum(c.jacobian.T @ (c.force_generator @ f) for c, f in zip(contacts, forces, strict=True))
    tau = state.mass_matrix[6:] @ a + state.bias_forces[6:] - generalized[6:]  # Eq. 2.4
    np.testing.assert_allclose(rows.torques(y, state.bias_forces), tau, atol=1e-9)
    dynamics = state.mass_matrix[:6] @ a + state.bias_forces[:6] - generalized[:6]  # the base is unactuated
    motion = [c.jacobian @ a - c.motion_rhs for c in contacts]
    np.testing.assert_allclose(rows.A @ y - rows.b, np.concatenate([dynamics, *motion]), atol=1e-9)
    friction = np.concatenate([c.friction_matrix @ f for c, f in zip(contacts, forces, strict=True)])
    np.testing.assert_allclose(rows.C @ y, np.concatenate([friction, tau - state.bias_forces[6:]]), atol=1e-9)
    np.testing.assert_allclose(rows.torque_lower, -limit - state.bias_forces[6:])
    np.testing.assert_allclose(rows.torque_upper, limit - state.bias_forces[6:])


def test_the_block_is_a_view_of_the_rows(problem):
    _, _, _, rows = problem
    block = rows.block(key="fixed")
    assert block.key == "fixed" and block.equality_matrix is rows.A and block.upper is rows.upper
    assert block.shape_problem(rows.n) is None


def test_a_task_equation_names_what_makes_it_unusable():
    good = TaskEquation(np.zeros((2, 38)), np.zeros(2), np.ones(2))
    assert good.problem(38) is None
    assert good.problem(37) == "task matrix has shape (2, 38), the robot has nv = 37"
    assert TaskEquation(np.zeros((2, 38)), np.zeros(3), np.ones(2)).problem(38).startswith("2 rows but a vector")
    assert TaskEquation(np.zeros((2, 38)), np.zeros(2), -np.ones(2)).problem(38).startswith("negative weights")
