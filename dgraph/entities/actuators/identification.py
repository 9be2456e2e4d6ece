"""Identification of an actuator chain's parameters by total least squares (thesis §3.3.1, Eqs. 3.9-3.12).

**The regressor (Eq. 3.9), re-derived from Eqs. 3.1-3.4.** With ``D = [q_ddot, q_dot, sign(q_dot), 1]``
and ``G = [g cos q, g sin q]``, Eqs. 3.1-3.2 read, per sample,

* motor: ``R K_m i_m = tau_m = G [M_X, M_Y] + D [I_m, F_vm, F_sm, off_m] + D [I_j, F_vj, F_sj, off_j]``
* joint: ``K_j tau_js = tau_j = G [M_X, M_Y] +           0              + D [I_j, F_vj, F_sj, off_j]``

so ``[tau_m; tau_j] = W phi`` with the rows ``[G, D, D]`` and ``[G, 0, D]`` and
``phi = [M_X, M_Y, I_m, F_vm, F_sm, off_m, I_j, F_vj, F_sj, off_j]`` (:data:`PHI_NAMES`). Where this
differs from the thesis's printing: (a) the thesis lists nine parameters and no ``I_j`` although its
rows have ten columns; the tenth is ``I_j``, the ``q_ddot`` of the second ``D`` (Table 3.1 identifies
it); (b) gravity's ``g`` is in the regressor, so ``M_X``, ``M_Y`` are first moments in kg m as in
:class:`~dgraph.entities.actuators.chain.ChainParameters` (the thesis's ``cos q``, ``sin q`` columns
would give them in N m); (c) ``off`` enters ``tau_m`` additively, as in Eq. 3.1 (Eq. 3.5 prints ``+ off``
on the acceleration's side; see :func:`simulate_chain`).

**Drive gains by total least squares (Eqs. 3.10-3.12, Gautier & Jubien).** ``R K_m`` and ``K_j`` are
unknown too, so the measured ``i_m`` and ``tau_js`` become columns. A payload of mass ``m`` fixed to the
link adds ``[g cos q, g sin q, q_ddot] [M_Xp, M_Yp, I_p]`` to both rows. Stacking the experiment without
payload (``W0``) and the one with it (``W1``)::

    [ -W0_m   i_m    0      0   ]   [ phi  ]
    [ -W0_j   0      tau_js 0   ]   [ R K_m]
    [ -W1_m   i_m    0     -W_p ] . [ K_j  ] = 0        (Eqs. 3.10-3.11, W_tot Phi_tot = 0)
    [ -W1_j   0      tau_js -W_p]   [ phi_p]

``W_tot`` is full rank because of noise; its closest rank-deficient matrix in the Frobenius norm is
the SVD's with the smallest singular value zeroed, whose null space is the last right singular vector
``v`` (Eq. 3.12). ``Phi_tot`` is ``v`` up to a scale: the scale is fixed by the payload's known first
moment ``M_Yp = m * arm`` (the thesis's "known position of the centre of mass of the payload along Y"),
``Phi_tot = v * M_Yp / v[M_Yp]``. ``M_Xp`` and ``I_p`` are identified (``phi_up``). Without the
payload experiment every multiple of ``v`` fits the data equally well: the scale is unidentifiable
unless ``R K_m`` is known (``drive_gain=``, the same scaling on another component).

**Relative standard deviations** (Table 3.1's sigma%, Presse & Gautier's definition
``sigma%_i = 100 sigma_i / |phi_i|``): with the known component's column moved to the right-hand side,
``W_tot Phi_tot = 0`` is the ordinary regression ``X Phi_rest = -w_k M_Yp``; ``sigma^2 = |W_tot Phi_tot|^2
/ (r - p)`` (``r`` rows, ``p`` unknowns) and ``C = sigma^2 (X^T X)^-1``. This is the least-squares
covariance of the scaled solution, an approximation for TLS (it ignores the noise in the columns).

**Data** (thesis §3.3.1): double S-curve motions over the joint's range, velocity plateaus in 20 %
steps (:func:`s_curve_excitation`); position, current and torque low-passed by a zero-phase
Butterworth filter (5 Hz, order 5: :func:`scipy.signal.sosfiltfilt`), velocity and acceleration by
centred differences of the filtered position, then decimation (:func:`prepare`). Samples whose
velocity is below ``min_velocity`` are left out: there ``sign(q_dot)`` is undefined and dry friction
is anywhere in ``[-F_s, F_s]``. :func:`simulate_chain` generates such recordings from known parameters
(Eq. 3.5 forward dynamics, encoder quantisation, current and torque noise) for tests and demonstration.
"""

