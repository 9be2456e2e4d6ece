"""InverseDynamicsSolver: the weighted whole-body inverse-dynamics QP as an entity."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import dgraph as dg
from dgraph.control.equation import TaskEquation
from dgraph.control.inverse_dynamics import DEFAULT_EPS_ABS, InverseDynamicsQP, TaskRowsError
from dgraph.control.passivity import Passivity
from dgraph.control.solutions import QPSolution
from dgraph.control.status import SOLVED
from dgraph.entities.robot.robot_state import RobotState
from dgraph.entities.solvers.torque_solver import TorqueSolver


@dg.register
class InverseDynamicsSolver(TorqueSolver):
    """Torque control from weighted tasks and rigid contacts (thesis Eq. 4.14, "TSID torque").

    Solves, every tick, for accelerations ``a`` and contact forces ``f``
    (:mod:`~dgraph.control.inverse_dynamics.qp`):

    ``min sum_i w_i ||A_i a - b_i||^2 + sum_c w_c ||f_c - f*_c||^2_{M_c} + eps ||a||^2``

    subject to the floating-base dynamics ``M_u a - (J_c^T T)_u f = -h_u``, each active
    contact's motion ``J_c a = rhs_c`` (Eq. 4.10), its friction pyramids and normal-force
    bounds, and the torque limits, then recovers ``tau = M_j a + h_j - (J_c^T T)_j f``
    (Eq. 2.4). The torque limits enter the QP only on ticks where the answer without them would
    exceed one (``torque_limited``); the answer is the same either way. When the QP fails
    (infeasible, iteration limit, non-finite data), ``status`` says why and ``tau`` is the
    gravity-compensation fallback of :class:`~dgraph.entities.solvers.torque_solver.TorqueSolver`.

    Passive mode (``passive: true``, thesis Eq. 5.34): an input ``passivity`` (an
    :class:`~dgraph.entities.energy.EnergyTank`'s ``passivity``) scales every task vector and
    force reference by ``beta gamma`` (Eq. 5.24) and adds the row ``-v_j^T tau >= H_dot``
    (Eq. 5.26). A tank that is disabled hands over scale 1 and no bound: the QP is then the
    plain one, bit for bit. When no torque within the limits can deliver the bound
    (``H_dot > sum |v_j| tau_max``), or the passive QP fails, it is solved without the
    passivity row (``passivity_relaxed`` is true for that tick: the tank, integrated from the
    delivered power, pays for it), and only if that fails too does the fallback act.

    Parameters: those of ``TorqueSolver`` (``model``, ``tasks``, ``contacts``,
    ``max_iterations``, ``fallback_damping``), ``acceleration_weight`` (regularisation
    ``eps ||a||^2``), ``eps_abs`` (ProxQP absolute tolerance, also the torque-limit margin),
    ``passive``.
    Inputs: ``robot`` (RobotModel state), one per task (a Task's ``equation``), one per contact
    (a contact's ``contact``), ``passivity`` (with ``passive``).
    Outputs: ``solution`` (:class:`~dgraph.control.solutions.QPSolution`, everything below,
    computed once), ``tau``, ``acceleration``, ``contact_wrenches`` (world axes),
    ``normal_force_total``, ``status``, ``iterations``, ``solve_time`` (those of
    ``TorqueSolver``), ``passivity_relaxed``, ``torque_limited``.
    """

    reserved_inputs = ("passivity",)

    eps_abs = dg.Param(DEFAULT_EPS_ABS, kind="float", minimum=1e-12, maximum=1e-3,
                       doc="ProxQP absolute tolerance (also the torque-limit margin)")
    passive = dg.Param(False, kind="bool", doc="declare a passivity input (an energy tank's, Eq. 5.34)")
    acceleration_weight = dg.Param(1e-6, kind="float", minimum=0.0, doc="regularisation of a")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", tasks: Sequence[str] = (), contacts: Sequence[str] = (),
            max_iterations: int = 1000, fallback_damping: float = 1.0, eps_abs: float = 1e-06, passive: bool = False,
            acceleration_weight: float = 1e-06,
        ) -> None: ...

    def configure(self) -> None:
        """The ports of a torque solver, the QP, and the passivity input in passive mode."""
        super().configure()
        self._qp = InverseDynamicsQP(self.nv, self.n_unactuated, self.effort_limit, eps_abs=self.eps_abs,
                                     max_iterations=self.max_iterations, acceleration_weight=self.acceleration_weight)
        if self.passive:
            self.declare("passivity", dg.Input(dtype=Passivity, doc="task scale and storage-rate bound of a tank"))

    def _bad_equation(self, tasks: list[TaskEquation], t: int, cause: TaskRowsError) -> dg.SpecError:
        """The error naming the task input whose equation did not fit its block of the QP."""
        name = self._task_inputs[cause.index].name
        problem = tasks[cause.index].problem(self.nv) or str(cause)
        return dg.SpecError(f"{self.name}.{name} at tick {t}: {problem}", entity=self.name, signal=name)

    @dg.output(dtype=QPSolution)
    def solution(self, t: int) -> QPSolution:
        """Solve the QP at ``t`` (or fall back)."""
        state: RobotState = self.robot(t)
        tasks = [inp(t) for inp in self._task_inputs]
        rows, contacts = self.active_contacts(t)
        passivity = self.passivity(t) if self.passive else None
        relax = passivity is not None and not self._qp.reaches(passivity)
        if relax:  # no torque within the limits delivers the bound: ProxQP would only run to its limit
            passivity = passivity.without_bound()
        try:  # a task whose rows do not fit its block (shape, negative weights) is named here
            solution = self._qp.solve(state.mass_matrix, state.bias_forces, tasks, contacts, t, passivity)
        except TaskRowsError as exc:
            raise self._bad_equation(tasks, t, exc) from exc
        if solution.status != SOLVED and passivity is not None and passivity.power_bound is not None:
            relax = True
            solution = self._qp.solve(state.mass_matrix, state.bias_forces, tasks, contacts, t,
                                      passivity.without_bound())
        solution.passivity_relaxed = relax
        solution.contact_rows = rows
        if solution.status == SOLVED:
            self.keep_state(state)
        else:
            solution.tau = self.fallback_torque(t, state, solution.status)
        return solution

    @dg.output(shape=(), dtype="bool", depends=("solution",))
    def passivity_relaxed(self, t: int) -> bool:
        """True when the passive QP failed and was solved without its passivity row."""
        return self.solution(t).passivity_relaxed

    @dg.output(shape=(), dtype="bool", depends=("solution",))
    def torque_limited(self, t: int) -> bool:
        """True when a torque limit binds (the QP was solved a second time, with the limits)."""
        return self.solution(t).torque_limited
