"""What the solvers return: QPSolution (accelerations, torques, contact forces) and CascadeSolution (a stack's x)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from dgraph.control.contact import ContactConstraint
from dgraph.control.rows import RowBlock
from dgraph.control.status import Status
from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)
class QPSolution:
    """An inverse-dynamics answer at one tick: ``acceleration`` (nv), ``tau`` (the actuated
    torques), ``forces`` (one array per active contact, in the order of ``contacts``).

    ``status`` is a :class:`~dgraph.control.status.Status`; when it is not ``SOLVED`` the
    solver puts its fallback in ``tau`` (the QP itself leaves None) and ``acceleration`` /
    ``forces`` are zeros. ``iterations`` and ``solve_time`` (s) add up every solve of the tick.
    ``contact_rows`` says which declared contact each active one is; ``torque_limited``: the
    torque limits bound the answer (a second solve with them); ``passivity_relaxed``: the
    passive problem was solved again without its passivity row.
    """

    acceleration: np.ndarray
    tau: np.ndarray | None
    forces: list[np.ndarray]
    status: Status
    iterations: int
    solve_time: float
    contacts: list[ContactConstraint] = field(default_factory=list)
    contact_rows: list[int] = field(default_factory=list)
    passivity_relaxed: bool = False
    torque_limited: bool = False

    def world_wrenches(self, n_contacts: int) -> np.ndarray:
        """One ``[force, torque]`` row per declared contact (``n_contacts``), world axes at the
        contact frame (:meth:`ContactConstraint.world_wrench`); zeros for an inactive one."""
        wrenches = np.zeros((n_contacts, 6))
        for row, contact, forces in zip(self.contact_rows, self.contacts, self.forces, strict=True):
            wrenches[row] = contact.world_wrench(forces)
        return wrenches


@value_type
@dataclass(slots=True)
class CascadeSolution:
    """A lexicographic cascade's answer: ``x``, ``status`` (``NOT_FINITE`` also for crossed
    bounds ``l > u``; ``x`` is zeros for non-finite data, and after a failed level the answer
    of the levels above it), ``iterations`` (ProxQP, summed), ``qp_levels`` (levels that needed
    ProxQP), ``solve_time`` (s), and the ``levels`` it was given (an empty one has no rows)."""

    x: np.ndarray
    status: Status
    iterations: int
    qp_levels: int
    solve_time: float
    levels: Sequence[RowBlock]

    @property
    def residuals(self) -> np.ndarray:
        """One per level, :meth:`RowBlock.residual` at ``x`` (0 for an empty level, inf for an
        invalid one); computed on request (the solve itself does not need them)."""
        return np.array([level.residual(self.x) if level.is_valid() else math.inf for level in self.levels])
