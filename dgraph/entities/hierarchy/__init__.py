"""Strict-priority stacks of tasks (SoT): velocity tasks, contacts, limits and the solvers that
run the lexicographic cascade (:mod:`dgraph.control.cascade`) over them."""

from dgraph.entities.hierarchy.hierarchical_inverse_dynamics import HierarchicalInverseDynamics
from dgraph.entities.hierarchy.hierarchical_solver import HierarchicalSolver
from dgraph.entities.hierarchy.joint_limits import JointLimits
from dgraph.entities.hierarchy.velocity_contact import VelocityContact
from dgraph.entities.hierarchy.velocity_task import VelocityTask

__all__ = ["HierarchicalInverseDynamics", "HierarchicalSolver", "JointLimits", "VelocityContact", "VelocityTask"]
