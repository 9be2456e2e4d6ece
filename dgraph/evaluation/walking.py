"""Walking evaluation (thesis §4.4.3-4.4.4): the passivity gait measure per gait stage (Table 4.9),
the ticks a walk is evaluated on, the normal-force jumps at the contact switches, the distance of
a ZMP to its support polygon's edge and the CoM jerk of a plan.

Per-tick flags (bool, one per tick) say the gait stage: ``double_support``, ``left_swing``,
``right_swing`` (a ContactScheduler's outputs of the same names); a foot is in contact when it
does not swing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgraph.evaluation.passivity import rms_torque

FEET = ("left", "right")


@dataclass(frozen=True)
class PhasePassivity:
    """The PGM of the three gait stages of Table 4.9 (NaN for a stage without a tick)."""

    double_support: float
    single_support: float
    flying_foot: float


def _ankles(torque: np.ndarray, ankles: dict[str, list[int]], selected: dict[str, np.ndarray]) -> np.ndarray:
    """Each foot's ankle columns of ``torque`` on the ticks where the foot is selected, zeros elsewhere."""
    return np.hstack([torque[:, ankles[foot]] * selected[foot][:, None] for foot in FEET])


def _stage_pgm(torque: np.ndarray, ankle_torque: np.ndarray, mask: np.ndarray) -> float:
    """``1 - RMS(ankle_torque) / RMS(torque)`` over ``mask`` (Eq. 4.17), NaN without a tick."""
    if not mask.any():
        return float("nan")
    return 1.0 - rms_torque(ankle_torque, mask) / rms_torque(torque, mask)


def phase_passivity(torque: np.ndarray, left_ankle: list[int], right_ankle: list[int], double_support: np.ndarray,
                    left_swing: np.ndarray, right_swing: np.ndarray) -> PhasePassivity:
    """The passivity gait measure ``PGM = 1 - RMS(tau_a) / RMS(tau_tot)`` (Eq. 4.17-4.18) of each
    gait stage of Table 4.9 (thesis L4912-4930), ``torque`` holding every joint (ticks x joints),
    ``left_ankle`` / ``right_ankle`` the columns of each ankle, ``tau_a`` per stage:

    - double support (the ticks of ``double_support``): both ankles;
    - single support (the ticks where a foot swings): the stance ankle, the one of the foot that
      does not swing at that tick;
    - flying foot (the same ticks): the ankle of the swinging foot.
    """
    torque = np.asarray(torque, dtype=float)
    double_support = np.asarray(double_support, dtype=bool)
    swing = {"left": np.asarray(left_swing, dtype=bool), "right": np.asarray(right_swing, dtype=bool)}
    single_support = swing["left"] | swing["right"]
    ankles = {"left": list(left_ankle), "right": list(right_ankle)}
    both = np.ones(len(torque), dtype=bool)
    stance = {"left": swing["right"], "right": swing["left"]}
    return PhasePassivity(
        double_support=_stage_pgm(torque, _ankles(torque, ankles, {"left": both, "right": both}), double_support),
        single_support=_stage_pgm(torque, _ankles(torque, ankles, stance), single_support),
        flying_foot=_stage_pgm(torque, _ankles(torque, ankles, swing), single_support))


def first_fall(fallen: np.ndarray) -> int | None:
    """The index of the first tick where ``fallen`` is true, None if the robot never fell."""
    fallen = np.asarray(fallen, dtype=bool)
    return int(np.argmax(fallen)) if fallen.any() else None


def before_fall(fallen: np.ndarray) -> np.ndarray:
    """The ticks a walk is evaluated on: true before the first fallen tick (all if it never fell)."""
    fallen = np.asarray(fallen, dtype=bool)
    fall = first_fall(fallen)
    return np.arange(len(fallen)) < (len(fallen) if fall is None else fall)


@dataclass(frozen=True)
class ForceJump:
    """The largest ``|f[k] - f[k - 1]|`` (N per tick) of one foot's normal force near the contact
    switches and its tick ``k``."""

    largest: float
    tick: int


def contact_switch_force_jumps(normal_force: np.ndarray, in_contact: np.ndarray,
                               window: int) -> list[ForceJump | None]:
    """Per foot (a column of ``normal_force``, ticks x feet, N), the largest per-tick change of
    its normal force on the ticks within ``window`` ticks of a contact switch (a tick where a
    column of ``in_contact``, ticks x feet bool, changes: a lift-off or a touch-down of any foot,
    since either one moves the load between the feet). None for a foot if no foot switches."""
    force = np.asarray(normal_force, dtype=float)
    contact = np.asarray(in_contact, dtype=bool)
    switches = np.flatnonzero((np.diff(contact.astype(int), axis=0) != 0).any(axis=1)) + 1
    if switches.size == 0:
        return [None] * force.shape[1]
    ticks = np.arange(1, len(force))
    near = (np.abs(ticks[:, None] - switches[None, :]) <= window).any(axis=1)
    changes = np.abs(np.diff(force, axis=0))
    changes[~near] = 0.0
    largest = np.argmax(changes, axis=0)
    return [ForceJump(float(changes[k, foot]), int(ticks[k])) for foot, k in enumerate(largest)]


def polygon_margin(points: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(n,) the signed distance of each point (n, 2) to the edge of its convex polygon, given as
    half-planes ``normals z <= offsets`` (n x m x 2 unit rows, n x m; a row of zeros with an
    infinite offset is no edge): ``min_j (b_j - a_j . z)``, > 0 inside, < 0 outside (there, the
    distance to the farthest violated edge's line, a lower bound of the distance to the polygon)."""
    points = np.asarray(points, dtype=float)
    slack = np.asarray(offsets, dtype=float) - np.einsum("nmk,nk->nm", np.asarray(normals, dtype=float), points)
    return slack.min(axis=1)


def jerk_statistics(acceleration: np.ndarray, dt: float) -> tuple[float, float]:
    """``(RMS, peak)`` of the jerk's norm, the jerk ``(a[k + 1] - a[k]) / dt`` from an
    acceleration sampled every ``dt`` s (ticks x axes)."""
    jerk = np.linalg.norm(np.diff(np.asarray(acceleration, dtype=float), axis=0), axis=1) / dt
    if jerk.size == 0:
        raise ValueError("the jerk needs at least two samples")
    return float(np.sqrt(np.mean(jerk**2))), float(jerk.max())
