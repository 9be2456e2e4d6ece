"""ProxQP as the solvers use it: problem settings, its status codes, and a problem solved tick after tick.

ProxQP (proxsuite) solves ``min x^T H x / 2 + g^T x`` s.t. ``A x = b``, ``l <= C x <= u``;
``INFINITY`` is its "no bound". :func:`dense_qp` makes a dense problem with the settings every
solver here shares (absolute tolerance, no relative one unless asked, warm start from a guess);
:func:`proxqp_status` maps its outcome to :class:`~dgraph.control.status.Status`;
:class:`WarmStartedQP` drives one problem of fixed size from tick to tick.
"""

from __future__ import annotations

import math

import numpy as np
import proxsuite

from dgraph.control.status import (
    DUAL_INFEASIBLE,
    MAX_ITERATIONS,
    NOT_FINITE,
    NOT_SOLVED,
    PRIMAL_INFEASIBLE,
    SOLVED,
    Status,
)

INFINITY = 1e20
"""ProxQP's bound for 'no bound'."""

_PROXQP_STATUS = {getattr(proxsuite.proxqp.QPSolverOutput, name): status for name, status in (
    ("PROXQP_SOLVED", SOLVED),
    ("PROXQP_MAX_ITER_REACHED", MAX_ITERATIONS),
    ("PROXQP_PRIMAL_INFEASIBLE", PRIMAL_INFEASIBLE),
    ("PROXQP_DUAL_INFEASIBLE", DUAL_INFEASIBLE),
)}
"""The status of each ProxQP outcome (keyed by the enum itself: reading its name costs more)."""


def proxqp_status(results: object) -> Status:
    """The :class:`Status` of ProxQP ``results`` (``NOT_FINITE`` for a "solved" answer with
    non-finite entries)."""
    status = _PROXQP_STATUS.get(results.info.status, NOT_SOLVED)
    if status == SOLVED and not math.isfinite(np.vdot(results.x, results.x)):
        return NOT_FINITE
    return status


def dense_qp(n: int, n_eq: int, n_in: int, *, eps_abs: float, max_iterations: int, eps_rel: float = 0.0,
             rho: float | None = None) -> proxsuite.proxqp.dense.QP:
    """A dense ProxQP problem (``n`` variables, ``n_eq`` equalities, ``n_in`` inequalities) that
    starts from the guess handed to ``solve`` (``WARM_START``); ``rho`` is the proximal parameter
    on the primal variables (None: ProxQP's default, 1e-6)."""
    qp = proxsuite.proxqp.dense.QP(n, n_eq, n_in)
    qp.settings.eps_abs = eps_abs
    qp.settings.eps_rel = eps_rel
    qp.settings.max_iter = max_iterations
    qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START
    if rho is not None:
        qp.settings.default_rho = rho
    return qp


class WarmStartedQP:
    """One ProxQP dense problem of fixed size, solved tick after tick.

    Warm-started from the solution of the latest earlier tick, with the preconditioner of its
    first solve (the problem's scaling hardly changes between ticks; recomputing it doubles the
    solve time). Solving again at the same tick (a graph with its cache off) repeats the tick's
    first solve exactly: the same guess, and a new preconditioner again if that one started
    cold, so ProxQP gives the same answer bit for bit. After a failure the next solve starts
    cold, with a new preconditioner (never from a failed iterate). ProxQP's proximal parameter
    is ``rho``. With ``same_inequalities`` the inequality rows and bounds are not handed over
    again (the caller knows they did not change since the last solve).
    """

    def __init__(self, n: int, n_eq: int, n_in: int, *, eps_abs: float, max_iterations: int, rho: float):
        self.qp = dense_qp(n, n_eq, n_in, eps_abs=eps_abs, max_iterations=max_iterations, rho=rho)
        self.initialised = False
        self.has_solution = False  # the latest buffers hold a solution
        self.latest = (np.zeros(n), np.zeros(n_eq), np.zeros(n_in))
        self.guess = (np.zeros(n), np.zeros(n_eq), np.zeros(n_in))
        self.guess_tick: int | None = None
        self.has_guess = False
        self.cold_tick: int | None = None  # the tick of the last init (a cold start)

    def _prepare_guess(self, tick: int | None, start: tuple[np.ndarray, ...] | None) -> None:
        """This tick's guess: ``start`` if given, else the latest solution of an earlier tick
        (the two sets of buffers swap: the new solution overwrites the older one)."""
        if start is not None:
            x, y, z = self.guess
            np.copyto(x, start[0])
            np.copyto(y, start[1])
            z[:len(start[2])] = start[2]  # rows the start does not have begin at 0
            z[len(start[2]):] = 0.0
            self.guess_tick, self.has_guess = tick, True
        elif tick is None or tick != self.guess_tick:
            self.guess_tick = tick
            self.has_guess = self.has_solution
            if self.has_solution:
                self.guess, self.latest = self.latest, self.guess

    def solve(self, problem: tuple[np.ndarray, ...], tick: int | None, start: tuple[np.ndarray, ...] | None = None,
              same_inequalities: bool = False) -> tuple[Status, int]:
        """ProxQP on ``problem`` = ``(H, g, A, b, C, lower, upper)``: ``(status, iterations)``; a
        solution lands in :attr:`latest`. ``start`` = ``(x, y, z)`` replaces the warm start (``z``
        may be shorter than this problem's: a solution without its last rows)."""
        self._prepare_guess(tick, start)
        qp = self.qp
        if not self.initialised or (tick is not None and tick == self.cold_tick):
            qp.init(*problem)
            self.initialised, self.cold_tick = True, tick
        elif same_inequalities:
            qp.update(*problem[:4], None, None, None, update_preconditioner=False)
        else:
            qp.update(*problem, update_preconditioner=False)
        if self.has_guess:
            qp.solve(*self.guess)
        else:
            qp.solve()
        results = qp.results
        status = proxqp_status(results)
        if status == SOLVED:
            x, y, z = self.latest
            np.copyto(x, results.x)  # ProxQP's arrays are views of its own memory
            np.copyto(y, results.y)
            np.copyto(z, results.z)
        self.has_solution = status == SOLVED
        if not self.has_solution:
            self.initialised = False
        return status, int(results.info.iter)