from __future__ import annotations

import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy import signal

from dgraph.entities.actuators.chain import GRAVITY, TALOS_ELBOW, ChainParameters
from dgraph.errors import DGraphError

PHI_NAMES = ("M_X", "M_Y", "I_m", "F_vm", "F_sm", "off_m", "I_j", "F_vj", "F_sj", "off_j")
"""The base parameters of Eq. 3.9, in the regressor's column order."""
PAYLOAD_NAMES = ("M_Xp", "M_Yp", "I_p")
"""The payload's parameters at the joint: first moments (kg m) and inertia (kg m²)."""
TOTAL_NAMES = (*PHI_NAMES, "R_Km", "K_j", *PAYLOAD_NAMES)
"""The unknowns ``Phi_tot`` of Eq. 3.10, in column order."""
ENCODER_COUNTS = 2 ** 19
"""TALOS's 19-bit encoders (counts per revolution)."""


class RecordingError(DGraphError, ValueError):
    """A recording cannot be identified: unreadable, a column missing or of the wrong shape, too little
    motion. The message names the file."""


@dataclass(frozen=True)
class Payload:
    """A payload fixed to the link: its mass (kg) and the distance of its centre of mass from the joint
    axis along the link's Y axis (m); its first moment ``M_Yp = mass * arm`` fixes the scale."""

    mass: float
    arm: float

    @property
    def first_moment(self) -> float:
        """``M_Yp = m * arm`` (kg m)."""
        return self.mass * self.arm

    @property
    def inertia(self) -> float:
        """``m * arm²`` (kg m²): a point mass's inertia about the joint."""
        return self.mass * self.arm ** 2


@dataclass(frozen=True)
class Samples:
    """One experiment, ready for the regressor: position, velocity, acceleration (rad, rad/s, rad/s²),
    motor current (A) and raw joint torque sensor reading ``tau_js`` (N m), one value per sample, and
    the payload carried (``None`` for none)."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    current: np.ndarray
    torque: np.ndarray
    payload: Payload | None = None

    def __len__(self) -> int:
        return len(self.q)


def regressor(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The motor and joint rows of Eq. 3.9, ``W_m`` and ``W_j`` (N x 10, columns :data:`PHI_NAMES`):
    ``[g cos q, g sin q, D, D]`` and ``[g cos q, g sin q, 0, D]``, ``D = [q_ddot, q_dot, sign(q_dot), 1]``."""
    q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
    gravity = np.column_stack([GRAVITY * np.cos(q), GRAVITY * np.sin(q)])
    d = np.column_stack([qdd, qd, np.sign(qd), np.ones_like(q)])
    return np.hstack([gravity, d, d]), np.hstack([gravity, np.zeros_like(d), d])


