"""Passivity: what a passive inverse-dynamics solve needs from an energy tank (thesis Eq. 5.34)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)
class Passivity:
    """The task scale ``beta gamma`` (Eq. 5.24), the bound ``H_dot`` on the storage rate (None:
    no passivity row) and the velocity ``v`` of the port: the QP keeps ``-v_j^T tau >= H_dot``
    (Eq. 5.26)."""

    scale: float
    power_bound: float | None
    velocity: np.ndarray

    def without_bound(self) -> Passivity:
        """The same scale without the passivity row (a relaxed solve)."""
        return Passivity(self.scale, None, self.velocity)
