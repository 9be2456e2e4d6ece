"""MptcSolver on TALOS at a fixed state: the answer holds the robot on its feet, the passivity
signals are what their definitions say, and bad tasks or data are named, never crashes."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.control.status import SOLVED
from dgraph.entities.features import AngularMomentum
from dgraph.entities.solvers import MptcSolver
from dgraph.entities.tasks import Task
from tests.entities.talos_graph import TASKS, build, half_sitting

GRAVITY = 9.81


def mptc_graph(q: np.ndarray | None = None, v: np.ndarray | None = None, **params) -> dg.Graph:
    g = build(q, v, solver_type=MptcSolver, **params)
    for name in TASKS:  # psi_k: one importance per task
        g[name].weight.set(1.0)
    return g


def test_standing_still_the_feet_carry_the_weight_and_the_tasks_store_nothing():
    g = mptc_graph()
    solver = g["solver"]
    with g:
        assert solver.status(0) == SOLVED
        mass = g["robot"].state(0).total_mass
        assert solver.normal_force_total(0) == pytest.approx(mass * GRAVITY, rel=1e-3)
        for foot in ("left_foot", "right_foot"):  # rigid feet, at rest
            contact = g[foot].contact(0)
            np.testing.assert_allclose(contact.jacobian @ solver.acceleration(0), contact.motion_rhs, atol=1e-5)
        np.testing.assert_allclose(solver.acceleration(0), 0.0, atol=2e-3)  # ProxQP's tolerance: no motion
        np.testing.assert_allclose(solver.task_storage(0), 0.0, atol=1e-12)  # references met, at rest
        assert solver.residual_power(0) == pytest.approx(0.0, abs=1e-12)   # q_dot = 0


def test_storage_and_port_power_follow_their_definitions():
    q, v = half_sitting(), np.zeros(38)
    q[7 + 3] += 0.2  # a knee away from the posture reference
    v[6 + 3] = 0.5   # and moving
    g = mptc_graph(q, v)
    solver = g["solver"]
    with g:
        solution = solver.solution(0)
        posture = TASKS.index("posture_task")
        task = solution.tasks[solution.task_rows.index(posture)]
        error = solution.force_errors[solution.task_rows.index(posture)]
        rate, position = task.velocity_error, task.position_error
        assert position[3] == pytest.approx(-0.2) and rate[3] == pytest.approx(-0.5)
        expected = 0.5 * rate @ task.inertia @ rate + 0.5 * position @ task.stiffness @ position
        assert solver.task_storage(0)[posture] == pytest.approx(expected, rel=1e-12)
        assert solver.task_port_power(0)[posture] == pytest.approx(rate @ error, rel=1e-12)
        assert solver.task_storage_rate(0)[posture] == pytest.approx(-rate @ task.damping @ rate + rate @ error,
                                                                     rel=1e-12)
        assert solver.weighted_storage(0) == pytest.approx(sum(solver.task_storage(0)), rel=1e-12)  # psi = 1
        residual = sum(t.weight * t.jacobian.T @ e for t, e in zip(solution.tasks, solution.force_errors, strict=True))
        np.testing.assert_allclose(solver.weighted_force_residual(0), residual)
        assert solver.residual_power(0) == pytest.approx(-v @ residual)


def test_a_task_of_weight_zero_is_left_out():
    g = mptc_graph()
    g["waist_task"].weight.set(0.0)
    with g:
        solution = g["solver"].solution(0)
        assert solution.task_rows == [TASKS.index("com_task"), TASKS.index("posture_task")]
        assert g["solver"].task_storage(0)[TASKS.index("waist_task")] == 0.0


def test_per_row_weights_are_refused_naming_the_task():
    g = mptc_graph()
    g["com_task"].weight.set([1.0, 1.0, 2.0])
    with g, pytest.raises(dg.SpecError, match=r"solver\.com_task at tick 0: MPTC weights a task by one psi"):
        g["solver"].tau(0)


def test_a_rate_feature_is_refused_naming_the_task():
    g = build(solver_type=MptcSolver)
    g.add(AngularMomentum("momentum"))
    g.plug("robot.state", "momentum.robot")
    g.add(Task("momentum_task"))
    g.plug("momentum.feature", "momentum_task.feature")
    g.plug("momentum_task.equation", "solver.com_task")
    with g, pytest.raises(dg.SpecError, match=r"solver\.com_task at tick 0: its feature is a rate"):
        g["solver"].tau(0)


def test_a_failed_solve_falls_back_on_gravity_compensation_and_says_so():
    """Tick 1 asks the left sole to jump back to its anchor with an absurd stiffness: no torque
    within the limits gives that acceleration (primal infeasible), so ``tau`` is the fallback
    ``g_j(q) - d v_j`` on the tick's state, the passivity signals are zeros, and the fault names it."""
    g = mptc_graph()
    solver = g["solver"]
    assert solver.status(0) == SOLVED
    g.step()
    q = half_sitting()
    q[0] += 0.05
    g["robot"].q.set(q)
    g["left_foot"].kp.set(1e9)
    assert solver.status(1) != SOLVED
    model = g["robot"].pin_model
    gravity = pin.computeGeneralizedGravity(model, model.createData(), q)[6:]
    np.testing.assert_allclose(solver.tau(1), np.clip(gravity, -model.effortLimit[6:], model.effortLimit[6:]),
                               atol=1e-9)
    np.testing.assert_allclose(solver.task_storage(1), 0.0)
    np.testing.assert_allclose(solver.weighted_force_residual(1), 0.0)
    [fault] = g.fault_log.staged(1)
    assert fault.signal == "solver.tau" and fault.action == "fallback torque g(q) - d v on the state at this tick"


def test_a_tick_solved_again_gives_the_same_answer():
    """With the cache off every read solves again: the task Coriolis matrix, which takes J_dot_k
    from the previous tick's Jacobian, must not take this tick's own for it the second time."""
    g = mptc_graph()
    g.cache_enabled = False
    solver = g["solver"]
    assert solver.status(0) == SOLVED
    g.step()
    q, v = half_sitting(), np.zeros(38)
    q[7:19] += 0.05  # the legs bent: every Jacobian changes from tick 0
    v[6:] = np.random.default_rng(3).normal(scale=0.3, size=32)
    g["robot"].q.set(q)
    g["robot"].v.set(v)
    first, again = solver.solution(1), solver.solution(1)
    for one, other in zip(first.tasks, again.tasks, strict=True):
        np.testing.assert_array_equal(one.desired_force, other.desired_force)
    np.testing.assert_array_equal(first.tau, again.tau)  # the same guess, the same ProxQP answer