def payload_regressor(q: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """The payload's columns ``W_p`` (N x 3, :data:`PAYLOAD_NAMES`): ``[g cos q, g sin q, q_ddot]``,
    on both the motor and the joint rows (the payload is on the link)."""
    q = np.asarray(q, dtype=float)
    return np.column_stack([GRAVITY * np.cos(q), GRAVITY * np.sin(q), np.asarray(qdd, dtype=float)])


def phi_of(params: ChainParameters) -> np.ndarray:
    """``phi`` (:data:`PHI_NAMES`) of a chain's parameters."""
    return np.array([getattr(params, name) for name in PHI_NAMES])


def prepare(time: np.ndarray, q: np.ndarray, current: np.ndarray, torque: np.ndarray, *,
            velocity: np.ndarray | None = None, payload: Payload | None = None, cutoff: float = 5.0,
            order: int = 5, decimation: int | None = None, min_velocity: float = 0.05,
            trim: float = 1.0) -> Samples:
    """Filter, differentiate and decimate one recording (thesis §3.3.1).

    ``q``, ``current`` and ``torque`` (and ``velocity`` if given) are low-passed by a zero-phase
    Butterworth filter (``cutoff`` Hz, ``order``; :func:`scipy.signal.sosfiltfilt`), the same filter
    on every signal so that the model's linear terms stay consistent; ``q_dot`` is the centred
    difference of the filtered position (or the filtered recorded ``velocity``), ``q_ddot`` the centred
    difference of ``q_dot``. ``trim`` seconds are dropped at both ends (the filter's transients), then
    one sample in ``decimation`` is kept (default: the rate that leaves 4 samples per period of the
    cutoff, ``fs / (4 cutoff)``), then samples with ``|q_dot| < min_velocity`` are dropped.
    ``cutoff=None`` skips the filter (noise-free data).
    """
    time = np.asarray(time, dtype=float)
    columns = {"q": q, "current": current, "torque": torque} | ({} if velocity is None else {"velocity": velocity})
    data = {name: np.asarray(x, dtype=float).ravel() for name, x in columns.items()}
    for name, x in {"time": time.ravel(), **data}.items():
        if name != "time" and x.shape != time.shape:
            raise ValueError(f"{name} has {x.size} samples, time has {time.size}")
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            raise ValueError(f"column {name!r} is not finite at {bad.size} sample(s), the first at sample "
                             f"{bad[0]} ({x[bad[0]]!r}); the filter would spread it over the whole recording")
    if time.size < 3 or not np.all(np.diff(time) > 0):
        raise ValueError("time must increase, with at least 3 samples")
    dt = float(np.median(np.diff(time)))
    fs = 1.0 / dt
    if cutoff is not None:
        if not 0 < cutoff < fs / 2:
            raise ValueError(f"the cutoff {cutoff} Hz must be below the Nyquist frequency {fs / 2:g} Hz")
        sos = signal.butter(order, cutoff, btype="low", fs=fs, output="sos")
        data = {name: signal.sosfiltfilt(sos, x) for name, x in data.items()}
    qd = np.gradient(data["q"], time) if velocity is None else data["velocity"]
    qdd = np.gradient(qd, time)
    keep = np.zeros(time.size, dtype=bool)
    margin = round(trim * fs)
    step = decimation or (max(1, int(fs / (4 * cutoff))) if cutoff is not None else 1)
    keep[margin:time.size - margin:step] = True
    keep &= np.abs(qd) >= min_velocity
    if keep.sum() < 2 * len(PHI_NAMES):
        raise ValueError(f"only {keep.sum()} samples left after trimming, decimation and |q_dot| >= "
                         f"{min_velocity}: the recording does not move enough")
    return Samples(data["q"][keep], qd[keep], qdd[keep], data["current"][keep], data["torque"][keep], payload)


@dataclass(frozen=True)
class Identification:
    """The result of :func:`identify`: the parameters (a :class:`ChainParameters`), every unknown's
    estimate and relative standard deviation (%), cond(W), the singular values of ``W_tot``, the
    torque fit's RMSD (N m) and the number of rows used."""

    parameters: ChainParameters
    estimates: dict[str, float]
    sigma_percent: dict[str, float]
    cond: float
    singular_values: np.ndarray
    rmsd: float
    rows: int
    scale: str = ""
    payload: dict[str, float] = field(default_factory=dict)

    def table(self) -> str:
        """Table 3.1's layout: parameter, estimate, sigma%, then R K_m, K_j, the payload's
        parameters and cond(W)."""
        lines = [f"{'parameter':<10} {'estimate':>12} {'sigma%':>8}"]
        for name, value in self.estimates.items():
            sigma = self.sigma_percent.get(name, float("nan"))
            known = " (known)" if np.isnan(sigma) and name in self.scale else ""
            lines.append(f"{name:<10} {value:>12.5g} {sigma:>8.2f}{known}")
        lines.append(f"cond(W) = {self.cond:.1f}   torque RMSD = {self.rmsd:.3g} N m   rows = {self.rows}"
                     f"   scale: {self.scale}")
        return "\n".join(lines)

    def yaml_mapping(self) -> dict[str, float]:
        """The identified parameters (:data:`PHI_NAMES`, ``R_Km``, ``K_j``; :class:`ChainParameters`
        names) as a plain mapping; ``i_max`` is not identified and left out."""
        return {name: float(getattr(self.parameters, name)) for name in ChainParameters.names()
                if name in (*PHI_NAMES, "R_Km", "K_j")}

    def actuator_file(self, joint: str, i_max: float) -> dict[str, object]:
        """An actuator parameter file's document (what
        :func:`~dgraph.entities.actuators.chain.load_chain_file` reads): ``{source: ..., joints:
        {joint: {<the identified parameters>, i_max}}}``. ``i_max`` (A, positive, may be inf) is not
        identified: the caller gives it (the drive's current limit)."""
        if not joint or not isinstance(joint, str):
            raise ValueError("the joint name must be a non-empty string")
        if not i_max > 0:  # also refuses NaN
            raise ValueError(f"i_max must be positive (A), got {i_max!r}")
        return {"source": f"dgraph identify (total least squares, thesis Eqs. 3.9-3.12; scale: {self.scale}); "
                          "i_max given, not identified",
                "joints": {joint: {**self.yaml_mapping(), "i_max": float(i_max)}}}


def total_regressor(experiments: Sequence[Samples]) -> np.ndarray:
    """``W_tot`` of Eq. 3.10 (columns :data:`TOTAL_NAMES`), stacking each experiment's motor rows and
    joint rows; an experiment without payload has zeros in the payload's columns."""
    blocks = []
    for exp in experiments:
        w_m, w_j = regressor(exp.q, exp.qd, exp.qdd)
        n = len(exp)
        w_p = payload_regressor(exp.q, exp.qdd) if exp.payload is not None else np.zeros((n, 3))
        zeros = np.zeros((n, 1))
        blocks.append(np.hstack([-w_m, exp.current[:, None], zeros, -w_p]))
        blocks.append(np.hstack([-w_j, zeros, exp.torque[:, None], -w_p]))
    return np.vstack(blocks)


def identify(experiments: Sequence[Samples], *, drive_gain: float | None = None,
             base: ChainParameters = TALOS_ELBOW) -> Identification:
    """Total least squares of Eqs. 3.10-3.12 over ``experiments`` (no payload and known payload).

    The scale of the null vector comes from the payload's first moment ``M_Yp`` (the first experiment
    with a payload), or from ``drive_gain`` = ``R K_m`` if given and no experiment has a payload.
    Parameters outside the regressor (``i_max``) are taken from ``base``. Raises ``ValueError`` if
    neither fixes the scale (the solution is then any multiple of the null vector).
    """
    experiments = list(experiments)
    loaded = [exp for exp in experiments if exp.payload is not None]
    w_tot = total_regressor(experiments)
    carried = next((exp.payload for exp in loaded if exp.payload is not None), None)
    if carried is not None:
        known = TOTAL_NAMES.index("M_Yp")
        value = carried.first_moment
        if any(exp.payload != carried for exp in loaded):
            raise ValueError("the payload experiments must carry the same payload")
        scale = f"M_Yp = {carried.mass:g} kg x {carried.arm:g} m"
        columns = list(range(len(TOTAL_NAMES)))
    elif drive_gain is not None:
        known = TOTAL_NAMES.index("R_Km")
        value = float(drive_gain)
        scale = f"R_Km = {value:g} (given)"
        columns = list(range(len(PHI_NAMES) + 2))  # no payload columns
        w_tot = w_tot[:, columns]
    else:
        raise ValueError("the scale of the total least-squares solution is unidentifiable without an experiment "
                         "with a known payload (or a known R K_m): every multiple of the null vector fits")
    if value == 0:
        raise ValueError("the known component that fixes the scale is zero")
    _, s, vt = np.linalg.svd(w_tot, full_matrices=False)
    v = vt[-1]
    if abs(v[known]) < 1e-9 * np.abs(v).max():
        raise ValueError("the null vector has no component along the known parameter: it cannot fix the scale")
    theta = v * (value / v[known])
    names = [TOTAL_NAMES[c] for c in columns]
    estimates = dict(zip(names, theta.tolist(), strict=True))
    wrong = [name for name in ("R_Km", "K_j") if not estimates[name] > 0]
    if wrong:
        given = ("the payload's first moment M_Yp = mass x arm: check the sign of the payload's arm (its centre "
                 "of mass along the link's Y axis, the side of the forearm's own M_Y) and of its mass"
                 if carried is not None else "the given R K_m (drive_gain): it must be positive")
        raise ValueError(f"the scale gives {', '.join(f'{n} = {estimates[n]:.4g}' for n in wrong)}, which must be "
                         f"positive (the current and the torque sensor read the joint torque with a positive gain): "
                         f"the scale comes from {given}; every estimate has the wrong sign")

    # sigma%: the known column moved to the right-hand side, ordinary least-squares covariance
    rows = w_tot.shape[0]
    rest = [c for c in range(w_tot.shape[1]) if c != known]
    x = w_tot[:, rest]
    residual = w_tot @ theta
    sigma2 = float(residual @ residual) / (rows - len(rest))
    cov = sigma2 * np.linalg.inv(x.T @ x)
    sigma_percent = {name: float("nan") for name in names}
    for i, c in enumerate(rest):
        sigma_percent[names[c]] = 100.0 * float(np.sqrt(cov[i, i])) / max(abs(theta[c]), 1e-300)

    # the torque fit over every experiment: [R K_m i_m; K_j tau_js] - W_p phi_p against W phi
    phi = np.array([estimates[name] for name in PHI_NAMES])
    phi_p = np.array([estimates.get(name, 0.0) for name in PAYLOAD_NAMES])
    errors = []
    for exp in experiments:
        w_m, w_j = regressor(exp.q, exp.qd, exp.qdd)
        w_p = payload_regressor(exp.q, exp.qdd) if exp.payload is not None else np.zeros((len(exp), 3))
        errors.append(estimates["R_Km"] * exp.current - w_p @ phi_p - w_m @ phi)
        errors.append(estimates["K_j"] * exp.torque - w_p @ phi_p - w_j @ phi)
    rmsd = float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))
    no_payload = [exp for exp in experiments if exp.payload is None] or experiments
    w0 = np.vstack([np.vstack(regressor(exp.q, exp.qd, exp.qdd)) for exp in no_payload])
    parameters = replace(base, **{name: estimates[name] for name in (*PHI_NAMES, "R_Km", "K_j")})
    payload = {name: estimates[name] for name in PAYLOAD_NAMES if name in estimates}
    return Identification(parameters, estimates, sigma_percent, float(np.linalg.cond(w0)), s, rmsd, rows,
                          scale, payload)


