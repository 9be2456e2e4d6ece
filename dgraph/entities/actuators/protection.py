"""Torque protection: the thesis's per-joint iLQR MPC with exponential barriers (Eqs. 3.13-3.31).

One joint's state is ``x = [q, q_dot]`` and its input the motor current ``u = i_m`` (Eq. 3.13).
The dynamics are the chain's (Eq. 3.5) with ``sign`` smoothed as ``tanh(mu q_dot)``, mu = 1000
(Eq. 3.18)::

    I q_ddot = R K_m i_m - F_v q_dot - F_s tanh(mu q_dot) - off - g (M_Y sin q + M_X cos q)

with ``I = I_j + I_m``, ``F_v = F_vm + F_vj``, ``F_s = F_sm + F_sj``, ``off = off_m + off_j``.

**Discretisation** (the thesis does not give one): at the knot step ``h``, a semi-implicit Euler
step whose velocity update is *linearly implicit* (one Newton step of backward Euler in
``q_dot``), then the position with the new velocity::

    q_dot+ = q_dot + h a(q, q_dot, u) / (1 - h da/dq_dot),     q+ = q + h q_dot+

The smoothed dry friction has ``da/dq_dot`` down to ``-(F_v + mu F_s) / I`` = -5800 /s on the
elbow, so explicit Euler at 3 ms would diverge near ``q_dot = 0``; the implicit velocity keeps
the step stable and, at rest, lets the friction hold the joint as the model says.
``f_u`` and ``f_x`` of this step are analytic (the thesis takes ``f_x`` by central finite
differences, Eqs. 3.20-3.21); ``tests/entities/actuators/test_protection.py`` checks them
against finite differences.

**Cost** per knot (Eqs. 3.22-3.23; the last knot has the state terms only)::

    l = (x - x*)^T Q (x - x*) + R u^2 + S rho(u - u*) + C_s(x)^T W C_s(x) + P C_s(tau_m)^2

with ``rho(e) = 2 delta^2 (sqrt(1 + (e/delta)^2) - 1)``, a pseudo-Huber: ``e^2`` for ``|e| << delta``,
its slope bounded by ``2 delta``.

with the exponential barrier (Eq. 3.14) ``C_s(c) = exp(lam [1 - lam (c_max - c)]) +
exp(lam [1 - lam (c - c_min)])``, ``dC_s/dc = lam^2 (e^(lam max) - e^(lam min))`` and
``d2C_s/dc2 = lam^4 C_s`` (Eqs. 3.26-3.27, 3.30-3.31), on ``q``, ``q_dot`` and
``tau_m = R K_m u`` (chain rule through ``R K_m``). The Hessian of ``W C_s^2`` is
``2 W (C_s C_s'' + C_s'^2)``; Eqs. 3.24-3.25 print ``W`` where ``P`` belongs on the ``tau_m``
barrier, and Eq. 3.29 drops ``W`` from its first term; both are read as the derivatives of
Eq. 3.22. Defaults are the thesis's: Q = diag(40, 0.01), R = 1e-4, W = diag(1, 0.1), P = 10,
lam(q) = 10, lam(q_dot) = 1, lam(tau_m) = 0.5.

**What is tracked.** The thesis tracks a position trajectory ``x*``. The entity receives the
commanded *joint torque* ``tau_j*`` instead, and turns it into a reference: the current that
delivers it, ``u* = (tau_j* + I_m q_ddot* + tau_fm(q_dot)) / (R K_m)`` with the link's
acceleration ``q_ddot* = (tau_j* - g(...) - tau_fj(q_dot)) / I_j`` (Eq. 3.1 split into its motor
and joint sides), and ``x*`` the model's trajectory under ``u*`` held over the horizon. Without
barriers the optimum is then ``u = u*``, ``x = x*``: the filter is transparent. The term
``S rho(u - u*)`` (``torque_weight`` S, ``torque_scale`` delta; not in the thesis) is needed
because over a 15 ms horizon a current hardly moves the position (about 4.3e-4 rad per A on the
elbow at R K_m = 2.977 N m/A), so ``Q`` alone gives the torque no weight against the barriers,
whose interior slope would pull the current to zero. It is a pseudo-Huber rather than a square
because the barrier is soft: a square's pull grows with the demand (an outer loop that has lost
tracking asks 100 A or more); the bounded pull ``2 S delta`` (30 A^-1 with S = 50, delta = 0.3 A)
meets the barrier's slope (``2 P e lam^2 R K_m`` at the limit, 40.5 A^-1 on the elbow at 2.977,
falling by e^-1 every 0.67 A below it) near 5.8 A however large the demand, while for
``|i - i*| << delta`` it is a square as in Eq. 3.22. S is large so that the filter is transparent
inside the limits (on the elbow at rest, a demand of 4.8 A, 80 % of i_max, gives 4.74 A; 4 A
gives 3.98 A; with the former S = 1, delta = 10: 3.90 A and 3.51 A). The barrier stays soft and
near a position limit its ``W_q`` term (exponent up to ``lam_q`` = 10) outweighs the current
barrier's (``lam_tau R K_m`` per A): the entity clips its output current to ``±i_max`` and flags
``saturated`` where the clip acts, the last line of defence. ``torque_weight = 0`` with ``x*`` a
position reference is the thesis's cost exactly
(:func:`solve` takes any ``x*``, ``u*``).

**Solver** (Li and Todorov's iLQR, thesis §3.4.3, Eqs. 3.16-3.17), vectorised over joints
(each joint is its own problem; the arrays hold all joints): Riccati backward pass with a
Levenberg term on ``Q_uu`` (raised for a joint whose line search fails), forward pass with the
feedback gains and a backtracking line search per joint, stop when every joint has converged (its
step accepted and its cost decrease below ``tolerance``, relative) or has its regularisation past
:data:`REGULARISATION_CAP` (reported as :attr:`Solution.capped`), or after ``max_iterations``;
warm start from the previous plan shifted by the elapsed time (one knot when the re-solve period
equals the knot step), clipped to the current limits (Newton steps on an exponential barrier crawl from far outside it).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.actuators.chain import (
    GRAVITY,
    TALOS_ELBOW,
    ChainFileError,
    ChainParameters,
    desired_current,
    friction,
    load_chain_file,
)

EXPONENT_CAP = 150.0
"""Barrier exponents are capped here (far beyond a limit) so that ``C_s^2`` stays finite."""
REGULARISATION_CAP = 1e8
"""The iLQR gives up on a joint whose Levenberg term on ``Q_uu`` passes this (its steps are then
negligible): :attr:`Solution.capped`."""


@dataclass(frozen=True)
class Weights:
    """The cost's weights and barrier sharpness (thesis Eq. 3.23 and §3.4.5); ``S`` is ours."""

    Q_q: float = 40.0
    Q_qd: float = 0.01
    R: float = 1e-4
    S: float = 50.0
    delta: float = 0.3
    W_q: float = 1.0
    W_qd: float = 0.1
    P: float = 10.0
    lam_q: float = 10.0
    lam_qd: float = 1.0
    lam_tau: float = 0.5


