"""ConstraintRows: the constraints of whole-body inverse dynamics over ``y = [a, f]``, for one set of active contacts.

Variables: the generalized accelerations ``a`` (nv, the first ``n_u`` of them unactuated: 6 for
a free-flyer base) and the force variables ``f_c`` of each active contact. Torques are not
variables: the actuated rows of the dynamics give them back (thesis Eq. 2.4),
``tau = M_j a + h_j - (J_c^T T)_j f``. The rows, laid out as TSID lays out its formulation
(each contact owns fixed columns of ``y`` and fixed rows):

```
A y = b:        M_u a - (J_c^T T)_u f = -h_u                   floating-base dynamics (n_u rows)
                J_c a = rhs_c                                   each contact's motion
l <= C y <= u:  l_c <= C_c f_c <= u_c                           each contact's friction and normal force
                (extra rows, left to the caller)                e.g. a passivity row
                -tau_max - h_j <= M_j a - (J_c^T T)_j f <= tau_max - h_j     torque limits (n_a rows, last)
```

The weighted QP (:mod:`~dgraph.control.inverse_dynamics.qp`) adds its cost to these rows; a
strict-priority solver takes them as its first level (:meth:`ConstraintRows.block`).
"""

from __future__ import annotations

import math
from collections.abc import Hashable

import numpy as np

from dgraph.control.contact import ContactConstraint
from dgraph.control.proxqp import INFINITY
from dgraph.control.rows import RowBlock


class ContactRows:
    """Where one active contact sits in the rows: its force columns, its motion rows, its
    friction rows, and views of them (made once)."""

    def __init__(self, rows: ConstraintRows, contact: ContactConstraint, column: int, row: int, friction_row: int):
        nv, n_unactuated = rows.nv, rows.n_unactuated
        k, m = contact.n_forces, len(contact.motion_rhs)
        columns, motion = slice(column, column + k), slice(row, row + m)
        self.columns = columns
        self.generalized = np.zeros((nv, k))  # -J^T T: the columns of the contact's forces in the dynamics
        self.base_part, self.joint_part = self.generalized[:n_unactuated], self.generalized[n_unactuated:]
        self.dynamics = rows.A[:n_unactuated, columns]
        self.torque = rows.torque_rows[:, columns]
        self.motion_matrix = rows.A[motion, :nv]
        self.motion_rhs = rows.b[motion]
        friction = slice(friction_row, friction_row + len(contact.friction_lower))
        self.friction, self.friction_lower, self.friction_upper = rows.C[friction, columns], rows.lower[friction], \
            rows.upper[friction]
        self.written: tuple[object, ...] = ()  # the constant arrays last written
        self.negated_generator = -contact.force_generator
        self.write_constant(contact)

    def write_constant(self, contact: ContactConstraint) -> None:
        """Friction rows and their bounds (constant: written again only when the contact hands
        over other arrays than last time)."""
        self.friction[...] = contact.friction_matrix
        self.friction_lower[...] = np.maximum(contact.friction_lower, -INFINITY)
        self.friction_upper[...] = np.minimum(contact.friction_upper, INFINITY)
        self.negated_generator = -contact.force_generator
        self.written = (contact.friction_matrix, contact.friction_lower, contact.friction_upper,
                        contact.force_generator)

    def write(self, contact: ContactConstraint) -> bool:
        """The contact's columns of the dynamics and torque rows, and its motion rows; True if
        its constant rows were written again."""
        written = self.written
        rewritten = (contact.friction_matrix is not written[0] or contact.friction_lower is not written[1]
                     or contact.friction_upper is not written[2] or contact.force_generator is not written[3])
        if rewritten:
            self.write_constant(contact)
        np.dot(contact.jacobian.T, self.negated_generator, out=self.generalized)
        self.dynamics[...] = self.base_part
        self.torque[...] = self.joint_part
        self.motion_matrix[...] = contact.jacobian
        self.motion_rhs[...] = contact.motion_rhs
        return rewritten


def _views(buffer: np.ndarray, shapes: tuple[tuple[int, ...], ...]) -> list[np.ndarray]:
    """Consecutive C-contiguous views of ``buffer`` with the given shapes."""
    views, start = [], 0
    for shape in shapes:
        size = math.prod(shape)
        views.append(buffer[start:start + size].reshape(shape))
        start += size
    return views