# --- data generator -------------------------------------------------------------------------------


def _triangle(x: np.ndarray) -> np.ndarray:
    """The jerk-limited ramp's acceleration over its duration ``x`` in [0, 1] (unit mean):
    ``4x`` then ``4(1 - x)``, zero outside."""
    return np.where(x < 0.5, 4 * x, 4 * (1 - x)) * ((x > 0) & (x < 1))


def s_curve_excitation(q_min: float = -2.35, q_max: float = 0.0, v_max: float = 1.5, *,
                       levels: Sequence[float] = (0.2, 0.4, 0.6, 0.8, 1.0), dwell: float = 0.5,
                       dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The thesis's exciting motion (§3.3.1): at each velocity plateau ``level * v_max`` (20 % steps),
    a double S-curve from ``q_max`` to ``q_min`` and back over the whole range, acceleration, constant
    velocity and deceleration phases of equal duration, the acceleration itself jerk-limited
    (triangular: the velocity is an S), ``dwell`` s at rest before each move. Returns
    ``(t, q, q_dot, q_ddot)`` sampled every ``dt``.

    A move of length ``L`` at plateau ``V`` lasts ``T = 3 L / (2 V)`` (the ramps cover ``V T/6`` each).
    """
    length = q_max - q_min
    if length <= 0 or v_max <= 0:
        raise ValueError("need q_min < q_max and v_max > 0")
    pieces_a, pieces_v, pieces_q = [], [], []
    q_now = q_max
    for level in levels:
        speed = level * v_max
        duration = 3 * length / (2 * speed)
        ramp = duration / 3
        for direction in (-1.0, 1.0):
            n_dwell = round(dwell / dt)
            n = int(np.ceil(duration / dt))
            tau = np.arange(n) * dt
            x_up = np.clip(tau / ramp, 0, 1)
            x_down = np.clip((tau - 2 * ramp) / ramp, 0, 1)
            acc = direction * speed / ramp * (_triangle(x_up) - _triangle(x_down))
            acc = np.concatenate([np.zeros(n_dwell), acc])
            vel = np.concatenate([[0.0], np.cumsum((acc[1:] + acc[:-1]) / 2) * dt])
            pos = np.concatenate([[0.0], np.cumsum((vel[1:] + vel[:-1]) / 2) * dt])
            ratio = length / abs(pos[-1])  # discretisation: land exactly on the range's end
            pieces_a.append(acc * ratio)
            pieces_v.append(vel * ratio)
            pieces_q.append(q_now + pos * ratio)
            q_now = q_min if direction < 0 else q_max
    acc, vel, pos = (np.concatenate(p) for p in (pieces_a, pieces_v, pieces_q))
    pos = np.concatenate([pos, np.full(round(dwell / dt), q_max)])
    vel, acc = (np.concatenate([x, np.zeros(pos.size - x.size)]) for x in (vel, acc))
    return np.arange(pos.size) * dt, pos, vel, acc


@dataclass(frozen=True)
class Noise:
    """Measurement noise of :func:`simulate_chain`: encoder quantisation (counts per revolution, ``None``
    for none), current noise std (A) and joint torque sensor noise std (N m), white and Gaussian."""

    encoder_counts: int | None = ENCODER_COUNTS
    current_std: float = 0.02
    torque_std: float = 0.1


NO_NOISE = Noise(encoder_counts=None, current_std=0.0, torque_std=0.0)
"""Noise-free measurements."""


def simulate_chain(params: ChainParameters, t: np.ndarray, q_ref: np.ndarray, qd_ref: np.ndarray,
                   qdd_ref: np.ndarray, *, payload: Payload | None = None, noise: Noise = Noise(),
                   gains: tuple[float, float] = (400.0, 40.0), substeps: int = 2,
                   seed: int = 0) -> dict[str, np.ndarray]:
    """Simulate the chain tracking ``q_ref`` and return a recording (columns ``time``, ``position``,
    ``velocity``, ``current``, ``torque``, as :func:`prepare` and ``dgraph identify`` read them).

    Forward dynamics (Eq. 3.5, with ``off`` on the torque side as in Eq. 3.1 and the payload on the link)::

        (I_m + I_j + I_p) q_ddot = R K_m i_m - F_v q_dot - F_s sign(q_dot) - off
                                   - g ((M_Y + M_Yp) sin q + (M_X + M_Xp) cos q)

    with Karnopp's stiction (at ``|q_dot| < 1e-4`` rad/s the joint sticks while the other torques stay
    within ``F_s``), integrated by semi-implicit Euler at ``dt / substeps``. The current is the drive's
    command: feedforward from the reference through the model with 10 % errors on every parameter
    (a controller does not know them) plus a PD (``gains`` in N m/rad, N m s/rad) on the true state.
    Recorded: the current and ``tau_js = tau_j / K_j`` with ``tau_j = (I_j + I_p) q_ddot + gravity +
    tau_fj`` (the sensor sits between drive and link), plus Gaussian noise; the position quantised to
    ``noise.encoder_counts``; the velocity as the encoder's backward difference.
    """
    rng = np.random.default_rng(seed)
    t = np.asarray(t, dtype=float)
    dt = float(t[1] - t[0])
    m_x, m_y, i_p = (0.0, payload.first_moment, payload.inertia) if payload is not None else (0.0, 0.0, 0.0)
    inertia = params.I_m + params.I_j + i_p
    mx, my = params.M_X + m_x, params.M_Y + m_y
    wrong = 1.1
    kp, kd = gains
    h = dt / substeps
    n = t.size
    q_true, qd_true, qdd_true, current = (np.empty(n) for _ in range(4))
    q, qd = float(q_ref[0]), float(qd_ref[0])
    for k in range(n):
        ff = (wrong * inertia * qdd_ref[k] + wrong * (params.F_v * qd_ref[k] + params.F_s * np.sign(qd_ref[k]))
              + GRAVITY * wrong * (my * np.sin(q_ref[k]) + mx * np.cos(q_ref[k])))
        i_m = (ff + kp * (q_ref[k] - q) + kd * (qd_ref[k] - qd)) / params.R_Km
        acc = 0.0
        for _ in range(substeps):
            drive = params.R_Km * i_m - params.off_m - params.off_j - GRAVITY * (my * np.sin(q) + mx * np.cos(q))
            if abs(qd) < 1e-4 and abs(drive) <= params.F_s:
                qd, acc = 0.0, 0.0
            else:
                direction = np.sign(qd) if abs(qd) >= 1e-4 else np.sign(drive)
                acc = (drive - params.F_v * qd - params.F_s * direction) / inertia
                qd += h * acc
                q += h * qd
        q_true[k], qd_true[k], qdd_true[k], current[k] = q, qd, acc, i_m
    tau_j = ((params.I_j + i_p) * qdd_true + GRAVITY * (my * np.sin(q_true) + mx * np.cos(q_true))
             + params.F_vj * qd_true + params.F_sj * np.sign(qd_true) + params.off_j)
    position = q_true
    if noise.encoder_counts:
        quantum = 2 * np.pi / noise.encoder_counts
        position = np.round(q_true / quantum) * quantum
    velocity = np.concatenate([[0.0], np.diff(position) / dt])
    return {"time": t, "position": position, "velocity": velocity,
            "current": current + noise.current_std * rng.standard_normal(n),
            "torque": tau_j / params.K_j + noise.torque_std * rng.standard_normal(n),
            "true_position": q_true, "true_velocity": qd_true, "true_acceleration": qdd_true}


DEMO_CHAIN = replace(TALOS_ELBOW, R_Km=5.3)
"""TALOS's elbow (Table 3.1) with ``R K_m`` = 5.3 N m/A (the thesis does not disclose it): the truth
of the generated recordings."""
DEMO_PAYLOAD = Payload(mass=2.0, arm=0.25)
"""The demonstration's payload: 2 kg at 25 cm (``M_Yp`` = 0.5 kg m)."""


