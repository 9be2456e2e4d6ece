"""Strict-priority stacks of tasks (SoT): velocity tasks, contacts, limits and the cascade solvers."""

from dgraph.entities.hierarchy.cascade import CascadeSolution, Level, LexicographicCascade
from dgraph.entities.hierarchy.hierarchical_inverse_dynamics import HierarchicalInverseDynamics
from dgraph.entities.hierarchy.hierarchical_solver import HierarchicalSolver
from dgraph.entities.hierarchy.joint_limits import JointLimits
from dgraph.entities.hierarchy.rows import PriorityRows
from dgraph.entities.hierarchy.velocity_contact import VelocityContact
from dgraph.entities.hierarchy.velocity_task import VelocityTask

__all__ = ["CascadeSolution", "HierarchicalInverseDynamics", "HierarchicalSolver", "JointLimits", "Level",
           "LexicographicCascade", "PriorityRows", "VelocityContact", "VelocityTask"]
