"""The MPTC QP: the weighting W = Lambda^-1 Psi makes the task-force errors do no net work
(sum_k psi_k J_k^T f~_k = 0 at the unconstrained optimum), on random over-determined stacks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dgraph.control.contact import ContactConstraint
from dgraph.control.feature import FeatureValue
from dgraph.control.mptc import Dynamics, MptcQP, generalized_force_map, task_force, weighted_force_residual
from dgraph.control.proxqp import INFINITY, WarmStartedQP
from dgraph.control.status import PRIMAL_INFEASIBLE, SOLVED

UNBOUNDED = INFINITY


def random_dynamics(rng: np.random.Generator, nv: int) -> Dynamics:
    """A random robot: M symmetric positive definite and well conditioned, any C and g."""
    root = rng.normal(size=(nv, nv))
    mass = root @ root.T / nv + np.eye(nv)
    coriolis, gravity, velocity = rng.normal(size=(nv, nv)), rng.normal(size=nv), rng.normal(size=nv)
    return Dynamics(np.linalg.inv(mass), coriolis, coriolis @ velocity + gravity, velocity)


def random_feature(rng: np.random.Generator, rows: int, nv: int) -> FeatureValue:
    return FeatureValue(rng.normal(size=rows), rng.normal(size=rows), rng.normal(size=(rows, nv)),
                        rng.normal(size=rows), rng.normal(size=rows))


def free_contact(rng: np.random.Generator, nv: int) -> ContactConstraint:
    """A contact with a 6D wrench and bounds that never bind; its Jacobian's floating-base block
    is well conditioned, as a body's (an adjoint map) is."""
    jacobian = 0.5 * rng.normal(size=(6, nv))
    jacobian[:, :6] += 2.0 * np.eye(6)
    return ContactConstraint("contact", True, jacobian, np.zeros(6), np.eye(6), np.eye(6),
                             -UNBOUNDED * np.ones(6), UNBOUNDED * np.ones(6), 0.0, np.eye(3), np.zeros(6))


def random_stack(seed: int, nv: int, task_rows: list[int], n_unactuated: int, n_contacts: int):
    rng = np.random.default_rng(seed)
    dynamics = random_dynamics(rng, nv)
    tasks = [task_force(random_feature(rng, rows, nv), rng.uniform(1, 100, rows), rng.uniform(1, 20, rows),
                        float(rng.uniform(0.1, 10)), dynamics, rng.normal(size=(rows, nv))) for rows in task_rows]
    contacts = [free_contact(rng, nv) for _ in range(n_contacts)]
    qp = MptcQP(nv, n_unactuated, UNBOUNDED * np.ones(nv - n_unactuated), eps_abs=1e-10, max_iterations=10_000,
                regularisation=0.0)
    return dynamics, tasks, contacts, qp


def over_determined(nv: int, rows: list[int], seed: int) -> tuple[int, list[int], int]:
    """``rows`` with 6-row tasks added until the tasks have more rows than the QP has variables
    (``nv`` both ways: ``nv`` torques on a fixed base, ``nv - 6`` and one contact's 6 forces on a
    floating one)."""
    while sum(rows) <= nv:
        rows = [*rows, 6]
    return nv, rows, seed


STACKS = st.builds(over_determined, st.integers(8, 14), st.lists(st.integers(1, 6), min_size=2, max_size=5),
                   st.integers(0, 2**32 - 1))
"""nv, the rows of 2 or more tasks (over-determined), a seed."""


def unconstrained_optimum(dynamics, tasks, contacts, qp) -> tuple[np.ndarray, list[np.ndarray]]:
    """``u`` minimising the MPTC cost of ``qp.problem`` exactly (its normal equations), and the
    task-force errors there."""
    (hessian, gradient, *_), actuation = qp.problem(dynamics, tasks, contacts, rigid_contacts=False)
    u = np.linalg.solve(hessian, -gradient)
    return u, [task.desired_force - task.force(actuation @ u) for task in tasks]


@pytest.mark.parametrize("floating", [False, True], ids=["fixed base", "floating base"])
@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_force_errors_do_no_net_work_at_the_unconstrained_optimum(floating: bool, data: st.DataObject):
    nv, rows, seed = data.draw(STACKS)
    n_unactuated, n_contacts = (6, 1) if floating else (0, 0)
    dynamics, tasks, contacts, qp = random_stack(seed, nv, rows, n_unactuated, n_contacts)
    _, errors = unconstrained_optimum(dynamics, tasks, contacts, qp)
    residual = weighted_force_residual(tasks, errors)
    scale = max(np.linalg.norm(task.weight * task.jacobian.T @ task.desired_force) for task in tasks)
    assert np.linalg.norm(residual) <= 1e-9 * max(scale, 1.0)
    # over-determined: the errors themselves are not zero, only their weighted work
    assert max(np.linalg.norm(error) for error in errors) > 1e-6


