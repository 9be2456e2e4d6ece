"""MPTC task forces (report Eq. 16) on a Pinocchio arm: the task Coriolis matrix satisfies
M_k_dot = C_k + C_k^T (finite differences), and the desired force gives the closed loop
M_k x~_ddot + (C_k + D_k) x~_dot + K_k x~ = 0 when it is delivered."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from dgraph.control.feature import FeatureValue
from dgraph.control.mptc import Dynamics, MptcQP, task_force
from dgraph.control.proxqp import INFINITY

WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@pytest.fixture(scope="module")
def arm() -> tuple[pin.Model, pin.Data, int]:
    model = pin.buildSampleModelManipulator()
    return model, model.createData(), model.nframes - 1


def dynamics_at(model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> Dynamics:
    pin.computeAllTerms(model, data, q, v)
    mass = data.M.copy()
    mass = np.triu(mass) + np.triu(mass, 1).T
    coriolis = pin.computeCoriolisMatrix(model, data, q, v).copy()
    gravity = pin.computeGeneralizedGravity(model, data, q).copy()
    return Dynamics(np.linalg.inv(mass), coriolis, coriolis @ v + gravity, v)


def position_task(model: pin.Model, data: pin.Data, frame: int, q: np.ndarray, v: np.ndarray, reference: np.ndarray,
                  kp: float = 0.0, kd: float = 0.0):
    """The frame's position task at (q, v): its feature, exact J_dot, and the task force."""
    dynamics = dynamics_at(model, data, q, v)
    pin.computeJointJacobiansTimeVariation(model, data, q, v)
    pin.updateFramePlacements(model, data)
    jacobian = pin.getFrameJacobian(model, data, frame, WORLD)[:3].copy()
    jacobian_rate = pin.getFrameJacobianTimeVariation(model, data, frame, WORLD)[:3].copy()
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    drift = pin.getFrameClassicalAcceleration(model, data, frame, WORLD).linear.copy()
    position = pin.updateFramePlacement(model, data, frame).translation
    feature = FeatureValue(position - reference, jacobian @ v, jacobian, drift, np.zeros(3))
    force = task_force(feature, np.full(3, kp), np.full(3, kd), 1.0, dynamics, jacobian_rate)
    return feature, force, dynamics, jacobian_rate


def test_the_task_coriolis_matrix_makes_the_inertia_rate_skew_free(arm):
    model, data, frame = arm
    rng = np.random.default_rng(0)
    q, v = pin.randomConfiguration(model), rng.normal(size=model.nv)
    _, force, dynamics, jacobian_rate = position_task(model, data, frame, q, v, np.zeros(3))
    step = 1e-6
    inertias = [position_task(model, data, frame, pin.integrate(model, q, s * step * v), v, np.zeros(3))[1].inertia
                for s in (-1, 1)]
    inertia_rate = (inertias[1] - inertias[0]) / (2 * step)
    # C_k's own definition, M_k (J M^-1 C - J_dot) M^-1 J^T M_k, from the pieces
    mobility = dynamics.inverse_mass_matrix @ force.jacobian.T
    coriolis = force.inertia @ (mobility.T @ dynamics.coriolis_matrix - jacobian_rate) @ mobility @ force.inertia
    np.testing.assert_allclose(coriolis + coriolis.T, inertia_rate, rtol=1e-5, atol=1e-6 * np.abs(inertia_rate).max())
    velocity_error = rng.normal(size=3)
    delivered = task_force(FeatureValue(np.zeros(3), -velocity_error, force.jacobian, np.zeros(3), np.zeros(3)),
                           np.zeros(3), np.zeros(3), 1.0, dynamics, jacobian_rate)
    baseline = task_force(FeatureValue(np.zeros(3), np.zeros(3), force.jacobian, np.zeros(3), np.zeros(3)),
                          np.zeros(3), np.zeros(3), 1.0, dynamics, jacobian_rate)
    # the velocity error enters f_des through (C_k + D_k), here D_k = 0: the difference is C_k x~_dot
    np.testing.assert_allclose(delivered.desired_force - baseline.desired_force, coriolis @ velocity_error,
                               atol=1e-9 * max(1.0, np.abs(coriolis).max()))


@pytest.mark.parametrize("kp", [4.0, 100.0])
def test_a_delivered_task_force_gives_the_closed_loop_it_promises(arm, kp: float):
    model, data, frame = arm
    rng = np.random.default_rng(1)
    q, v = pin.randomConfiguration(model), rng.normal(size=model.nv)
    reference = rng.normal(size=3) * 0.1
    kd = 2.0 * np.sqrt(kp)
    feature, force, dynamics, jacobian_rate = position_task(model, data, frame, q, v, reference, kp, kd)
    qp = MptcQP(model.nv, 0, np.full(model.nv, INFINITY), eps_abs=1e-12, max_iterations=10_000, regularisation=0.0)
    solution = qp.solve(dynamics, [force], [], tick=None)
    acceleration = pin.aba(model, data, q, v, solution.tau)
    task_acceleration = force.jacobian @ acceleration + feature.drift
    x_err, xd_err, xdd_err = -feature.error, -feature.error_velocity, -task_acceleration
    np.testing.assert_allclose(np.linalg.solve(force.inertia, force.stiffness), kp * np.eye(3), atol=1e-9 * kp)
    np.testing.assert_allclose(np.linalg.solve(force.inertia, force.damping), kd * np.eye(3), atol=1e-9 * kd)
    task_coriolis = force.inertia @ (force.mobility.T @ dynamics.coriolis_matrix - jacobian_rate) @ force.mobility \
        @ force.inertia
    closed_loop = force.inertia @ xdd_err + (task_coriolis + force.damping) @ xd_err + force.stiffness @ x_err
    np.testing.assert_allclose(closed_loop, 0.0, atol=1e-7 * np.abs(force.desired_force).max())
