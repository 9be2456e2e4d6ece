"""One MPTC task at one tick: its inertia, its dynamically consistent force map, and the task
force that makes it a passive mass-spring-damper (report Eq. 16).

Notation (report §2-3, with the printed Eq. 5's ``tau - tau_j`` read as ``tau - tau_g``): the
robot ``M q_ddot + C q_dot + g = tau``; task ``k`` with ``x_dot_k = J_k q_dot``; errors
``x~_k = x*_k (-) x_k`` and ``x~_dot_k = x*_dot_k - x_dot_k`` (the opposite sign of a
:class:`~dgraph.control.feature.FeatureValue`'s ``error``, ``x (-) x*``):

- task inertia ``M_k = (J_k M^-1 J_k^T)^-1``, force map ``T_k = M_k J_k M^-1`` (``f_k = T_k tau``),
  ``Q_k = J_k M^-1 C - J_dot_k`` and task Coriolis ``C_k = M_k Q_k T_k^T``;
- desired task force ``f_k,des = T_k g + M_k Q_k q_dot + M_k x*_ddot_k + (C_k + D_k) x~_dot_k + K_k x~_k``,
  which gives the closed loop ``M_k x~_ddot + (C_k + D_k) x~_dot + K_k x~ = f~_k`` with
  ``f~_k = f_k,des - f_k`` (report Eq. 16-19);
- storage ``V_k = x~_dot^T M_k x~_dot / 2 + x~^T K_k x~ / 2``, whose rate along the closed loop
  (``M_k_dot = C_k + C_k^T``) is ``V_k_dot = -x~_dot^T D_k x~_dot + x~_dot^T f~_k``: the task is passive
  from the force error ``f~_k`` to ``x~_dot_k`` whatever the conflicts and the limits.

Gains are shaped by the task inertia (the report's implementation; the notes' §4.3):
``K_k = diag(sqrt(k)) M_k diag(sqrt(k))`` and ``D_k = diag(sqrt(d)) M_k diag(sqrt(d))`` with the
per-row ``k`` (a task's ``kp``) and ``d`` (its ``kd``), so that with one value per task each row
obeys ``x~_ddot + d x~_dot + k x~ = M_k^-1 f~`` and ``d = 2 sqrt(k)`` damps it critically.

``q_dot^T C v`` terms use ``h - g = C q_dot`` exactly, and the feature's drift is ``J_dot_k
q_dot`` exactly; the matrix ``J_dot_k`` enters only ``C_k`` and is the caller's (the solver
entity differentiates ``J_k`` over one tick).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.control.feature import FeatureValue


@dataclass(slots=True)
class Dynamics:
    """The robot's dynamics at one tick: ``M^-1``, ``C``, ``h = C q_dot + g`` and ``q_dot`` (the
    desired forces need ``g`` only in ``T_k g + M_k Q_k q_dot = M_k J_k M^-1 h - M_k J_dot_k q_dot``)."""

    inverse_mass_matrix: np.ndarray
    coriolis_matrix: np.ndarray
    bias_forces: np.ndarray
    velocity: np.ndarray


@dataclass(slots=True)
class TaskForce:
    """Task ``k`` at one tick: ``weight`` ``psi_k``, ``jacobian`` ``J_k`` (m x nv), ``mobility``
    ``M^-1 J_k^T`` (nv x m), ``inertia`` ``M_k``, ``desired_force`` ``f_k,des``, the errors
    ``position_error`` ``x~`` and ``velocity_error`` ``x~_dot``, and the gains ``stiffness``
    ``K_k``, ``damping`` ``D_k`` (m x m)."""

    weight: float
    jacobian: np.ndarray
    mobility: np.ndarray
    inertia: np.ndarray
    desired_force: np.ndarray
    position_error: np.ndarray
    velocity_error: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray

    def storage(self) -> float:
        """``V_k = x~_dot^T M_k x~_dot / 2 + x~^T K_k x~ / 2``."""
        rate, error = self.velocity_error, self.position_error
        return 0.5 * float(rate @ self.inertia @ rate + error @ self.stiffness @ error)

    def force(self, generalized_force: np.ndarray) -> np.ndarray:
        """``f_k = T_k tau = M_k J_k M^-1 tau``: the task force a generalized force produces."""
        return self.inertia @ (self.mobility.T @ generalized_force)

    def port_power(self, force_error: np.ndarray) -> float:
        """``x~_dot^T f~_k``: the power the force error feeds into the task."""
        return float(self.velocity_error @ force_error)

    def storage_rate(self, force_error: np.ndarray) -> float:
        """``V_k_dot = -x~_dot^T D_k x~_dot + x~_dot^T f~_k`` along the closed loop."""
        rate = self.velocity_error
        return float(-rate @ self.damping @ rate) + self.port_power(force_error)


def inertia_shaped(inertia: np.ndarray, gains: np.ndarray) -> np.ndarray:
    """``diag(sqrt(g)) M_k diag(sqrt(g))``: symmetric, positive definite when every gain is."""
    root = np.sqrt(gains)
    return root[:, None] * inertia * root[None, :]


def task_force(feature: FeatureValue, stiffness: np.ndarray, damping: np.ndarray, weight: float,
               dynamics: Dynamics, jacobian_rate: np.ndarray) -> TaskForce:
    """Task ``k`` (module docstring) from its ``feature``, per-row gains ``stiffness`` (``k``)
    and ``damping`` (``d``), importance ``weight`` (``psi_k``), the robot's ``dynamics`` and
    ``jacobian_rate`` ``J_dot_k`` (m x nv). ``J_k`` must have full row rank
    (``numpy.linalg.LinAlgError`` otherwise)."""
    jacobian = feature.jacobian
    mobility = dynamics.inverse_mass_matrix @ jacobian.T
    inverse_inertia = jacobian @ mobility
    # numpy, not scipy.linalg.cho_solve: in the control loop SciPy's LAPACK took ~3 ms a call (its threads)
    inverse_factor = np.linalg.inv(np.linalg.cholesky(inverse_inertia))  # LinAlgError unless positive definite
    inertia = inverse_factor.T @ inverse_factor  # symmetric by construction
    position_error, velocity_error = -feature.error, -feature.error_velocity
    stiffness_matrix, damping_matrix = inertia_shaped(inertia, stiffness), inertia_shaped(inertia, damping)
    coriolis = inertia @ (mobility.T @ dynamics.coriolis_matrix - jacobian_rate) @ mobility @ inertia
    acceleration = mobility.T @ dynamics.bias_forces - feature.drift + feature.reference_acceleration
    desired = (inertia @ acceleration + (coriolis + damping_matrix) @ velocity_error
               + stiffness_matrix @ position_error)
    return TaskForce(weight, jacobian, mobility, inertia, desired, position_error, velocity_error,
                     stiffness_matrix, damping_matrix)


def weighted_force_residual(tasks: list[TaskForce], force_errors: list[np.ndarray]) -> np.ndarray:
    """``sum_k psi_k J_k^T f~_k`` (nv): the generalized force of the weighted task-force errors.
    The weighting ``W = Lambda^-1 Psi`` makes it zero at the unconstrained optimum when the
    actuation map has full row rank, so the conflicts do no net work on ``q_dot``."""
    residual = np.zeros(tasks[0].jacobian.shape[1]) if tasks else np.zeros(0)
    for task, error in zip(tasks, force_errors, strict=True):
        residual += task.weight * (task.jacobian.T @ error)
    return residual
