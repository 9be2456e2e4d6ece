"""The Modular Passive Tracking Controller (MPTC; Englsberger et al., RSS 2020; the report
``../shared/reference/000_f010bfa6716960a7.txt``): task forces that make every task a passive
mass-spring-damper (:mod:`~dgraph.control.mptc.task_force`, report Eq. 16) and the QP that
blends them over the torques and the contact wrenches with the weighting ``W = Lambda^-1 Psi``
(:mod:`~dgraph.control.mptc.qp`, report Eq. 24-28)."""

from dgraph.control.mptc.qp import DEFAULT_REGULARISATION, MptcQP, MptcSolution, generalized_force_map
from dgraph.control.mptc.task_force import Dynamics, TaskForce, task_force, weighted_force_residual

__all__ = ["DEFAULT_REGULARISATION", "Dynamics", "MptcQP", "MptcSolution", "TaskForce", "generalized_force_map",
           "task_force", "weighted_force_residual"]
