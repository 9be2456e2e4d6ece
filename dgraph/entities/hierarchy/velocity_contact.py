"""VelocityContact: a sole contact held at velocity level, ``J_c v = -lambda e``, for a priority stack."""

from __future__ import annotations

import dgraph as dg
from dgraph.control.rows import RowBlock
from dgraph.entities.contacts.contact6d import Contact6d


@dg.register
class VelocityContact(Contact6d):
    """A contact of the inverse-kinematics stack (thesis Eq. 4.3): the contact frame keeps its
    anchored placement, ``x_c^{i+1} = x_c^i``, i.e. ``J_c v = 0``, here with an optional
    correction of the placement error: ``J_c v = -kp e``.

    ``J_c`` is the frame's Jacobian in its local frame (body twist) and
    ``e = [R^T (p - p_a), log3(R_a^T R)]`` the error against the anchor ``(p_a, R_a)``, the
    placement at the first active tick, exactly as in :class:`Contact6d` (which this extends:
    same parameters, ``anchor`` state, ``active`` input and commands). At velocity level ``kp``
    is the gain ``lambda`` (1/s; 0: ``J_c v = 0``, the thesis's form) and ``kd`` is not used; the
    ``contact`` output remains that of a Contact6d with these gains.

    Parameters, inputs and state: those of :class:`~dgraph.entities.contacts.Contact6d`
    (``robot``, ``kp`` as ``lambda``, ``kd`` unused here, ``active``; ``anchor``).
    Outputs: those of Contact6d, and ``rows`` (:class:`~dgraph.control.rows.RowBlock`, 6
    equalities over ``v``, none while inactive).
    """

    @dg.output(dtype=RowBlock, depends=("contact",))
    def rows(self, t: int) -> RowBlock:
        """``J_c v = -kp e`` (no row while inactive)."""
        contact = self.contact(t)
        gain = self._gains.vector("kp", 6, t)
        return RowBlock.equalities(contact.jacobian, -gain * contact.error, contact.active)
