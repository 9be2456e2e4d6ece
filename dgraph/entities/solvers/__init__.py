"""Solvers: whole-body QP controllers."""

from dgraph.entities.solvers.inverse_dynamics import InverseDynamicsSolver
from dgraph.entities.solvers.inverse_dynamics_qp import STATUS_NAMES, InverseDynamicsQP, QPSolution

__all__ = ["STATUS_NAMES", "InverseDynamicsQP", "InverseDynamicsSolver", "QPSolution"]
