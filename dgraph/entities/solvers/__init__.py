"""Solvers: whole-body torque controllers (the maths they run is in :mod:`dgraph.control`)."""

from dgraph.entities.solvers.inverse_dynamics import InverseDynamicsSolver
from dgraph.entities.solvers.mptc import MptcSolver
from dgraph.entities.solvers.torque_solver import TorqueSolver

__all__ = ["InverseDynamicsSolver", "MptcSolver", "TorqueSolver"]
