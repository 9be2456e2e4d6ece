"""ContactConstraint: what a contact contributes to an inverse-dynamics QP at one tick."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class ContactConstraint:
    """A contact's rows for the solver (``k`` force variables, ``nv`` accelerations).

    - motion: ``jacobian a = motion_rhs`` (m x nv: 6 for a plane contact's body twist, 3 for a
      point);
    - forces: ``f`` (k) produce the contact wrench ``force_generator f`` (6, contact frame),
      hence the generalized force ``jacobian^T force_generator f``;
    - friction and normal-force bounds: ``friction_lower <= friction_matrix f <= friction_upper``;
    - ``force_weight``: the cost ``force_weight ||f - force_reference||_M^2`` (``force_reference``
      None: 0, a regularisation; a force task sets it, thesis Eq. 4.12), in the metric
      ``force_metric`` (``M``, k x k, symmetric positive definite; None: the identity);
    - ``rotation``: the contact frame's orientation in the world (to report world wrenches);
    - ``error``: the contact's placement error that ``motion_rhs`` corrects.
    """

    name: str
    active: bool
    jacobian: np.ndarray
    motion_rhs: np.ndarray
    force_generator: np.ndarray
    friction_matrix: np.ndarray
    friction_lower: np.ndarray
    friction_upper: np.ndarray
    force_weight: float
    rotation: np.ndarray
    error: np.ndarray
    force_reference: np.ndarray | None = None
    force_metric: np.ndarray | None = None

    @property
    def n_forces(self) -> int:
        """Number of force variables."""
        return self.force_generator.shape[1]

    def metric(self) -> np.ndarray:
        """``M``, the metric of the force cost (the identity when ``force_metric`` is None)."""
        return np.eye(self.n_forces) if self.force_metric is None else self.force_metric

    def world_wrench(self, forces: np.ndarray) -> np.ndarray:
        """The contact wrench ``[force, torque]`` at the contact frame origin, world axes (a point
        contact, whose generator gives a force only, has no torque)."""
        wrench = np.dot(self.force_generator, forces)
        if len(wrench) != 6:
            return np.concatenate([np.dot(self.rotation, wrench), np.zeros(3)])
        return np.dot(wrench.reshape(2, 3), self.rotation.T).reshape(6)  # rows R f, R tau