@pytest.mark.parametrize("floating", [False, True], ids=["fixed base", "floating base"])
@pytest.mark.parametrize("seed", range(5))
def test_proxqp_lands_on_the_unconstrained_optimum(floating: bool, seed: int):
    n_unactuated, n_contacts = (6, 1) if floating else (0, 0)
    dynamics, tasks, contacts, qp = random_stack(seed, 12, [6, 6, 3, 4], n_unactuated, n_contacts)
    solution = qp.solve(dynamics, tasks, contacts, tick=None, rigid_contacts=False)
    assert solution.status == SOLVED
    optimum, _ = unconstrained_optimum(dynamics, tasks, contacts, qp)
    np.testing.assert_allclose(np.concatenate([solution.tau, *solution.forces]), optimum, atol=1e-6)
    assert np.linalg.norm(weighted_force_residual(tasks, solution.force_errors)) < 1e-6


def test_a_naive_weighting_leaves_the_errors_doing_work():
    """With W = Psi (the task inertias left out) the same stack does not balance: the identity is
    the weighting's doing, not a property of any least squares."""
    dynamics, tasks, contacts, qp = random_stack(3, 10, [6, 6, 3, 4], 0, 0)
    # the cost sum_k psi_k/2 ||f_k,des - f_k||^2, without the task inertias' inverses
    actuation = generalized_force_map(0, 10, [])
    maps = [task.inertia @ task.jacobian @ dynamics.inverse_mass_matrix @ actuation for task in tasks]
    hessian = sum(task.weight * m.T @ m for task, m in zip(tasks, maps, strict=True))
    gradient = -sum(task.weight * m.T @ task.desired_force for task, m in zip(tasks, maps, strict=True))
    u = np.linalg.solve(hessian, -gradient)
    errors = [task.desired_force - m @ u for task, m in zip(tasks, maps, strict=True)]
    assert np.linalg.norm(weighted_force_residual(tasks, errors)) > 1e-3
    _, weighted_errors = unconstrained_optimum(dynamics, tasks, contacts, qp)
    assert np.linalg.norm(weighted_force_residual(tasks, weighted_errors)) < 1e-9


def test_rigid_contacts_give_the_accelerations_they_ask_for():
    rng = np.random.default_rng(5)
    nv = 12
    dynamics = random_dynamics(rng, nv)
    tasks = [task_force(random_feature(rng, rows, nv), np.full(rows, 25.0), np.full(rows, 10.0), 1.0, dynamics,
                        np.zeros((rows, nv))) for rows in (3, 6, 6)]
    contact = free_contact(rng, nv)
    contact.motion_rhs = rng.normal(size=6)
    qp = MptcQP(nv, 6, UNBOUNDED * np.ones(nv - 6), eps_abs=1e-10, max_iterations=10_000)
    solution = qp.solve(dynamics, tasks, [contact], tick=None)
    assert solution.status == SOLVED
    np.testing.assert_allclose(contact.jacobian @ solution.acceleration, contact.motion_rhs, atol=1e-7)


def test_torque_limits_and_friction_bind_and_the_residual_says_so():
    dynamics, tasks, contacts, _ = random_stack(11, 10, [6, 6, 3], 6, 1)
    free = MptcQP(10, 6, UNBOUNDED * np.ones(4), eps_abs=1e-10, max_iterations=10_000, regularisation=0.0)
    unbounded = free.solve(dynamics, tasks, contacts, tick=None, rigid_contacts=False)
    limit = 0.5 * np.abs(unbounded.tau).max()
    limited = MptcQP(10, 6, np.full(4, limit), eps_abs=1e-10, max_iterations=10_000, regularisation=0.0)
    solution = limited.solve(dynamics, tasks, contacts, tick=None, rigid_contacts=False)
    assert solution.status == SOLVED
    assert np.abs(solution.tau).max() <= limit + 1e-8
    assert np.abs(solution.tau).max() >= limit - 1e-6  # a limit binds
    assert np.linalg.norm(weighted_force_residual(tasks, solution.force_errors)) > 1e-3


def test_non_finite_data_is_a_failed_solve_not_an_exception():
    dynamics, tasks, contacts, qp = random_stack(2, 9, [6, 6], 0, 0)
    tasks[0].desired_force[0] = np.nan
    solution = qp.solve(dynamics, tasks, contacts, tick=None)
    assert solution.status != SOLVED and solution.tau is None and not solution.force_errors


def test_a_failed_warm_started_solve_is_retried_fresh(monkeypatch):
    """ProxQP, warm-started, has called feasible MPTC problems infeasible: a fresh solve with a
    stronger regularisation answers instead, and the solution says it was retried."""
    dynamics, tasks, contacts, qp = random_stack(4, 12, [6, 6, 3, 4], 6, 1)
    reference = qp.solve(dynamics, tasks, contacts, tick=0)
    assert reference.status == SOLVED and not reference.retried
    monkeypatch.setattr(WarmStartedQP, "solve", lambda self, problem, tick, start=None: (PRIMAL_INFEASIBLE, 7))
    retried = qp.solve(dynamics, tasks, contacts, tick=1)
    assert retried.status == SOLVED and retried.retried and retried.iterations > 7
    np.testing.assert_allclose(retried.tau, reference.tau, rtol=1e-3, atol=1e-3)
