"""HierarchicalSolver: strict-priority inverse kinematics (SoT's stack of tasks) as an entity."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.control.cascade import LexicographicCascade
from dgraph.control.rows import RowBlock, stacked
from dgraph.control.solutions import CascadeSolution
from dgraph.entities.hierarchy.stack import StackCommands
from dgraph.entities.named_inputs import declare_named_inputs
from dgraph.entities.robot.loading import load_model
from dgraph.entities.solver_report import SolverReport


@dg.register
class HierarchicalSolver(StackCommands, SolverReport, dg.Entity):
    """Velocity-level inverse kinematics with strict priorities (thesis §4.2.1, Eq. 4.3–4.4;
    Saab et al., Eq. 2.59).

    Every tick, the levels of ``stack`` (highest first) are solved lexicographically over the
    velocity ``v`` (nv) by :class:`~dgraph.control.cascade.LexicographicCascade`:
    level ``k`` minimises ``||A_k v - b_k||^2 + ||s_k||^2`` (equalities and the slack ``s_k`` of
    its inequalities ``l_k <= C_k v - s_k <= u_k``) while every level above keeps its optimal
    residual and slack; a lower level never degrades a higher one. A last, implicit level
    ``min ||v||^2`` makes ``v`` unique. The rows of a level are those of its active tasks
    (:class:`~dgraph.control.rows.RowBlock` from :class:`VelocityTask`, :class:`VelocityContact`,
    :class:`JointLimits`); Table 4.1's stack is contacts and limits at 0, then CoM height, CoM
    lateral-sagittal, waist orientation, posture.

    Failures never raise: non-finite rows or a failed ProxQP level give ``status`` (a
    :class:`~dgraph.control.status.Status`: 0 solved, 1 max iterations, 2 primal infeasible, 3 dual
    infeasible, 4 not finite, 5 other). After a failed level ``velocity`` is the solution of the
    levels above it, which all still hold (limits and contacts first); with non-finite rows it
    is 0 (the robot stops). The next tick starts cold.

    Parameters: ``model`` (sizes ``v``), ``tasks`` (names of the task inputs), ``priorities``
    (one per task, 0 highest, equal values share a level; default: one level per task in
    order), ``eps_abs``, ``max_iterations`` (ProxQP), ``rank_tolerance``, ``closed_form``
    (false: every level goes to ProxQP; see the cascade).
    Inputs: one per task (a ``rows`` output), ``stack`` (the levels; edited by the commands
    ``push(task, level=None)``, ``remove(task)``, ``up(task)``, ``down(task)``, ``clear()``;
    ``levels()`` lists them).
    Outputs: ``solution`` (:class:`~dgraph.control.solutions.CascadeSolution`; its ``levels``
    are those of the stack, then the minimum norm), ``velocity`` (nv, the command of a
    velocity-controlled device or an integrator), ``level_residuals`` (one per level of the
    stack, 0 while a level has no active task, then the final ``||v||``), ``status``,
    ``iterations``, ``qp_levels`` (levels that needed ProxQP), ``solve_time`` (s).
    """

    model = dg.Param("talos", kind="name_or_path", doc="robot name, URDF path or pinocchio.Model (sizes v)")
    tasks = dg.Param((), kind="str_list", doc="task input names")
    priorities = dg.Param((), kind="int_list", doc="priority of each task (0 highest); default: in order")
    eps_abs = dg.Param(1e-8, kind="float", minimum=1e-12, maximum=1e-3, doc="ProxQP absolute tolerance (then polished)")
    max_iterations = dg.Param(1000, kind="int", minimum=1, doc="ProxQP iteration limit")
    rank_tolerance = dg.Param(1e-9, kind="float", minimum=0.0, doc="relative singular-value threshold")
    closed_form = dg.Param(True, kind="bool", doc="solve a level in closed form when no inequality binds")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", tasks: Sequence[str] = (), priorities: Sequence[int] = (),
            eps_abs: float = 1e-08, max_iterations: int = 1000, rank_tolerance: float = 1e-09, closed_form: bool = True,
        ) -> None: ...

    def configure(self) -> None:
        """Size ``v``, declare the task inputs and the stack."""
        self.nv = load_model(self.model, self.name).nv
        declare_named_inputs(self, [(self.tasks, RowBlock, "rows of task")], reserved=("stack",))
        self.declare_stack(self.priorities)
        self._cascade = LexicographicCascade(eps_abs=self.eps_abs, max_iterations=self.max_iterations,
                                             rank_tolerance=self.rank_tolerance, closed_form=self.closed_form)
        self._minimum_norm = RowBlock.equalities(np.eye(self.nv), np.zeros(self.nv), key="minimum_norm")
        self._no_rows = RowBlock.empty(self.nv, key=())  # a level whose tasks are all inactive

    def setup(self) -> None:
        """Index the task inputs."""
        self._inputs = {name: getattr(self, name) for name in self.tasks}

    def _rows(self, name: str, t: int) -> RowBlock:
        """The task's rows, checked (``SpecError`` naming the input)."""
        rows = self._inputs[name](t)
        problem = rows.shape_problem(self.nv)
        if problem is not None:
            raise dg.SpecError(f"{self.name}.{name} at tick {t}: {problem} (the robot has nv = {self.nv})",
                               entity=self.name, signal=name)
        return rows

    def _levels(self, t: int) -> list[RowBlock]:
        """One level per level of the stack, highest first (the rows of its active tasks, none
        while they are all inactive, so that an index always names the same level), then the
        minimum-norm level."""
        levels = []
        for level in self.read_stack(t):
            active = [(name, rows) for name in level if (rows := self._rows(name, t)).active]
            if active:
                key = tuple((name, len(r.equality_vector), len(r.lower)) for name, r in active)
                levels.append(stacked([r for _, r in active], key))
            else:
                levels.append(self._no_rows)
        return [*levels, self._minimum_norm]

    @dg.output(dtype=CascadeSolution, on_demand=True)  # reads only the tasks in the stack
    def solution(self, t: int) -> CascadeSolution:
        """The cascade's answer at ``t`` (its ``levels``: those of the stack, then the minimum norm)."""
        return self._cascade.solve(self._levels(t), self.nv, t)

    @dg.output(shape=("nv",), depends=("solution",))
    def velocity(self, t: int) -> np.ndarray:
        """``v`` (after a failed level, the levels above it; zeros for non-finite rows)."""
        return self.solution(t).x

    @dg.output(shape=None, depends=("solution",), finite=False)
    def level_residuals(self, t: int) -> np.ndarray:
        """``sqrt(||A_k v - b_k||^2 + ||s_k||^2)`` per level of the stack (0 for a level whose
        tasks are all inactive: it has no rows; an index always names the same level; inf for a
        level that was not solved), then ``||v||``."""
        return self.solution(t).residuals

    @dg.output(shape=(), dtype="int", depends=("solution",))
    def qp_levels(self, t: int) -> int:
        """How many levels needed ProxQP (the others were solved in closed form)."""
        return self.solution(t).qp_levels
