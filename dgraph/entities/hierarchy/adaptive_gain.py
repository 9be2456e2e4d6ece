"""The adaptive gain of SoT velocity tasks: high near the goal, lower far from it."""

from __future__ import annotations

import math


def adaptive_gain(error_norm: float, at_zero: float, at_infinity: float, slope_at_zero: float) -> float:
    """``lambda(e) = (l0 - linf) exp(-l0' / (l0 - linf) ||e||) + linf`` (SoT's GainAdaptive).

    ``lambda(0) = l0`` (``at_zero``), ``lambda -> linf`` (``at_infinity``) as ``||e||`` grows,
    and ``d lambda / d||e|| = -l0'`` at 0 (``slope_at_zero``). With ``l0 = linf`` it is the
    constant ``l0``. Requires ``l0 >= linf >= 0`` and ``l0' >= 0``.
    """
    span = at_zero - at_infinity
    if span <= 0.0:
        return at_zero
    return span * math.exp(-slope_at_zero / span * error_norm) + at_infinity
