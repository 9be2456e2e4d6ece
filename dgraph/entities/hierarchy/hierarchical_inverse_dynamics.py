"""HierarchicalInverseDynamics: strict-priority inverse dynamics (accelerations and contact forces)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg

import dgraph as dg
from dgraph.control.cascade import LexicographicCascade
from dgraph.control.contact import ContactConstraint
from dgraph.control.inverse_dynamics import ConstraintRows
from dgraph.control.rows import RowBlock
from dgraph.control.solutions import QPSolution
from dgraph.control.status import PRIMAL_INFEASIBLE, SOLVED
from dgraph.entities.hierarchy.stack import StackCommands
from dgraph.entities.solvers.torque_solver import TorqueSolver


@dg.register
class HierarchicalInverseDynamics(StackCommands, TorqueSolver):
    """Torque control from tasks in strict priority (thesis Eq. 2.58, the hierarchical form of
    Eq. 4.14).

    Variables ``y = [a, f]`` as in :class:`~dgraph.entities.solvers.InverseDynamicsSolver`,
    solved by the same lexicographic cascade as :class:`HierarchicalSolver`
    (:mod:`~dgraph.control.cascade`); only the variables and the fixed constraints differ.
    Levels, highest first:

    0. the constraints of whole-body inverse dynamics, the weighted QP's
       (:class:`~dgraph.control.inverse_dynamics.ConstraintRows`): floating-base dynamics
       ``M_u a - (J_c^T T)_u f = -h_u``, each active contact's motion ``J_c a = rhs_c``
       (Eq. 4.10), its friction pyramids and normal-force bounds, and the torque limits
       ``-tau_max - h_j <= M_j a - (J_c^T T)_j f <= tau_max - h_j``;
    1. … the levels of ``stack``: each task's rows ``sqrt(w) (A a - b)`` (weights act within
       a level only; a level never trades against another);
    last: the regularisation of the weighted QP as a level of its own,
       ``min acceleration_weight ||a||^2 + sum_c force_weight_c ||f_c||^2_{M_c}`` (each contact's force metric).

    ``tau = M_j a + h_j - (J_c^T T)_j f`` (Eq. 2.4). If the fixed constraints cannot all hold
    (their residual exceeds ``constraint_tolerance``) ``status`` is 2 (primal infeasible); a
    failed or infeasible solve gives the gravity-compensation fallback of the torque solvers.

    Limits: task levels hold equalities over the accelerations only (a Task's equation), so a
    force task or a task inequality cannot be a level here (inequalities live in the fixed
    level); tasks are removed with the stack commands (a Task has no ``active`` input); there
    is no passive mode (an energy tank's row would be one more fixed constraint whose bound
    follows the weighted tasks' power: use :class:`~dgraph.entities.solvers.InverseDynamicsSolver`).

    Parameters: those of :class:`~dgraph.entities.solvers.TorqueSolver` (``model``, ``tasks``,
    ``contacts``, ``max_iterations`` for ProxQP, ``fallback_damping``), ``acceleration_weight``,
    ``eps_abs`` (ProxQP's), ``priorities`` (one per task, 0 highest; default: one level per task
    in order), ``rank_tolerance``, ``closed_form``, ``constraint_tolerance``.
    Inputs: ``robot``, one per task (a Task's ``equation``), one per contact (a Contact6d's
    ``contact``), ``stack`` (commands ``push``, ``remove``, ``up``, ``down``, ``clear``,
    ``levels``, as :class:`HierarchicalSolver`).
    Outputs: those of a ``TorqueSolver`` (``solution``, ``tau``, ``acceleration``,
    ``contact_wrenches``, ``normal_force_total``, ``status``, ``iterations``, summed over the
    levels, ``solve_time``).
    """

    reserved_inputs = ("stack",)

    priorities = dg.Param((), kind="int_list", doc="priority of each task (0 highest); default: in order")
    eps_abs = dg.Param(1e-8, kind="float", minimum=1e-12, maximum=1e-3, doc="ProxQP absolute tolerance (then polished)")
    rank_tolerance = dg.Param(1e-9, kind="float", minimum=0.0, doc="relative rank threshold of the cascade")
    closed_form = dg.Param(True, kind="bool", doc="solve a level in closed form when no inequality binds")
    constraint_tolerance = dg.Param(1e-6, kind="float", minimum=0.0, doc="largest residual of the fixed level")
    acceleration_weight = dg.Param(1e-6, kind="float", minimum=0.0, doc="regularisation of a")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", tasks: Sequence[str] = (), contacts: Sequence[str] = (),
            max_iterations: int = 1000, fallback_damping: float = 1.0, priorities: Sequence[int] = (),
            eps_abs: float = 1e-08, rank_tolerance: float = 1e-09, closed_form: bool = True,
            constraint_tolerance: float = 1e-06, acceleration_weight: float = 1e-06,
        ) -> None: ...

    def configure(self) -> None:
        """The ports of a torque solver, the stack and the cascade."""
        super().configure()
        self.declare_stack(self.priorities)
        self._cascade = LexicographicCascade(eps_abs=self.eps_abs, max_iterations=self.max_iterations,
                                             rank_tolerance=self.rank_tolerance, closed_form=self.closed_form)
        self._constraints: dict[tuple[object, ...], ConstraintRows] = {}
        self._regularisations: dict[tuple[object, ...], RowBlock] = {}

    def _constraint_rows(self, contacts: list[ContactConstraint]) -> ConstraintRows:
        """The rows of this set of active contacts (by name and size), made on first use."""
        key = ConstraintRows.key(contacts)
        rows = self._constraints.get(key)
        if rows is None:
            rows = self._constraints[key] = ConstraintRows(self.nv, self.n_unactuated, self.effort_limit, contacts)
        return rows

    def _regularisation(self, contacts: list[ContactConstraint]) -> RowBlock:
        """``R y = 0`` with ``R^T R`` the weighted QP's regularisation (``eps I`` on ``a``,
        ``w_c M_c`` on each contact's forces) as the last level."""
        key = tuple((c.name, c.n_forces, c.force_weight, None if c.force_metric is None else c.force_metric.tobytes())
                    for c in contacts)
        level = self._regularisations.get(key)
        if level is None:
            blocks = [np.sqrt(self.acceleration_weight) * np.eye(self.nv)]
            for c in contacts:
                blocks.append(np.sqrt(c.force_weight) * np.linalg.cholesky(c.metric()).T)  # U^T U = M
            matrix = scipy.linalg.block_diag(*blocks)
            level = RowBlock.equalities(matrix, np.zeros(len(matrix)), key=("regularisation", key))
            self._regularisations[key] = level
        return level

    def _task_levels(self, t: int, n: int) -> list[RowBlock]:
        """The stack's levels over ``y`` (the force columns are zero)."""
        levels = []
        for names in self.read_stack(t):
            equations = [self.checked_equation(name, t) for name in names]
            scale = np.concatenate([np.sqrt(e.weight) for e in equations])
            matrix = np.zeros((len(scale), n))
            matrix[:, :self.nv] = np.vstack([e.matrix for e in equations]) * scale[:, None]
            vector = np.concatenate([e.vector for e in equations]) * scale
            key = tuple((name, len(e.vector)) for name, e in zip(names, equations, strict=True))
            levels.append(RowBlock.equalities(matrix, vector, key=key))
        return levels

    @dg.output(dtype=QPSolution, on_demand=True)  # reads only the tasks in the stack
    def solution(self, t: int) -> QPSolution:
        """Solve the cascade at ``t`` (or fall back)."""
        state = self.robot(t)
        rows, active = self.active_contacts(t)
        constraints = self._constraint_rows(active)
        constraints.write(state.mass_matrix, state.bias_forces, active)
        constraints.write_torque_bounds(state.bias_forces)
        fixed = constraints.block(("fixed", tuple(c.name for c in active)))
        n = constraints.n
        result = self._cascade.solve([fixed, *self._task_levels(t, n), self._regularisation(active)], n, t)
        status = result.status
        if status == SOLVED and fixed.residual(result.x) > self.constraint_tolerance:
            status = PRIMAL_INFEASIBLE
        y = result.x
        if status == SOLVED:
            self.keep_state(state)
            tau = constraints.torques(y, state.bias_forces)
        else:
            tau = self.fallback_torque(t, state, status)
        return QPSolution(y[:self.nv], tau, constraints.forces(y), status, result.iterations, result.solve_time,
                          contacts=active, contact_rows=rows)
