"""FeatureValue: a task-space quantity at one tick (error, its rate, Jacobian, drift, reference acceleration)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.signals.value_types import value_type


@value_type
@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class FeatureValue:
    """What a task needs from a feature at one tick (``m`` rows, ``nv`` columns).

    ``x_dot = J v`` and ``x_ddot = J a + drift``; ``error = x (-) x*`` (a Lie-group difference
    where ``x`` lives on a group), ``error_velocity = x_dot - x_dot*``, and
    ``reference_acceleration = x_ddot*``.

    ``is_rate`` marks a feature that is already a rate (angular momentum): its ``error`` is a
    velocity error, regulated by ``kp`` alone (the energy tank stores no energy for it).
    """

    error: np.ndarray
    error_velocity: np.ndarray
    jacobian: np.ndarray
    drift: np.ndarray
    reference_acceleration: np.ndarray
    is_rate: bool = False

    def select(self, rows: np.ndarray | slice | None) -> FeatureValue:
        """The same feature restricted to ``rows`` (``None``: all; a slice gives views)."""
        if rows is None:
            return self
        return FeatureValue(self.error[rows], self.error_velocity[rows], self.jacobian[rows],
                            self.drift[rows], self.reference_acceleration[rows], self.is_rate)