class ConstraintRows:
    """The rows of the module docstring for ``contacts``, with ``extra_rows`` caller rows before
    the torque rows, over a robot with ``nv`` velocities (the first ``n_unactuated`` unactuated)
    and torque limits ``effort_limit`` (n_a; ``inf``: none).

    ``A``, ``b``, ``C``, ``lower``, ``upper`` are the rows; ``torque_rows`` (the last ``n_a`` of
    ``C``, ``[M_j, -(J_c^T T)_j]``), ``torque_lower`` and ``torque_upper`` views of them; ``n`` the
    number of variables, ``n_free`` the rows of ``C`` before the torque rows. ``memory`` holds the
    arrays (:meth:`size` numbers; default: their own): a QP hands the tail of its buffer, so that
    one finiteness check covers its whole problem.
    """

    def __init__(self, nv: int, n_unactuated: int, effort_limit: np.ndarray, contacts: list[ContactConstraint],
                 extra_rows: int = 0, memory: np.ndarray | None = None):
        self.nv, self.n_unactuated = nv, n_unactuated
        self.effort_limit = effort_limit
        self._negative_limit = -effort_limit
        shapes = self.shapes(nv, n_unactuated, contacts, extra_rows)
        if memory is None:
            memory = np.zeros(sum(math.prod(shape) for shape in shapes))
        self.A, self.b, self.C, self.lower, self.upper = _views(memory, shapes)
        self.n = self.A.shape[1]
        self.n_free = sum(len(c.friction_lower) for c in contacts) + extra_rows
        self.torque_rows = self.C[self.n_free:]
        self.torque_lower, self.torque_upper = self.lower[self.n_free:], self.upper[self.n_free:]
        self.base_dynamics, self.base_rhs = self.A[:n_unactuated, :nv], self.b[:n_unactuated]
        self.torque_acceleration = self.torque_rows[:, :nv]
        column, row, friction_row = nv, n_unactuated, 0
        self.contacts: list[ContactRows] = []
        for contact in contacts:
            self.contacts.append(ContactRows(self, contact, column, row, friction_row))
            column, row = column + contact.n_forces, row + len(contact.motion_rhs)
            friction_row += len(contact.friction_lower)

    @staticmethod
    def key(contacts: list[ContactConstraint]) -> tuple[tuple[object, ...], ...]:
        """What decides the rows' layout: each contact's name and sizes (rows made for one key
        serve every tick with the same key)."""
        return tuple((c.name, c.n_forces, len(c.friction_lower), len(c.motion_rhs)) for c in contacts)

    @staticmethod
    def shapes(nv: int, n_unactuated: int, contacts: list[ContactConstraint],
               extra_rows: int = 0) -> tuple[tuple[int, ...], ...]:
        """The shapes of ``A``, ``b``, ``C``, ``lower``, ``upper``."""
        n = nv + sum(c.n_forces for c in contacts)
        n_eq = n_unactuated + sum(len(c.motion_rhs) for c in contacts)
        n_in = sum(len(c.friction_lower) for c in contacts) + extra_rows + nv - n_unactuated
        return (n_eq, n), (n_eq,), (n_in, n), (n_in,), (n_in,)

    @classmethod
    def size(cls, nv: int, n_unactuated: int, contacts: list[ContactConstraint], extra_rows: int = 0) -> int:
        """How many numbers the rows take (the length of ``memory``)."""
        return sum(math.prod(shape) for shape in cls.shapes(nv, n_unactuated, contacts, extra_rows))

    def write(self, mass_matrix: np.ndarray, bias_forces: np.ndarray, contacts: list[ContactConstraint]) -> bool:
        """The dynamics, torque and contact rows of this tick (the torque bounds apart:
        :meth:`write_torque_bounds`); True if a contact's constant rows were written again."""
        n_unactuated = self.n_unactuated
        # the dynamics (floating-base rows) and the torque rows share [M, -J_c^T T]
        self.base_dynamics[...] = mass_matrix[:n_unactuated]
        np.negative(bias_forces[:n_unactuated], out=self.base_rhs)
        self.torque_acceleration[...] = mass_matrix[n_unactuated:]
        rewritten = False
        for contact, rows in zip(contacts, self.contacts, strict=True):
            if rows.write(contact):
                rewritten = True
        return rewritten

    def write_torque_bounds(self, bias_forces: np.ndarray) -> None:
        """``tau_min - h_j <= (torque rows) y <= tau_max - h_j``, within ``+-INFINITY`` (ProxQP's
        "no bound": a model without a limit on a joint). ``h_j`` must be finite."""
        bias = bias_forces[self.n_unactuated:]
        np.subtract(self._negative_limit, bias, out=self.torque_lower)
        np.subtract(self.effort_limit, bias, out=self.torque_upper)
        np.clip(self.torque_lower, -INFINITY, INFINITY, out=self.torque_lower)
        np.clip(self.torque_upper, -INFINITY, INFINITY, out=self.torque_upper)

    def torques(self, y: np.ndarray, bias_forces: np.ndarray) -> np.ndarray:
        """``tau = (torque rows) y + h_j`` (the torque rows are ``[M_j, -(J_c^T T)_j]``, Eq. 2.4)."""
        tau = np.dot(self.torque_rows, y)
        tau += bias_forces[self.n_unactuated:]
        return tau

    def forces(self, y: np.ndarray) -> list[np.ndarray]:
        """Each contact's force variables in ``y`` (views)."""
        return [y[rows.columns] for rows in self.contacts]

    def block(self, key: Hashable = None) -> RowBlock:
        """The rows as one :class:`RowBlock` (views: valid until the next :meth:`write`)."""
        return RowBlock(self.A, self.b, self.C, self.lower, self.upper, key=key)
