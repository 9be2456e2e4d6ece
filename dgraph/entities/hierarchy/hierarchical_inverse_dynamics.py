"""HierarchicalInverseDynamics: strict-priority inverse dynamics (accelerations and contact forces)."""

from __future__ import annotations

import numpy as np
import scipy.linalg

import dgraph as dg
from dgraph.entities.contacts.constraint import ContactConstraint
from dgraph.entities.hierarchy.cascade import Level, LexicographicCascade
from dgraph.entities.hierarchy.stack import StackCommands
from dgraph.entities.solvers.inverse_dynamics import InverseDynamicsSolver
from dgraph.entities.solvers.inverse_dynamics_qp import PRIMAL_INFEASIBLE, SOLVED, QPSolution


@dg.register
class HierarchicalInverseDynamics(StackCommands, InverseDynamicsSolver):
    """Torque control from tasks in strict priority (thesis Eq. 2.58, the hierarchical form of
    Eq. 4.14).

    Variables ``y = [a, f]`` as in :class:`InverseDynamicsSolver`, solved by the same
    lexicographic cascade as :class:`HierarchicalSolver`
    (:mod:`~dgraph.entities.hierarchy.cascade`); only the variables and the fixed constraints
    differ. Levels, highest first:

    0. the fixed constraints of the weighted QP (built by the same
       :meth:`InverseDynamicsQP.assemble`): floating-base dynamics
       ``M_u a - (J_c^T T)_u f = -h_u``, each active contact's motion ``J_c a = rhs_c``, its
       friction pyramids and normal-force bounds, and the torque limits
       ``-tau_max - h_j <= M_j a - (J_c^T T)_j f <= tau_max - h_j``;
    1. … the levels of ``stack``: each task's rows ``sqrt(w) (A a - b)`` (weights act within
       a level only; a level never trades against another);
    last: the regularisation of the weighted QP as a level of its own,
       ``min acceleration_weight ||a||^2 + sum_c force_weight_c ||f_c||^2_{M_c}`` (each contact's force metric).

    ``tau = M_j a + h_j - (J_c^T T)_j f`` (Eq. 2.4). If the fixed constraints cannot all hold
    (their residual exceeds ``constraint_tolerance``) ``status`` is 2 (primal infeasible); a
    failed or infeasible solve gives the gravity-compensation fallback of
    :class:`InverseDynamicsSolver`.

    Limits: task levels hold equalities over the accelerations only (a Task's equation), so a
    force task or a task inequality cannot be a level here (inequalities live in the fixed
    level); tasks are removed with the stack commands (a Task has no ``active`` input); the
    energy tank's passive mode is not available (``passive: true`` is refused).

    Parameters: those of :class:`InverseDynamicsSolver` (``eps_abs`` and ``max_iterations``
    go to ProxQP), ``priorities`` (one per task, 0 highest; default: one level per task in
    order), ``rank_tolerance``, ``closed_form``, ``constraint_tolerance``.
    Inputs: ``robot``, one per task (a Task's ``equation``), one per contact (a Contact6d's
    ``contact``), ``stack`` (commands ``push``, ``remove``, ``up``, ``down``, ``clear``,
    ``levels``, as :class:`HierarchicalSolver`).
    Outputs: those of :class:`InverseDynamicsSolver`; ``iterations`` sums the levels'.
    """

    priorities = dg.Param((), kind="int_list", doc="priority of each task (0 highest); default: in order")
    eps_abs = dg.Param(1e-8, kind="float", minimum=1e-12, maximum=1e-3, doc="ProxQP absolute tolerance (then polished)")
    rank_tolerance = dg.Param(1e-9, kind="float", minimum=0.0, doc="relative rank threshold of the cascade")
    closed_form = dg.Param(True, kind="bool", doc="solve a level in closed form when no inequality binds")
    constraint_tolerance = dg.Param(1e-6, kind="float", minimum=0.0, doc="largest residual of the fixed level")

    def configure(self) -> None:
        """The weighted solver's ports, the stack and the cascade."""
        if self.passive:
            raise dg.ParamError(f"{self.name}: the hierarchical solver has no passive mode (use "
                                "InverseDynamicsSolver with an EnergyTank)", entity=self.name)
        super().configure()
        self.declare_stack(self.priorities)
        self._cascade = LexicographicCascade(eps_abs=self.eps_abs, max_iterations=self.max_iterations,
                                             rank_tolerance=self.rank_tolerance, closed_form=self.closed_form)
        self._regularisations: dict[tuple[object, ...], Level] = {}

    def _regularisation(self, contacts: list[ContactConstraint]) -> Level:
        """``R y = 0`` with ``R^T R`` the weighted QP's regularisation (``eps I`` on ``a``,
        ``w_c M_c`` on each contact's forces) as the last level."""
        key = tuple((c.name, c.n_forces, c.force_weight, None if c.force_metric is None else c.force_metric.tobytes())
                    for c in contacts)
        level = self._regularisations.get(key)
        if level is None:
            blocks = [np.sqrt(self.acceleration_weight) * np.eye(self.nv)]
            for c in contacts:
                metric = np.eye(c.n_forces) if c.force_metric is None else c.force_metric
                blocks.append(np.sqrt(c.force_weight) * np.linalg.cholesky(metric).T)  # U^T U = M
            matrix = scipy.linalg.block_diag(*blocks)
            n = len(matrix)
            level = Level(("regularisation", key), matrix, np.zeros(n), np.zeros((0, n)), np.zeros(0), np.zeros(0))
            self._regularisations[key] = level
        return level

    def _task_levels(self, t: int, n: int) -> list[Level]:
        """The stack's levels over ``y`` (the force columns are zero)."""
        levels = []
        for names in self.read_stack(t):
            equations = []
            for name in names:
                equation = getattr(self, name)(t)
                self._check_equation(name, equation, t)
                equations.append(equation)
            scale = np.concatenate([np.sqrt(e.weight) for e in equations])
            matrix = np.zeros((len(scale), n))
            matrix[:, :self.nv] = np.vstack([e.matrix for e in equations]) * scale[:, None]
            vector = np.concatenate([e.vector for e in equations]) * scale
            key = tuple((name, len(e.vector)) for name, e in zip(names, equations, strict=True))
            levels.append(Level(key, matrix, vector, np.zeros((0, n)), np.zeros(0), np.zeros(0)))
        return levels

    @dg.output(dtype=QPSolution, on_demand=True)  # reads only the tasks in the stack
    def solution(self, t: int) -> QPSolution:
        """Solve the cascade at ``t`` (or fall back)."""
        state = self.robot(t)
        contacts = [inp(t) for inp in self._contact_inputs]
        rows = [row for row, contact in enumerate(contacts) if contact.active]
        active = [contacts[r] for r in rows]
        ws = self._qp.assemble(state.mass_matrix, state.bias_forces, [], active)
        n = ws.H.shape[0]
        fixed = Level(("fixed", tuple(c.name for c in active)), ws.A, ws.b, ws.C, ws.lower, ws.upper)
        result = self._cascade.solve([fixed, *self._task_levels(t, n), self._regularisation(active)], n, t)
        status = result.status
        if status == SOLVED and fixed.residual(result.x) > self.constraint_tolerance:
            status = PRIMAL_INFEASIBLE
        y = result.x
        forces = np.split(y[self.nv:], np.cumsum([c.n_forces for c in active])[:-1]) if active else []
        tau = ws.C[-self.na:] @ y + state.bias_forces[self.n_unactuated:] if status == SOLVED else \
            self.fallback_torque(state)
        solution = QPSolution(y[:self.nv], tau, forces, status, result.iterations, result.solve_time,
                              contacts=active)
        solution.contact_rows = rows
        return solution
