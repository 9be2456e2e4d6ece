"""Rotations in Python floats (logarithms, quaternions, cross products), for the 3-vectors and
3 x 3 matrices of one frame at one tick.

A numpy or Pinocchio call costs about a microsecond in a control tick whatever its size (its code
is cold after the simulator's step), so ``log3(A B)`` of two 3 x 3 rotations is cheaper as 27
products and 18 sums in Python than as a matrix product and ``pin.log3``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

MatrixRows = Sequence[Sequence[float]]
"""A 3 x 3 matrix as three rows of three floats (``array.tolist()``)."""

_NEAR_PI = -0.5
"""Below this ``cos(theta)`` (beyond 120°) the axis is taken from Pinocchio's ``log3``, which
reads it from the diagonal near ``theta = pi``, where ``R - R^T`` vanishes."""


def log3_product(a: MatrixRows, b: MatrixRows) -> tuple[float, float, float]:
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


def quat_to_rows(q: Sequence[float]) -> list[list[float]]:
    """Rows of the rotation matrix of a quaternion ``[x, y, z, w]`` (normalised here), in Python floats.

    With ``(x, y, z, w)`` of unit norm: ``R = I + 2 w [u]x + 2 [u]x^2``, ``u = (x, y, z)``, i.e.
    ``R_00 = 1 - 2 (y^2 + z^2)``, ``R_01 = 2 (x y - z w)``, ... (Eigen's expression order).
    """
    x, y, z, w = q
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz, txx, txy, txz, tyy, tyz, tzz = tx * w, ty * w, tz * w, tx * x, ty * x, tz * x, ty * y, tz * y, tz * z
    return [[1.0 - (tyy + tzz), txy - twz, txz + twy],
            [txy + twz, 1.0 - (txx + tzz), tyz - twx],
            [txz - twy, tyz + twx, 1.0 - (txx + tyy)]]


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (an array) of a quaternion ``[x, y, z, w]`` (normalised here)."""
    return np.array(quat_to_rows(np.asarray(q, dtype=float).tolist()))


def matrix_to_quat(r: Any) -> list[float]:
    """Quaternion ``[x, y, z, w]`` (``w >= 0``) of a rotation matrix (Shepperd's method).

    ``r`` is an array or nested rows; Python floats throughout (a few dozen operations, cheaper
    than as many numpy calls on 3-vectors).
    """
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = r.tolist() if isinstance(r, np.ndarray) else r
    trace = r00 + r11 + r22
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = ((r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s, 0.25 * s)
    elif r00 > r11 and r00 > r22:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        q = (0.25 * s, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s)
    elif r11 > r22:
        s = 2.0 * math.sqrt(1.0 + r11 - r00 - r22)
        q = ((r01 + r10) / s, 0.25 * s, (r12 + r21) / s, (r02 - r20) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r22 - r00 - r11)
        q = ((r02 + r20) / s, (r12 + r21) / s, 0.25 * s, (r10 - r01) / s)
    x, y, z, w = q
    scale = (-1.0 if w < 0 else 1.0) / math.sqrt(x * x + y * y + z * z + w * w)
    return [x * scale, y * scale, z * scale, w * scale]


def cross(a: Sequence[float], b: Sequence[float]) -> list[float]:
    """``a × b`` of 3-vectors in Python floats (``np.cross`` costs tens of µs on 3-vectors)."""
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
