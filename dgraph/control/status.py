"""Status: how a solve ended, one code shared by every solver (the QP, the cascade, and the next ones).

A solver never raises on a numerical failure: it returns one of these codes and its caller
chooses a fallback (the torque solvers' gravity compensation, the inverse kinematics' last
feasible velocity). The codes are integers, so a ``status`` output records as a number.
"""

from __future__ import annotations

from enum import IntEnum


class Status(IntEnum):
    """The outcome of a solve (0 is success)."""

    SOLVED = 0
    MAX_ITERATIONS = 1
    """The iteration limit was reached before the tolerance."""
    PRIMAL_INFEASIBLE = 2
    """No point satisfies the constraints (or the solver says so)."""
    DUAL_INFEASIBLE = 3
    """The cost is unbounded below on the constraints."""
    NOT_FINITE = 4
    """The problem data, or the answer, has a NaN or an infinity (or crossed bounds ``l > u``)."""
    NOT_SOLVED = 5
    """Any other failure."""


SOLVED, MAX_ITERATIONS, PRIMAL_INFEASIBLE, DUAL_INFEASIBLE, NOT_FINITE, NOT_SOLVED = Status