def demo_recordings(params: ChainParameters = DEMO_CHAIN, payload: Payload = DEMO_PAYLOAD, *,
                    noise: Noise = Noise(), v_max: float = 1.5, seed: int = 0,
                    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Two recordings of :func:`simulate_chain` under :func:`s_curve_excitation`: without and with
    ``payload`` (different noise draws)."""
    t, q, qd, qdd = s_curve_excitation(v_max=v_max)
    return (simulate_chain(params, t, q, qd, qdd, noise=noise, seed=seed),
            simulate_chain(params, t, q, qd, qdd, payload=payload, noise=noise, seed=seed + 1))


def write_demo_recordings(directory: str | Path, **kwargs: object) -> tuple[Path, Path]:
    """Write :func:`demo_recordings` as ``chain.npz`` and ``chain_payload.npz`` in ``directory``."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = directory / "chain.npz", directory / "chain_payload.npz"
    for path, data in zip(paths, demo_recordings(**kwargs), strict=True):  # type: ignore[arg-type]
        np.savez(path, **data)
    return paths


def samples_of(recording: Mapping[str, np.ndarray], payload: Payload | None = None, *,
               use_velocity: bool = False, **kwargs: object) -> Samples:
    """:func:`prepare` on a :func:`simulate_chain` recording's columns."""
    return prepare(recording["time"], recording["position"], recording["current"], recording["torque"],
                   velocity=recording["velocity"] if use_velocity else None, payload=payload,
                   **kwargs)  # type: ignore[arg-type]


COLUMNS = {"time": "time", "position": "position", "current": "current", "torque": "torque"}
"""The default column names of a recording (:func:`load_recording`); ``velocity`` is optional."""


def load_recording(path: str | Path, columns: Mapping[str, str | None] | None = None,
                   joint: int = 0) -> dict[str, np.ndarray]:
    """The columns of an ``.npz`` recording (the Recorder's ``data()``, or :func:`write_demo_recordings`'s)
    that :func:`prepare` needs, as 1-D arrays: ``columns`` maps ``time``, ``position``, ``current``,
    ``torque`` and optionally ``velocity`` to the file's keys (defaults :data:`COLUMNS`); a 2-D column
    (ticks x joints, as the Recorder writes vector signals) gives its ``joint``-th component. Raises
    :class:`RecordingError` naming the file and the column."""
    wanted = dict(COLUMNS) | {k: v for k, v in (columns or {}).items() if v}
    try:
        loaded = np.load(path, allow_pickle=False)
        if not isinstance(loaded, np.lib.npyio.NpzFile):
            raise RecordingError(f"{path}: a single array ({type(loaded).__name__}), not an .npz archive of named "
                                 "columns (write one with numpy.savez(path, time=..., position=..., current=..., "
                                 "torque=...), or the Recorder's data())")
        with loaded as data:
            keys = list(data.keys())
            missing = [f"{role} column {key!r}" for role, key in wanted.items() if key not in keys]
            if missing:
                raise RecordingError(f"{path}: no {', no '.join(missing)} (the file has: {', '.join(keys)})")
            out = {}
            for role, key in wanted.items():
                column = np.asarray(data[key], dtype=float)
                if column.ndim == 2 and role != "time":
                    if not 0 <= joint < column.shape[1]:
                        raise RecordingError(f"{path}: column {key!r} has {column.shape[1]} components, "
                                             f"no joint {joint}")
                    column = column[:, joint]
                if column.ndim != 1:
                    raise RecordingError(f"{path}: column {key!r} has shape {column.shape}, expected one "
                                         "value per sample")
                bad = np.flatnonzero(~np.isfinite(column))
                if bad.size:
                    raise RecordingError(f"{path}: column {key!r} ({role}) is not finite at {bad.size} sample(s), "
                                         f"the first at sample {bad[0]} ({column[bad[0]]!r})")
                out[role] = column
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        if isinstance(exc, RecordingError):
            raise
        raise RecordingError(f"{path}: cannot read the recording: {exc}") from None
    return out


def identify_recordings(recording: str | Path, payload_recording: str | Path | None = None,
                        payload: Payload | None = None, *, columns: Mapping[str, str | None] | None = None,
                        joint: int = 0, drive_gain: float | None = None, **prepare_options: object,
                        ) -> Identification:
    """:func:`identify` on recordings: ``recording`` without payload and ``payload_recording`` with
    ``payload`` (or ``drive_gain`` = a known ``R K_m`` and no payload recording). ``prepare_options``
    go to :func:`prepare` (``cutoff``, ``order``, ``decimation``, ``min_velocity``, ``trim``)."""
    if (payload_recording is None) != (payload is None):
        raise RecordingError("a payload recording needs its payload's mass and arm, and the other way round")
    experiments = []
    for path, carried in ((recording, None), (payload_recording, payload)):
        if path is None:
            continue
        data = load_recording(path, columns, joint)
        try:
            experiments.append(prepare(data["time"], data["position"], data["current"], data["torque"],
                                       velocity=data.get("velocity"), payload=carried,
                                       **prepare_options))  # type: ignore[arg-type]
        except ValueError as exc:
            raise RecordingError(f"{path}: {exc}") from None
    try:
        return identify(experiments, drive_gain=drive_gain)
    except ValueError as exc:
        raise RecordingError(str(exc)) from None
