"""Rotation logarithms in Python floats, for the 3 x 3 matrices of one frame at one tick.

A numpy or Pinocchio call costs about a microsecond in a control tick whatever its size (its code
is cold after the simulator's step), so ``log3(A B)`` of two 3 x 3 rotations is cheaper as 27
products and 18 sums in Python than as a matrix product and ``pin.log3``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

Rows = Sequence[Sequence[float]]
"""A 3 x 3 matrix as three rows of three floats (``array.tolist()``)."""

_NEAR_PI = -0.5
"""Below this ``cos(theta)`` (beyond 120°) the axis is taken from Pinocchio's ``log3``, which
reads it from the diagonal near ``theta = pi``, where ``R - R^T`` vanishes."""


def log3_product(a: Rows, b: Rows) -> tuple[float, float, float]:
    """``log3(A B)``: the rotation vector ``theta u`` of the rotation ``M = A B``.

    With ``vee(M - M^T) = 2 sin(theta) u`` and ``trace(M) = 1 + 2 cos(theta)``:
    ``theta = atan2(sin, cos)`` and ``log3(M) = theta / (2 sin(theta)) vee(M - M^T)``, which is
    exact at small angles (no ``acos`` near 1); Pinocchio's ``log3`` gives the same to rounding.
    """
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = b
    m00 = a00 * b00 + a01 * b10 + a02 * b20
    m01 = a00 * b01 + a01 * b11 + a02 * b21
    m02 = a00 * b02 + a01 * b12 + a02 * b22
    m10 = a10 * b00 + a11 * b10 + a12 * b20
    m11 = a10 * b01 + a11 * b11 + a12 * b21
    m12 = a10 * b02 + a11 * b12 + a12 * b22
    m20 = a20 * b00 + a21 * b10 + a22 * b20
    m21 = a20 * b01 + a21 * b11 + a22 * b21
    m22 = a20 * b02 + a21 * b12 + a22 * b22
    cos = 0.5 * (m00 + m11 + m22 - 1.0)
    if cos < _NEAR_PI:
        x, y, z = pin.log3(np.array([[m00, m01, m02], [m10, m11, m12], [m20, m21, m22]])).tolist()
        return x, y, z
    x, y, z = m21 - m12, m02 - m20, m10 - m01
    sin = 0.5 * math.sqrt(x * x + y * y + z * z)
    scale = 0.5 * math.atan2(sin, cos) / sin if sin > 0.0 else 0.5
    return scale * x, scale * y, scale * z
