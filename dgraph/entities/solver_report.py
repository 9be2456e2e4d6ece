"""SolverReport: the outputs every solver entity reads off its ``solution`` output."""

from __future__ import annotations

import dgraph as dg


class SolverReport:
    """Mixin of the solver entities (a torque QP, the strict-priority cascades): ``status``,
    ``iterations`` and ``solve_time`` of the value of the entity's ``solution`` output (a
    :class:`~dgraph.control.solutions.QPSolution` or
    :class:`~dgraph.control.solutions.CascadeSolution`, which both carry them).

    Outputs: ``status`` (a :class:`~dgraph.control.status.Status`: 0 solved, 1 max iterations,
    2 primal infeasible, 3 dual infeasible, 4 not finite, 5 other), ``iterations`` (ProxQP
    iterations of the tick, summed over its solves or levels), ``solve_time`` (s, wall time of
    the tick's assembly and solves).
    """

    @dg.output(shape=(), dtype="int", depends=("solution",))
    def status(self, t: int) -> int:
        """0 when solved; see the class docstring for the failure codes."""
        return self.solution(t).status

    @dg.output(shape=(), dtype="int", depends=("solution",))
    def iterations(self, t: int) -> int:
        """ProxQP iterations of the tick (summed over its solves or levels)."""
        return self.solution(t).iterations

    @dg.output(shape=(), depends=("solution",))
    def solve_time(self, t: int) -> float:
        """Wall time of the tick's assembly and solves (s)."""
        return self.solution(t).solve_time
