"""Whole-body inverse dynamics over accelerations and contact forces: its constraint rows, and the
weighted QP of thesis Eq. 4.14 solved by ProxQP."""

from dgraph.control.inverse_dynamics.constraints import ConstraintRows
from dgraph.control.inverse_dynamics.qp import DEFAULT_EPS_ABS, PROXIMAL_RHO, InverseDynamicsQP
from dgraph.control.inverse_dynamics.task_rows import TaskRowsError

__all__ = ["DEFAULT_EPS_ABS", "PROXIMAL_RHO", "ConstraintRows", "InverseDynamicsQP", "TaskRowsError"]
