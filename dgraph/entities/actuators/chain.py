"""The parameters of a rigid actuator chain (thesis Ch. 3, Eqs. 3.1-3.5) and its friction.

One joint's chain: a current-controlled brushless motor, a harmonic drive of ratio R, a joint
torque sensor and the link. With ``q`` the joint position (motor and link encoders taken as
equal, the drive being stiff):

* motor side (Eq. 3.1): ``tau_m = (I_m + I_j) q_ddot + g (M_Y sin q + M_X cos q) + tau_fm + tau_fj``
* joint side: ``tau_j = I_j q_ddot + g (M_Y sin q + M_X cos q) + tau_fj``
* friction (Eq. 3.2): ``tau_fm = F_vm q_dot + F_sm sign(q_dot) + off_m`` and the same with ``j``
* current to torque (Eq. 3.3): ``tau_m = R K_m i_m``; sensor (Eq. 3.4): ``tau_j = K_j tau_js``

so the torque the chain delivers to the joint is ``tau_m - I_m q_ddot - tau_fm``: the motor's
torque less what the rotor's inertia and the motor-side friction take. ``M_X``, ``M_Y`` and
``I_j`` describe the link (the rigid-body model has them); the chain's own parameters are the
motor side's, the joint side's friction, ``R K_m`` and ``K_j``.

:data:`TALOS_ELBOW` holds the thesis's identified values (Table 3.1, joint-level SI units).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np


@dataclass(frozen=True)
class ChainParameters:
    """One joint's chain (thesis Table 3.1 names; SI units at the joint: kg m, kg m², N m, N m s/rad)."""

    M_X: float = 0.0
    """first moment of the link along X (kg m): gravity torque ``g M_X cos q``"""
    M_Y: float = 0.0
    """first moment of the link along Y (kg m): gravity torque ``g M_Y sin q``"""
    I_j: float = 0.0
    """link inertia about the joint axis (kg m²)"""
    I_m: float = 0.0
    """rotor inertia reflected at the joint (kg m²): MuJoCo's joint armature"""
    F_vm: float = 0.0
    """motor-side viscous friction (N m s/rad)"""
    F_sm: float = 0.0
    """motor-side dry (Coulomb) friction (N m)"""
    off_m: float = 0.0
    """motor-side torque offset (N m)"""
    F_vj: float = 0.0
    """joint-side viscous friction (N m s/rad)"""
    F_sj: float = 0.0
    """joint-side dry friction (N m)"""
    off_j: float = 0.0
    """joint-side torque offset (N m)"""
    R_Km: float = 1.0
    """gear ratio times the drive's current-to-torque gain (N m/A, Eq. 3.3)"""
    K_j: float = 1.0
    """joint torque sensor gain (Eq. 3.4)"""
    i_max: float = float("inf")
    """motor current limit (A)"""

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The parameter names, in declaration order."""
        return tuple(f.name for f in fields(cls))

    @property
    def F_v(self) -> float:
        """Total viscous friction ``F_vm + F_vj`` (Eq. 3.5)."""
        return self.F_vm + self.F_vj

    @property
    def F_s(self) -> float:
        """Total dry friction ``F_sm + F_sj`` (Eq. 3.5)."""
        return self.F_sm + self.F_sj


def friction(viscous: float, dry: float, offset: float, velocity: np.ndarray | float,
             smoothing: float | None = None) -> np.ndarray:
    """``F_v q_dot + F_s sign(q_dot) + off`` (Eq. 3.2); with ``smoothing`` = mu, ``sign`` is
    ``tanh(mu q_dot)`` (Eq. 3.18, mu = 1000 in the thesis's MPC)."""
    velocity = np.asarray(velocity, dtype=float)
    sign = np.sign(velocity) if smoothing is None else np.tanh(smoothing * velocity)
    return viscous * velocity + dry * sign + offset


TALOS_ELBOW = ChainParameters(M_X=-0.11, M_Y=1.1, I_j=0.33, I_m=0.45, F_vm=5.1, F_sm=4.0, off_m=0.86,
                              F_vj=0.47, F_sj=0.55, off_j=-0.27, K_j=1.015, i_max=6.0)
"""TALOS's elbow, thesis Table 3.1 (identified column), ``K_j`` = 1.015 and the 6 A a-priori
current limit (§3.5.3). ``R K_m`` is not disclosed (the identified value differs from the
manufacturer's by 16 %): it stays 1 here and is set where it is known."""
