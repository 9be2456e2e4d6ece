"""The contact wrench cone of a rectangular sole: every wrench that four corner forces, each in
its friction pyramid, can exert, written as 16 rows on the 6D wrench.

A sole whose corners push with forces ``f_i`` inside the four-face pyramids
``|f_x|, |f_y| <= mu f_z`` exerts the wrench ``w = T f`` (thesis Eq. 4.11). The set of those
wrenches is a polyhedral cone; for a rectangle of half-length ``X`` and half-width ``Y``,
with the wrench taken at the rectangle's centre, its faces are (Caron, Pham and Nakamura,
"Stability of surface contacts for humanoid robots: closed-form formulae of the contact
wrench cone for rectangular support areas", ICRA 2015):

```
|f_x| <= mu f_z,   |f_y| <= mu f_z                       friction (thesis Eq. 2.11, linearised)
|tau_x| <= Y f_z,  |tau_y| <= X f_z                      centre of pressure in the sole (Eq. 2.13-2.15)
tau_z >= -mu (X + Y) f_z + |Y f_x - mu tau_x| + |X f_y - mu tau_y|     yaw torque
tau_z <=  mu (X + Y) f_z - |Y f_x + mu tau_x| - |X f_y + mu tau_y|
```

(each absolute value unfolds into two rows: 4 + 4 + 8 = 16). With these rows on the wrench, a
contact needs 6 force variables instead of 12 and the QP has the same feasible wrenches
(``tests/entities/test_wrench_cone.py`` checks the equivalence with a linear program).
:func:`corner_force_metric` gives the cost that makes the two parametrisations choose the
same wrenches: ``w^T M w`` is the least ``||f||^2`` over the corner forces with ``T f = w``.
"""

from __future__ import annotations

import numpy as np


def wrench_cone(front: float, back: float, half_width: float, mu: float) -> np.ndarray:
    """Rows ``U`` (16 x 6) with ``U w <= 0`` exactly for the wrenches ``w = [f, tau]`` (at the
    contact frame's origin, contact axes) of corner forces in the pyramids ``|f_x|, |f_y| <=
    mu f_z`` at the corners of the sole ``x in [-back, front]``, ``y in [-half_width,
    half_width]``, ``z = 0``."""
    half_length, centre = 0.5 * (front + back), 0.5 * (front - back)
    x, y = half_length, half_width
    rows = [[1.0, 0.0, -mu, 0.0, 0.0, 0.0], [-1.0, 0.0, -mu, 0.0, 0.0, 0.0],
            [0.0, 1.0, -mu, 0.0, 0.0, 0.0], [0.0, -1.0, -mu, 0.0, 0.0, 0.0],
            [0.0, 0.0, -y, 1.0, 0.0, 0.0], [0.0, 0.0, -y, -1.0, 0.0, 0.0],
            [0.0, 0.0, -x, 0.0, 1.0, 0.0], [0.0, 0.0, -x, 0.0, -1.0, 0.0]]
    yaw_reach = -mu * (x + y)
    for sx in (1.0, -1.0):
        for sy in (1.0, -1.0):
            # s_x (Y f_x - mu tau_x) + s_y (X f_y - mu tau_y) - mu (X + Y) f_z - tau_z <= 0
            rows.append([sx * y, sy * x, yaw_reach, -sx * mu, -sy * mu, -1.0])
            # s_x (Y f_x + mu tau_x) + s_y (X f_y + mu tau_y) - mu (X + Y) f_z + tau_z <= 0
            rows.append([sx * y, sy * x, yaw_reach, sx * mu, sy * mu, 1.0])
    at_centre = np.array(rows)
    # the torque about the centre c = (centre, 0, 0): tau_c = tau - c x f
    shift = np.eye(6)
    shift[3:, :3] = -np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -centre], [0.0, centre, 0.0]])
    return at_centre @ shift


def corner_force_metric(generator: np.ndarray) -> np.ndarray:
    """``M = (T T^T)^-1`` (6 x 6) for a corner-force generator ``T`` (6 x 3n, full rank):
    ``w^T M w = min ||f||^2`` subject to ``T f = w``."""
    return np.linalg.inv(generator @ generator.T)
