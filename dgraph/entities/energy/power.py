"""Task storage and tank powers of thesis Ch. 5 (Eqs. 5.5, 5.10, 5.11, 5.18, 5.19), as pure functions.

A *task block* holds what a motion task knows at one tick: ``E = x (-) x*``, ``E_dot``,
``X_dot = J v``, ``X_ddot*``, ``J_dot v``, the gains and the Jacobian. From it and the mass
matrix, with ``Lambda = (J M^-1 J^T)^+`` (Eq. 5.5; for a stacked, skinny ``J`` this equals
``J^+T M J^+``, Eq. 5.10) and ``P = Lambda K_P``:

```
S      = 1/2 E^T P E = 1/2 E^T P_s E                                   storage (Eq. 5.11)
S_dot  = E_dot^T P_s E + 1/2 E^T P_dot E                                its rate
B_sig  = X_dot^T Lambda K_D E_dot + X_dot*^T P E - 1/2 E^T P_dot E
         + E_dot^T (P - P_s) E - X_dot^T Lambda (X_ddot* - J_dot v)    controllable power (Eq. 5.18)
```

``X_dot* = X_dot - E_dot`` and ``P_s = (P + P^T) / 2``, the symmetric part of ``P``, the only
part a quadratic form sees (thesis App. 5, Eqs. 6.7-6.8). With equal gains within a task
(``K_P = k I``, Table 5.2) ``P = P_s`` and these are the thesis's formulas. With unequal gains
(a posture task's per-joint ``K_P``, errata E4) the thesis's ``S_dot = E_dot^T P E + ...`` is
not the derivative of ``S``: on the 20 cm walk its posture term integrated to 6.1 J over 4 s
while ``S`` changed by 0.7 J, a drain of the tank by a storage that never grew. Here ``S_dot``
is the exact rate and the skew remainder ``E_dot^T (P - P_s) E`` is counted in ``B_sig``, so
``S_dot + B_sig``, the power that the passivity bound uses, is unchanged. The uncontrollable power (Eq. 5.19) is
``B_phi = v^T (C v + g) - sum_k v^T J_k^T T_k f_k`` (:func:`uncontrollable_power`). With
``a = J^+ beta gamma (X_ddot* - J_dot v - K_P E - K_D E_dot)`` these satisfy the balance
Eq. 5.25, ``-v^T (M a + h - tau_ext) = beta gamma (S_dot + B_sig) - B_phi``, which
``tests/entities/energy/test_power.py`` checks.

``P_dot`` is the finite difference of ``P`` over one tick (errata E18).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

PINV_TOLERANCE = 1e-9
"""Eigenvalues of ``J M^-1 J^T`` below this fraction of the largest are treated as zero."""


@dataclass(slots=True)
class TaskBlock:
    """One motion task (or a stack of them) at one tick; vectors have the task's ``m`` rows."""

    error: np.ndarray                   # E = x (-) x*
    error_velocity: np.ndarray          # E_dot = X_dot - X_dot*
    velocity: np.ndarray                # X_dot = J v
    reference_acceleration: np.ndarray  # X_ddot*
    drift: np.ndarray                   # J_dot v
    kp: np.ndarray                      # diagonal of K_P
    kd: np.ndarray                      # diagonal of K_D
    jacobian: np.ndarray                # J (m x nv)

    @property
    def reference_velocity(self) -> np.ndarray:
        """``X_dot* = X_dot - E_dot``."""
        return self.velocity - self.error_velocity


@dataclass(slots=True)
class TaskPower:
    """Storage ``S``, its rate ``S_dot`` and the controllable power ``B_sigma`` of a block."""

    storage: float
    storage_rate: float
    controllable_power: float


def stack(blocks: Sequence[TaskBlock]) -> TaskBlock:
    """The blocks stacked into one (Eq. 5.8: ``X``, ``J``, ``K_P``, ``K_D`` stacked)."""
    fields = TaskBlock.__slots__
    parts = {name: [getattr(b, name) for b in blocks] for name in fields}
    return TaskBlock(**{name: (np.vstack(v) if name == "jacobian" else np.concatenate(v)) for name, v in parts.items()})