@dataclass(frozen=True)
class Model:
    """Eq. 3.5 for ``n`` joints, each parameter an array of shape ``(n,)``."""

    inertia: np.ndarray
    F_v: np.ndarray
    F_s: np.ndarray
    offset: np.ndarray
    M_X: np.ndarray
    M_Y: np.ndarray
    R_Km: np.ndarray
    mu: float = 1000.0

    @classmethod
    def from_chains(cls, chains: Sequence[ChainParameters], mu: float = 1000.0, motor_offsets: bool = True) -> Model:
        """The model of the chains (one per joint); without ``off_m`` if ``motor_offsets`` is false (a
        plant with no motor-side offset, as ``compensate_offsets: false`` says)."""
        def col(f: Any) -> np.ndarray:
            return np.array([float(f(c)) for c in chains])
        return cls(col(lambda c: c.I_j + c.I_m), col(lambda c: c.F_v), col(lambda c: c.F_s),
                   col(lambda c: (c.off_m if motor_offsets else 0.0) + c.off_j), col(lambda c: c.M_X),
                   col(lambda c: c.M_Y), col(lambda c: c.R_Km), mu)

    def acceleration(self, q: np.ndarray, v: np.ndarray, u: np.ndarray) -> np.ndarray:
        """``q_ddot`` of Eq. 3.18."""
        return (self.R_Km * u - self.F_v * v - self.F_s * np.tanh(self.mu * v) - self.offset
                - GRAVITY * (self.M_Y * np.sin(q) + self.M_X * np.cos(q))) / self.inertia

    def step(self, q: np.ndarray, v: np.ndarray, u: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
        """One knot: linearly implicit velocity, then the position with the new velocity."""
        a = self.acceleration(q, v, u)
        sech2 = 1.0 - np.tanh(self.mu * v) ** 2
        a_v = -(self.F_v + self.F_s * self.mu * sech2) / self.inertia
        v_next = v + h * a / (1.0 - h * a_v)
        return q + h * v_next, v_next

    def jacobians(self, q: np.ndarray, v: np.ndarray, u: np.ndarray, h: float) -> tuple[np.ndarray, ...]:
        """Analytic ``f_x`` (entries A11, A12, A21, A22) and ``f_u`` (B1, B2) of :meth:`step`."""
        a = self.acceleration(q, v, u)
        th = np.tanh(self.mu * v)
        sech2 = 1.0 - th * th
        a_q = -GRAVITY * (self.M_Y * np.cos(q) - self.M_X * np.sin(q)) / self.inertia
        a_v = -(self.F_v + self.F_s * self.mu * sech2) / self.inertia
        a_vv = 2.0 * self.F_s * self.mu ** 2 * sech2 * th / self.inertia
        a_u = self.R_Km / self.inertia
        d = 1.0 - h * a_v
        dv_q = h * a_q / d
        dv_v = 1.0 + h * a_v / d + h * h * a * a_vv / (d * d)
        dv_u = h * a_u / d
        return 1.0 + h * dv_q, h * dv_v, dv_q, dv_v, h * dv_u, dv_u


def barrier(c: np.ndarray, c_min: np.ndarray, c_max: np.ndarray, lam: float) -> tuple[np.ndarray, ...]:
    """``C_s(c)`` (Eq. 3.14) and its first and second derivatives (Eqs. 3.26-3.27, 3.30-3.31)."""
    e_max = np.exp(np.minimum(lam * (1.0 - lam * (c_max - c)), EXPONENT_CAP))
    e_min = np.exp(np.minimum(lam * (1.0 - lam * (c - c_min)), EXPONENT_CAP))
    value = e_max + e_min
    return value, lam * lam * (e_max - e_min), lam ** 4 * value


def huber(e: np.ndarray, delta: float) -> tuple[np.ndarray, ...]:
    """Pseudo-Huber ``2 delta^2 (sqrt(1 + (e/delta)^2) - 1)`` (``e^2`` for small ``e``), its first
    and second derivatives; the first is bounded by ``2 delta``."""
    r = np.sqrt(1.0 + (e / delta) ** 2)
    return 2.0 * delta * delta * (r - 1.0), 2.0 * e / r, 2.0 / r ** 3


@dataclass(frozen=True)
class Limits:
    """Per-joint bounds, arrays of shape ``(n,)``: position (rad), velocity (rad/s), current (A)."""

    q_min: np.ndarray
    q_max: np.ndarray
    qd_max: np.ndarray
    i_max: np.ndarray


@dataclass
class Solution:
    """A solve's plan, arrays indexed ``[knot, joint]``."""

    u: np.ndarray
    q: np.ndarray
    v: np.ndarray
    gains: np.ndarray
    """(N, n, 2): the feedback ``K`` of each knot"""
    cost: np.ndarray
    iterations: int
    capped: np.ndarray
    """(n,) bool: the joint's line search kept failing until the regularisation passed its cap"""


def _costs(model: Model, lim: Limits, w: Weights, q: np.ndarray, v: np.ndarray, u: np.ndarray,
           q_ref: np.ndarray, v_ref: np.ndarray, u_ref: np.ndarray) -> np.ndarray:
    """The total cost per joint of a trajectory (``q``, ``v``: N+1 knots; ``u``: N)."""
    cq = barrier(q, lim.q_min, lim.q_max, w.lam_q)[0]
    cv = barrier(v, -lim.qd_max, lim.qd_max, w.lam_qd)[0]
    tau_max = model.R_Km * lim.i_max
    ct = barrier(model.R_Km * u, -tau_max, tau_max, w.lam_tau)[0]
    state = w.Q_q * (q - q_ref) ** 2 + w.Q_qd * (v - v_ref) ** 2 + w.W_q * cq ** 2 + w.W_qd * cv ** 2
    control = w.R * u ** 2 + w.S * huber(u - u_ref, w.delta)[0] + w.P * ct ** 2
    return state.sum(axis=0) + control.sum(axis=0)


def rollout(model: Model, q0: np.ndarray, v0: np.ndarray, u: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """The model's trajectory (N+1 knots) under the inputs ``u`` (N knots)."""
    n_knots = u.shape[0]
    q = np.empty((n_knots + 1, q0.size))
    v = np.empty_like(q)
    q[0], v[0] = q0, v0
    for k in range(n_knots):
        q[k + 1], v[k + 1] = model.step(q[k], v[k], u[k], h)
    return q, v


def solve(model: Model, lim: Limits, w: Weights, q0: np.ndarray, v0: np.ndarray, q_ref: np.ndarray,
          v_ref: np.ndarray, u_ref: np.ndarray, u_init: np.ndarray, h: float, max_iterations: int = 10,
          tolerance: float = 1e-3) -> Solution:
    """iLQR on every joint at once: ``q_ref``, ``v_ref`` (N+1, n), ``u_ref``, ``u_init`` (N, n)."""
    n_knots, n = u_init.shape
    u = np.clip(u_init, -lim.i_max, lim.i_max)  # from inside: Newton on an exponential crawls from outside
    q, v = rollout(model, q0, v0, u, h)
    cost = _costs(model, lim, w, q, v, u, q_ref, v_ref, u_ref)
    reg = np.full(n, 1e-6)
    gains = np.zeros((n_knots, n, 2))
    tau_max = model.R_Km * lim.i_max
    rk = model.R_Km
    iterations = 0
    capped = np.zeros(n, dtype=bool)
    for iterations in range(1, max_iterations + 1):  # noqa: B007 (returned)
        # cost derivatives (Eqs. 3.24-3.31, with P on the torque barrier)
        cq, dcq, ddcq = barrier(q, lim.q_min, lim.q_max, w.lam_q)
        cv, dcv, ddcv = barrier(v, -lim.qd_max, lim.qd_max, w.lam_qd)
        ct, dct, ddct = barrier(rk * u, -tau_max, tau_max, w.lam_tau)
        l_q = 2.0 * w.Q_q * (q - q_ref) + 2.0 * w.W_q * cq * dcq
        l_v = 2.0 * w.Q_qd * (v - v_ref) + 2.0 * w.W_qd * cv * dcv
        l_qq = 2.0 * w.Q_q + 2.0 * w.W_q * (cq * ddcq + dcq * dcq)
        l_vv = 2.0 * w.Q_qd + 2.0 * w.W_qd * (cv * ddcv + dcv * dcv)
        _, dh, ddh = huber(u - u_ref, w.delta)
        l_u = 2.0 * w.R * u + w.S * dh + 2.0 * w.P * ct * dct * rk
        l_uu = 2.0 * w.R + w.S * ddh + 2.0 * w.P * (ct * ddct + dct * dct) * rk * rk
        a11, a12, a21, a22, b1, b2 = model.jacobians(q[:-1], v[:-1], u, h)
        # backward pass (Riccati), V_xx = [[p11, p12], [p12, p22]]
        feedforward = np.empty((n_knots, n))
        gains = np.empty((n_knots, n, 2))
        vx1, vx2 = l_q[-1].copy(), l_v[-1].copy()
        p11, p12, p22 = l_qq[-1].copy(), np.zeros(n), l_vv[-1].copy()
        for k in range(n_knots - 1, -1, -1):
            # V_xx A and V_xx B
            m11 = p11 * a11[k] + p12 * a21[k]
            m12 = p11 * a12[k] + p12 * a22[k]
            m21 = p12 * a11[k] + p22 * a21[k]
            m22 = p12 * a12[k] + p22 * a22[k]
            vb1 = p11 * b1[k] + p12 * b2[k]
            vb2 = p12 * b1[k] + p22 * b2[k]
            qx1 = l_q[k] + a11[k] * vx1 + a21[k] * vx2
            qx2 = l_v[k] + a12[k] * vx1 + a22[k] * vx2
            qu = l_u[k] + b1[k] * vx1 + b2[k] * vx2
            qxx11 = l_qq[k] + a11[k] * m11 + a21[k] * m21
            qxx12 = a11[k] * m12 + a21[k] * m22
            qxx22 = l_vv[k] + a12[k] * m12 + a22[k] * m22
            qux1 = b1[k] * m11 + b2[k] * m21
            qux2 = b1[k] * m12 + b2[k] * m22
            quu = l_uu[k] + b1[k] * vb1 + b2[k] * vb2
            quu_reg = quu + reg
            kff = -qu / quu_reg
            k1, k2 = -qux1 / quu_reg, -qux2 / quu_reg
            feedforward[k] = kff
            gains[k, :, 0], gains[k, :, 1] = k1, k2
            vx1 = qx1 + k1 * quu * kff + k1 * qu + qux1 * kff
            vx2 = qx2 + k2 * quu * kff + k2 * qu + qux2 * kff
            p11 = qxx11 + k1 * quu * k1 + 2.0 * k1 * qux1
            p12 = qxx12 + k1 * quu * k2 + k1 * qux2 + k2 * qux1
            p22 = qxx22 + k2 * quu * k2 + 2.0 * k2 * qux2
        # forward pass with a backtracking line search per joint
        accepted = np.zeros(n, dtype=bool)
        new_u, new_q, new_v, new_cost = u.copy(), q.copy(), v.copy(), cost.copy()
        alpha = 1.0
        for _ in range(6):
            uu = np.empty_like(u)
            qq = np.empty_like(q)
            vv = np.empty_like(v)
            qq[0], vv[0] = q0, v0
            for k in range(n_knots):
                uu[k] = (u[k] + alpha * feedforward[k] + gains[k, :, 0] * (qq[k] - q[k])
                         + gains[k, :, 1] * (vv[k] - v[k]))
                qq[k + 1], vv[k + 1] = model.step(qq[k], vv[k], uu[k], h)
            trial = _costs(model, lim, w, qq, vv, uu, q_ref, v_ref, u_ref)
            take = ~accepted & (trial < cost)
            new_u[:, take], new_q[:, take], new_v[:, take], new_cost[take] = (
                uu[:, take], qq[:, take], vv[:, take], trial[take])
            accepted |= take
            if accepted.all():
                break
            alpha *= 0.5
        decrease = cost - new_cost
        reg = np.where(accepted, np.maximum(reg * 0.1, 1e-9), reg * 10.0)
        u, q, v, cost = new_u, new_q, new_v, new_cost
        # a joint has converged when its step was accepted and barely lowered the cost; one whose
        # line search failed is not (its decrease is 0): it retries with the raised regularisation
        # until the cap, where the steps are too small to matter
        capped = reg > REGULARISATION_CAP
        if np.all((accepted & (decrease <= tolerance * np.maximum(cost, 1e-12))) | capped):
            break
    return Solution(u=u, q=q, v=v, gains=gains, cost=cost, iterations=iterations, capped=capped)


def reference(model: Model, chains: Sequence[ChainParameters], torque: np.ndarray, q: np.ndarray,
              v: np.ndarray, n_knots: int, h: float, acceleration: np.ndarray | None = None,
              compensate_offsets: bool = True,
              controller_armature: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``x*`` and ``u*`` from the commanded joint torque: the current that delivers ``tau_j*``
    (:func:`~dgraph.entities.actuators.chain.desired_current`, ActuatorModel's ``i_m*``, with
    ``sign`` as ``tanh(mu q_dot)``, the link's acceleration from its joint side
    ``(tau_j* - g(q) - tau_fj) / (I_j + a_c)``, or ``acceleration`` where the controller gives it, i.e.
    where it is finite), held over the horizon, and the model's trajectory under it."""
    armature = np.broadcast_to(np.asarray(controller_armature, dtype=float), torque.shape)
    q_ddot = np.empty_like(torque)
    for j, c in enumerate(chains):
        if acceleration is not None and np.isfinite(acceleration[j]):
            q_ddot[j] = acceleration[j]
            continue
        grav = GRAVITY * (c.M_Y * np.sin(q[j]) + c.M_X * np.cos(q[j]))
        tau_fj = friction(c.F_vj, c.F_sj, c.off_j, v[j], smoothing=model.mu)
        link = c.I_j + armature[j]
        q_ddot[j] = (torque[j] - grav - tau_fj) / link if link > 0 else 0.0
    u_star = desired_current(chains, torque, v, q_ddot, model.mu, compensate_offsets, armature)
    u_ref = np.tile(u_star, (n_knots, 1))
    q_ref, v_ref = rollout(model, q, v, u_ref, h)
    return q_ref, v_ref, u_ref


def delivered_torque(model: Model, chains: Sequence[ChainParameters], q: np.ndarray, v: np.ndarray,
                     current: np.ndarray, compensate_offsets: bool = True) -> np.ndarray:
    """``tau_j = R K_m i_m - I_m q_ddot - tau_fm`` with ``q_ddot`` the model's (Eq. 3.18); ``tau_fm``
    without ``off_m`` if ``compensate_offsets`` is false."""
    acc = model.acceleration(q, v, current)
    out = np.empty_like(current)
    for j, c in enumerate(chains):
        off_m = c.off_m if compensate_offsets else 0.0
        out[j] = c.R_Km * current[j] - c.I_m * acc[j] - friction(c.F_vm, c.F_sm, off_m, v[j], smoothing=model.mu)
    return out


def _param_vector(value: Any, n: int, name: str, entity: str) -> np.ndarray:
    """A parameter given as one value for every joint or one per joint."""
    array = np.asarray(value, dtype=float)
    if array.ndim > 1 or array.size not in (1, n):
        raise dg.ParamError(f"{entity}: parameter {name!r}: expected 1 or {n} values (one per joint), got "
                            f"{array.size}", entity=entity)
    return np.broadcast_to(array.reshape(-1), (n,)).copy()


def _chain_list(chains: Any, entity: str) -> list[ChainParameters]:
    """``chains`` as one :class:`ChainParameters` per joint; a :class:`dg.ParamError` naming the joint
    and the key for a malformed entry."""
    if chains is None:
        return [TALOS_ELBOW]
    if isinstance(chains, ChainParameters | dict):
        chains = [chains]
    if isinstance(chains, str) or not isinstance(chains, Sequence):
        raise dg.ParamError(f"{entity}: parameter 'chains': expected a ChainParameters, a mapping or a list of "
                            f"them, got {type(chains).__name__}", entity=entity)
    if not chains:
        raise dg.ParamError(f"{entity}: parameter 'chains': at least one joint", entity=entity)
    names = set(ChainParameters.names())
    out = []
    for j, c in enumerate(chains):
        where = f"{entity}: parameter 'chains', joint {j}"
        if isinstance(c, ChainParameters):
            out.append(c)
            continue
        if not isinstance(c, dict):
            raise dg.ParamError(f"{where}: expected a ChainParameters or a mapping, got {type(c).__name__}",
                                entity=entity)
        unknown = sorted(str(k) for k in c if k not in names)
        if unknown:
            raise dg.ParamError(f"{where}: unknown key(s) {unknown}; known: {sorted(names)}", entity=entity)
        for key, value in c.items():
            if isinstance(value, bool) or not isinstance(value, int | float) or np.isnan(value):
                raise dg.ParamError(f"{where}: key {key!r} must be a number, got {value!r}", entity=entity)
        chain = ChainParameters(**{k: float(v) for k, v in c.items()})
        for key in ("R_Km", "i_max"):
            if not getattr(chain, key) > 0.0:
                raise dg.ParamError(f"{where}: key {key!r} must be positive, got {getattr(chain, key)!r}",
                                    entity=entity)
        out.append(chain)
    return out


def _n(entity: TorqueProtection) -> tuple[int]:
    return (entity.size,)


def _plan_shape(entity: TorqueProtection) -> tuple[int, int]:
    return (entity.size, entity.knots + 1)


def _barrier_shape(entity: TorqueProtection) -> tuple[int, int]:
    return (entity.size, 3)


@dg.register
class TorqueProtection(dg.Entity):
    """Per-joint iLQR MPC that keeps the motor current, velocity and position within their
    limits while tracking the commanded joint torque (thesis §3.4, Eqs. 3.13-3.31).

    Every ``resolve_every`` ticks the entity solves, for each joint, over ``horizon`` s at
    ``knot_step`` s (15 ms at 3 ms: 5 knots), the problem of the module docstring: state
    ``[q, q_dot]``, input the current, model Eq. 3.18 (tanh(mu q_dot) friction), cost Eq. 3.22
    with the exponential barriers of Eq. 3.14 on ``q``, ``q_dot`` and ``tau_m = R K_m i``, and the
    reference built from the commanded torque (``u*`` the current delivering ``tau_j*`` through
    Eq. 3.1, ``x*`` the model under ``u*``). Between solves it applies the plan at the elapsed
    time with its feedback gain. The first solve starts from ``u*``; later ones from the previous
    plan shifted by the elapsed time.

    Parameters: the chains, either ``path`` (an actuator parameter file,
    :func:`~dgraph.entities.actuators.chain.load_chain_file`, as ActuatorModel's) with ``joints``
    (names of its joints, one chain each), or ``chains`` (a :class:`ChainParameters`, a list of
    them or of their dicts, one per joint; default TALOS's elbow); ``compensate_offsets`` and
    ``controller_armature`` (``a_c``) as ActuatorModel's (the same
    :func:`~dgraph.entities.actuators.chain.desired_current` gives ``i*``): ``off_m`` compensated
    (default true; false for MuJoCo's twin, which has none: ``off_m`` then leaves ``i*``,
    ``torque_out`` and the plan's model alike) and ``I_m - a_c`` compensated (default ``a_c`` 0; 0.1
    under Pinocchio's TALOS model, whose armature is in ``tau_j*`` already); ``q_min``, ``q_max``
    (rad), ``q_dot_max`` (rad/s), ``i_max`` (A; default each chain's), ``horizon``, ``knot_step``
    (s), ``resolve_every`` (ticks), the
    weights ``Q_q``, ``Q_qd``, ``R``, ``W_q``, ``W_qd``, ``P`` and ``lam_q``, ``lam_qd``, ``lam_tau``
    (thesis Eq. 3.23 and §3.4.5), ``torque_weight`` (S, ours: the weight of the pseudo-Huber
    ``rho(i - i*)``), ``torque_scale`` (its delta, A: quadratic below, pull bounded by ``2 S delta``),
    ``mu`` (Eq. 3.18), ``max_iterations``, ``tolerance`` (relative cost decrease that stops).
    Inputs: ``torque`` (commanded joint torque ``tau_j*``, N m), ``q``, ``q_dot`` (measured),
    ``q_ddot`` (the acceleration the controller commands, e.g. a whole-body QP's: ``i*`` delivers
    ``tau_j*`` at it; default NaN, per joint: the link model's ``(tau_j* - g(q) - tau_fj) / I_j``,
    which is wrong when the link carries a load the chain's ``M_X``, ``M_Y`` do not hold).
    Outputs: ``current`` (the filtered ``i_m``, A, clipped to ``±i_max``), ``saturated`` (per joint:
    the clip acted), ``motor_torque`` (``R K_m i``, N m), ``torque_out`` (the joint torque it delivers,
    ``R K_m i - I_m q_ddot - tau_fm`` with the model's ``q_ddot``), ``reference_current``
    (``i*``, unfiltered), ``predicted_q``, ``predicted_q_dot`` (joints x knots+1, the plan),
    ``barriers`` (joints x 3: ``C_s`` of ``q``, ``q_dot``, ``tau_m`` now), ``solve_time`` (s of the
    last solve), ``iterations`` (of the last solve).
    """

    chains = dg.Param(None, kind="object", doc="ChainParameters (or a list, one per joint); default TALOS_ELBOW "
                      "unless path is given")
    path = dg.Param(None, kind="path", doc="actuator parameter file (YAML, load_chain_file; in a graph file, "
                    "relative to its folder), with joints; instead of chains")
    joints = dg.Param(None, kind="str_list", doc="names of the joints of path driven, one chain each")
    compensate_offsets = dg.Param(True, kind="bool", doc="compensate off_m in i* (a real chain); false for MuJoCo's "
                                  "twin, which has no offset torque")
    controller_armature = dg.Param(0.0, kind="vector", minimum=0.0, doc="rotor inertia the controller's model has at "
                                   "each joint, kg m² (Pinocchio's armature: in tau_j* already); I_m minus it is "
                                   "compensated in i*. Scalar or one per joint")
    q_min = dg.Param(-2.35619449019, kind="vector", doc="lower position limit (rad)")
    q_max = dg.Param(0.0, kind="vector", doc="upper position limit (rad)")
    q_dot_max = dg.Param(4.58, kind="vector", minimum=0.0, doc="velocity limit (rad/s)")
    i_max = dg.Param(None, kind="vector", minimum=0.0, doc="current limit (A); default each chain's i_max")
    horizon = dg.Param(0.015, kind="float", minimum=1e-4, doc="preview (s)")
    knot_step = dg.Param(0.003, kind="float", minimum=1e-5, doc="step between knots (s)")
    resolve_every = dg.Param(1, kind="int", minimum=1, doc="ticks between solves")
    Q_q = dg.Param(40.0, kind="float", minimum=0.0, doc="position tracking weight (Eq. 3.23)")
    Q_qd = dg.Param(0.01, kind="float", minimum=0.0, doc="velocity tracking weight (Eq. 3.23)")
    R = dg.Param(1e-4, kind="float", minimum=0.0, doc="current weight (Eq. 3.23)")
    W_q = dg.Param(1.0, kind="float", minimum=0.0, doc="position barrier weight (Eq. 3.23)")
    W_qd = dg.Param(0.1, kind="float", minimum=0.0, doc="velocity barrier weight (Eq. 3.23)")
    P = dg.Param(10.0, kind="float", minimum=0.0, doc="motor torque barrier weight (Eq. 3.23; 0: no current barrier)")
    lam_q = dg.Param(10.0, kind="float", minimum=1e-6, doc="position barrier sharpness")
    lam_qd = dg.Param(1.0, kind="float", minimum=1e-6, doc="velocity barrier sharpness")
    lam_tau = dg.Param(0.5, kind="float", minimum=1e-6, doc="motor torque barrier sharpness")
    torque_weight = dg.Param(50.0, kind="float", minimum=0.0, doc="weight S of the torque tracking (not in the thesis)")
    torque_scale = dg.Param(0.3, kind="float", minimum=1e-6,
                            doc="delta (A): the torque tracking is quadratic below it, its pull bounded by 2 S delta")
    mu = dg.Param(1000.0, kind="float", minimum=0.0, doc="tanh smoothing of the dry friction (Eq. 3.18)")
    max_iterations = dg.Param(10, kind="int", minimum=1, doc="iLQR iterations per solve")
    tolerance = dg.Param(1e-3, kind="float", minimum=0.0, doc="relative cost decrease that stops the iLQR")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, chains: Any = None, path: str | None = None, joints: Sequence[str] | None = None,
            compensate_offsets: bool = True, controller_armature: ArrayLike = 0.0, q_min: ArrayLike = -2.35619449019,
            q_max: ArrayLike = 0.0, q_dot_max: ArrayLike = 4.58, i_max: ArrayLike | None = None, horizon: float = 0.015,
            knot_step: float = 0.003, resolve_every: int = 1, Q_q: float = 40.0, Q_qd: float = 0.01, R: float = 0.0001,
            W_q: float = 1.0, W_qd: float = 0.1, P: float = 10.0, lam_q: float = 10.0, lam_qd: float = 1.0,
            lam_tau: float = 0.5, torque_weight: float = 50.0, torque_scale: float = 0.3, mu: float = 1000.0,
            max_iterations: int = 10, tolerance: float = 0.001, dt: float | None = None,
        ) -> None: ...

    torque = dg.Input(shape=_n, doc="commanded joint torque tau_j* (N m)")
    q = dg.Input(shape=_n, doc="joint position (rad)")
    q_dot = dg.Input(shape=_n, doc="joint velocity (rad/s)")
    # declared per instance (its NaN default is sized by the joints): q_ddot (n), the acceleration
    # the controller commands (rad/s²), for i*; NaN: the link model's

    def configure(self) -> None:
        """The chains, limits and weights from the parameters (checked), before the ports are sized."""
        name = self.name
        self._chains = self._read_chains()
        n = len(self._chains)
        self._armature = _param_vector(self.controller_armature, n, "controller_armature", name)
        self._model = Model.from_chains(self._chains, self.mu, self.compensate_offsets)
        i_max = self.i_max if self.i_max is not None else [c.i_max for c in self._chains]
        self._limits = Limits(_param_vector(self.q_min, n, "q_min", name), _param_vector(self.q_max, n, "q_max", name),
                              _param_vector(self.q_dot_max, n, "q_dot_max", name),
                              _param_vector(i_max, n, "i_max", name))
        lim = self._limits
        for key, values in (("q_min", lim.q_min), ("q_max", lim.q_max), ("q_dot_max", lim.qd_max)):
            if not np.all(np.isfinite(values)):
                raise dg.ParamError(f"{name}: parameter {key!r} must be finite, got {values.tolist()}", entity=name)
        if not np.all(lim.i_max > 0.0) or np.any(np.isnan(lim.i_max)):
            raise dg.ParamError(f"{name}: parameter 'i_max' must be > 0 (A), got {lim.i_max.tolist()}", entity=name)
        if not np.all(lim.q_min < lim.q_max):
            raise dg.ParamError(f"{name}: parameters 'q_min' < 'q_max' required per joint, got q_min "
                                f"{lim.q_min.tolist()}, q_max {lim.q_max.tolist()}", entity=name)
        if not np.all(lim.qd_max > 0.0):
            raise dg.ParamError(f"{name}: parameter 'q_dot_max' must be > 0 (rad/s), got {lim.qd_max.tolist()}",
                                entity=name)
        self._knots = max(1, round(self.horizon / self.knot_step))
        self._weights = Weights(
            Q_q=self.Q_q, Q_qd=self.Q_qd, R=self.R, S=self.torque_weight, delta=self.torque_scale, W_q=self.W_q,
            W_qd=self.W_qd, P=self.P, lam_q=self.lam_q, lam_qd=self.lam_qd, lam_tau=self.lam_tau)
        self.declare("q_ddot", dg.Input(shape=(n,), default=np.full(n, np.nan), finite=None,
                                        doc="joint acceleration the controller commands (rad/s²), for i*; NaN "
                                        "(default, per joint): the link model's"))

    def _read_chains(self) -> list[ChainParameters]:
        """One chain per joint: ``path`` and ``joints``, or ``chains``."""
        name = self.name
        if self.path is None:
            if self.joints is not None:
                raise dg.ParamError(f"{name}: parameter 'joints' needs 'path' (the file of their chains)", entity=name)
            return _chain_list(self.params.get("chains"), name)
        if self.params.get("chains") is not None:
            raise dg.ParamError(f"{name}: parameters 'path' and 'chains' both given: one source of chains",
                                entity=name)
        if not self.joints:
            raise dg.ParamError(f"{name}: parameter 'joints': at least one joint of {self.path}", entity=name)
        if len(set(self.joints)) != len(self.joints):
            raise dg.ParamError(f"{name}: parameter 'joints': a joint is named twice", entity=name)
        try:
            chains = load_chain_file(self.path)
        except ChainFileError as exc:
            raise dg.ParamError(f"{name}: parameter 'path': {exc}", entity=name) from None
        missing = [j for j in self.joints if j not in chains]
        if missing:
            raise dg.ParamError(f"{name}: parameter 'joints': {missing} not in {self.path} (it has {sorted(chains)})",
                                entity=name)
        return [chains[j] for j in self.joints]

    def reset(self) -> None:
        """No plan yet (the first solve starts from ``i*``)."""
        self._plan: Solution | None = None
        self._plan_tick = 0
        self._solve_time = 0.0
        self._unclipped = np.zeros(self.size)

    @property
    def size(self) -> int:
        """The number of joints."""
        return len(self._chains)

    @property
    def knots(self) -> int:
        """Knots of the horizon."""
        return self._knots

    def _warm_start(self, elapsed: float, u_ref: np.ndarray) -> np.ndarray:
        if self._plan is None:
            return u_ref.copy()
        old = self._plan.u
        times = np.arange(self._knots) * self.knot_step + elapsed
        grid = np.arange(old.shape[0]) * self.knot_step
        return np.stack([np.interp(times, grid, old[:, j]) for j in range(self.size)], axis=1)

    @dg.output(shape=None, depends=("torque", "q", "q_dot", "q_ddot", "t"), finite=None)
    def plan(self, t: int) -> Solution:
        """The last solution (re-solved every ``resolve_every`` ticks)."""
        if self._plan is not None and t - self._plan_tick < self.resolve_every:
            return self._plan
        q, v = self.q(t), self.q_dot(t)
        q_ref, v_ref, u_ref = reference(self._model, self._chains, self.torque(t), q, v, self._knots, self.knot_step,
                                        self.q_ddot(t), self.compensate_offsets, self._armature)
        elapsed = (t - self._plan_tick) * self.dt
        start = time.perf_counter()
        sol = solve(self._model, self._limits, self._weights, q, v, q_ref, v_ref, u_ref,
                    self._warm_start(elapsed, u_ref), self.knot_step, self.max_iterations, self.tolerance)
        self._solve_time = time.perf_counter() - start
        self._plan, self._plan_tick = sol, t
        return sol

    @dg.output(shape=_n, depends=("plan", "q", "q_dot", "t"))
    def current(self, t: int) -> np.ndarray:
        """The filtered current: the plan at the elapsed time with its feedback, clipped to
        ``±i_max`` (the barrier is soft: the clip is the last line of defence, ``saturated``)."""
        sol = self.plan(t)
        k = min(int(((t - self._plan_tick) * self.dt) / self.knot_step + 1e-9), self._knots - 1)
        if k == 0:
            raw = sol.u[0].copy()
        else:
            dq, dv = self.q(t) - sol.q[k], self.q_dot(t) - sol.v[k]
            raw = sol.u[k] + sol.gains[k, :, 0] * dq + sol.gains[k, :, 1] * dv
        self._unclipped = raw
        return np.clip(raw, -self._limits.i_max, self._limits.i_max)

    @dg.output(shape=_n, dtype="bool", depends=("current",))
    def saturated(self, t: int) -> np.ndarray:
        """Per joint: the plan asked more than ``i_max`` and ``current`` was clipped."""
        self.current(t)
        return np.abs(self._unclipped) > self._limits.i_max

    @dg.output(shape=_n, depends=("current", "q", "q_dot"))
    def torque_out(self, t: int) -> np.ndarray:
        """The joint torque the filtered current delivers (model's ``q_ddot``)."""
        return delivered_torque(self._model, self._chains, self.q(t), self.q_dot(t), self.current(t),
                                self.compensate_offsets)

    @dg.output(shape=_n, depends=("current",))
    def motor_torque(self, t: int) -> np.ndarray:
        """``tau_m = R K_m i`` (Eq. 3.3) of the filtered current, N m: what drives MuJoCo's twin."""
        return self._model.R_Km * self.current(t)

    @dg.output(shape=_n, depends=("torque", "q", "q_dot", "q_ddot"))
    def reference_current(self, t: int) -> np.ndarray:
        """``i*``: the current that delivers the commanded torque (unfiltered)."""
        return reference(self._model, self._chains, self.torque(t), self.q(t), self.q_dot(t), 1, self.knot_step,
                         self.q_ddot(t), self.compensate_offsets, self._armature)[2][0]

    @dg.output(shape=_plan_shape, depends=("plan",))
    def predicted_q(self, t: int) -> np.ndarray:
        """The plan's positions (joints x knots+1)."""
        return self.plan(t).q.T.copy()

    @dg.output(shape=_plan_shape, depends=("plan",))
    def predicted_q_dot(self, t: int) -> np.ndarray:
        """The plan's velocities (joints x knots+1)."""
        return self.plan(t).v.T.copy()

    @dg.output(shape=_barrier_shape, depends=("current", "q", "q_dot"))
    def barriers(self, t: int) -> np.ndarray:
        """``C_s`` of ``q``, ``q_dot`` and ``tau_m`` at the current state and output (joints x 3)."""
        lim, w = self._limits, self._weights
        q, v = self.q(t), self.q_dot(t)
        tau_max = self._model.R_Km * lim.i_max
        return np.stack([barrier(q, lim.q_min, lim.q_max, w.lam_q)[0],
                         barrier(v, -lim.qd_max, lim.qd_max, w.lam_qd)[0],
                         barrier(self._model.R_Km * self.current(t), -tau_max, tau_max, w.lam_tau)[0]], axis=1)

    @dg.output(shape=(), depends=("plan",))
    def solve_time(self, t: int) -> float:
        """Wall time of the last solve (s)."""
        self.plan(t)
        return self._solve_time

    @dg.output(shape=(), dtype="int", depends=("plan",))
    def iterations(self, t: int) -> int:
        """iLQR iterations of the last solve."""
        return self.plan(t).iterations