def _pseudo_inverse(symmetric: np.ndarray) -> np.ndarray:
    """Moore-Penrose inverse of a symmetric PSD matrix (eigen-decomposition; the rare path)."""
    values, vectors = np.linalg.eigh(0.5 * (symmetric + symmetric.T))
    keep = values > PINV_TOLERANCE * max(values[-1], 0.0) if len(values) else values > 0
    kept = vectors[:, keep]
    return (kept / values[keep]) @ kept.T


def _well_conditioned(symmetric: np.ndarray) -> bool:
    """True when ``symmetric`` is positive definite with a Cholesky factor of bounded ratio."""
    try:
        diagonal = np.diag(np.linalg.cholesky(symmetric))
    except np.linalg.LinAlgError:
        return False
    return bool(diagonal.min() ** 2 > PINV_TOLERANCE * diagonal.max() ** 2)


def _inverse(symmetric: np.ndarray) -> np.ndarray:
    """The inverse of a symmetric PSD matrix, or its pseudo-inverse when it is singular or its
    condition number (estimated as ``||A|| ||A^-1||``, infinity norms) passes ``1 / PINV_TOLERANCE``."""
    try:
        inverse = np.linalg.inv(symmetric)
    except np.linalg.LinAlgError:
        return _pseudo_inverse(symmetric)
    condition = np.abs(symmetric).sum(axis=1).max() * np.abs(inverse).sum(axis=1).max()
    if not condition * PINV_TOLERANCE < 1.0:  # also catches NaN and inf
        return _pseudo_inverse(symmetric)
    return inverse


def task_space_inertia(jacobian: np.ndarray, mass_matrix: np.ndarray, mass_matrix_inverse: np.ndarray) -> np.ndarray:
    """``Lambda = (J M^-1 J^T)^+`` (Eq. 5.5).

    A fat ``J`` of full row rank (one task) gives the plain inverse; a skinny ``J`` of full column
    rank (stacked tasks) gives ``J^+T M J^+`` with ``J^+ = (J^T J)^-1 J^T`` (Eqs. 5.9-5.10); the
    rank-deficient cases fall back to an eigen-decomposition (slow with a multithreaded BLAS).
    """
    rows, cols = jacobian.shape
    if rows <= cols:
        return _inverse(jacobian @ mass_matrix_inverse @ jacobian.T)
    gram = jacobian.T @ jacobian
    if _well_conditioned(gram):
        j_pinv = np.linalg.solve(gram, jacobian.T)
        return j_pinv.T @ mass_matrix @ j_pinv
    return _pseudo_inverse(jacobian @ mass_matrix_inverse @ jacobian.T)


def task_power(block: TaskBlock, inertia: np.ndarray, stiffness_rate: np.ndarray) -> TaskPower:
    """``S``, ``S_dot`` and ``B_sigma`` of a block, given ``Lambda`` and ``P_dot`` (module docstring)."""
    e, e_dot, x_dot = block.error, block.error_velocity, block.velocity
    stiffness_e = inertia @ (block.kp * e)                      # P e = Lambda K_P e
    symmetric_e = 0.5 * (stiffness_e + block.kp * (inertia.T @ e))  # P_s e = (P + P^T) e / 2
    rate_term = 0.5 * float(e @ stiffness_rate @ e)              # 1/2 E^T P_dot E
    storage = 0.5 * float(e @ stiffness_e)
    storage_rate = float(e_dot @ symmetric_e) + rate_term
    skew_power = float(e_dot @ (stiffness_e - symmetric_e))     # E_dot^T (P - P_s) E
    controllable = (float(x_dot @ inertia @ (block.kd * e_dot)) + float(block.reference_velocity @ stiffness_e)
                    - rate_term + skew_power - float(x_dot @ inertia @ (block.reference_acceleration - block.drift)))
    return TaskPower(storage, storage_rate, controllable)


def stiffness(block: TaskBlock, inertia: np.ndarray) -> np.ndarray:
    """``P = Lambda K_P`` (the matrix whose rate ``P_dot`` enters ``S_dot`` and ``B_sigma``)."""
    return inertia * block.kp


def uncontrollable_power(velocity: np.ndarray, bias_forces: np.ndarray, contact_power: float) -> float:
    """``B_phi = v^T (C v + g) - sum_k (J_k v)^T (T_k f_k)`` (Eq. 5.19); ``contact_power`` is the sum."""
    return float(velocity @ bias_forces) - contact_power
