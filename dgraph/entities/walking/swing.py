"""Swing-foot trajectories: the path of a sole from lift-off to touch-down (:class:`SwingPath`) and
the :class:`SwingTrajectory` entity that samples it for one foot along a footstep plan."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.entities.references.minimum_jerk import minimum_jerk
from dgraph.entities.robot.rotations import matrix_to_quat
from dgraph.entities.walking.footsteps import FootstepPlan

_ZERO6 = np.zeros(6)
_ZERO6.setflags(write=False)

Sample = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""Position (3), quaternion xyzw (4), velocity (6), acceleration (6) of a sole reference."""


def bump(x: float) -> tuple[float, float, float]:
    """``b(x) = 64 x^3 (1 - x)^3`` and its first two derivatives in ``x``: ``b(1/2) = 1`` is its
    maximum; ``b``, ``b'`` and ``b''`` vanish at both ends (``u = x (1 - x)``: ``b = 64 u^3``,
    ``b' = 192 u^2 u'``, ``b'' = 384 u u'^2 - 384 u^2``, ``u' = 1 - 2 x``)."""
    u, du = x * (1.0 - x), 1.0 - 2.0 * x
    return 64.0 * u**3, 192.0 * u * u * du, 384.0 * u * (du * du - u)


@dataclass(frozen=True)
class SwingSample:
    """The sole at one instant of a swing: ``position`` (3), ``rotation`` (3x3), ``velocity``
    and ``acceleration`` (6: ``[p_dot, omega]`` and ``[p_ddot, omega_dot]``, world axes)."""

    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


class SwingPath:
    """The swing of a sole from the placement ``start`` (4x4, lift-off) to ``end`` (touch-down) in
    ``duration`` s, ``height`` m above the higher of the two at mid-swing. With ``x = tau / T`` the
    swing's progress, ``s`` the minimum-jerk profile and ``b`` the bump (:func:`minimum_jerk`,
    :func:`bump`)::

        p(x) = p0 + (p1 - p0) s(x) + H b(x) e_z,       H = height + |z1 - z0| / 2
        R(x) = R0 exp3(s(x) w),                         w = log3(R0^T R1)

    so ``p(1/2)`` is ``height`` above ``max(z0, z1)`` (on flat ground the apex, at mid-swing), and
    the position, the velocity and the acceleration are those of ``start`` at ``x = 0`` and of
    ``end`` at ``x = 1``, at rest (s', s'', b' and b'' vanish at both ends). ``R`` turns about the
    fixed world axis ``R0 w``, so the world angular velocity and acceleration are exactly
    ``omega = R0 w s' / T`` and ``omega_dot = R0 w s'' / T^2``; ``p_dot = ((p1 - p0) s' + H b'
    e_z) / T``, ``p_ddot = ((p1 - p0) s'' + H b'' e_z) / T^2``.
    """

    def __init__(self, start: np.ndarray, end: np.ndarray, duration: float, height: float):
        if not duration > 0.0:
            raise ValueError(f"a swing lasts > 0 s, got {duration}")
        self.duration = float(duration)
        self._p0 = np.asarray(start[:3, 3], dtype=float)
        self._dp = np.asarray(end[:3, 3], dtype=float) - self._p0
        self._lift = float(height) + 0.5 * abs(self._dp[2])
        self._r0 = np.asarray(start[:3, :3], dtype=float)
        self._w = pin.log3(self._r0.T @ np.asarray(end[:3, :3], dtype=float))
        self._axis = self._r0 @ self._w

    def at(self, x: float) -> SwingSample:
        """The sample at progress ``x`` (clipped to [0, 1])."""
        x = min(max(x, 0.0), 1.0)
        s, ds, dds = minimum_jerk(x)
        b, db, ddb = bump(x)
        period = self.duration
        position = self._p0 + self._dp * s
        position[2] += self._lift * b
        linear_velocity = self._dp * (ds / period)
        linear_velocity[2] += self._lift * db / period
        linear_acceleration = self._dp * (dds / period**2)
        linear_acceleration[2] += self._lift * ddb / period**2
        rotation = self._r0 @ pin.exp3(self._w * s)
        velocity = np.concatenate([linear_velocity, self._axis * (ds / period)])
        acceleration = np.concatenate([linear_acceleration, self._axis * (dds / period**2)])
        return SwingSample(position, rotation, velocity, acceleration)


@dg.register
class SwingTrajectory(dg.Entity):
    """The reference of one sole along a footstep plan, for a FramePose feature's reference inputs
    (its error is ``[p - p*, log3(R R*^T)]`` with world axes, its reference velocity and
    acceleration ``[p_dot*, omega*]``, ``[p_ddot*, omega_dot*]``, world axes: the conventions
    here).

    Plan time ``s = t dt - plan.start``. While the foot swings (the single support of one of its
    footsteps, progress ``x``): the :class:`SwingPath` from its lift-off placement to its
    footstep's placement over the single-support duration, ``height`` m above the higher of the
    two at mid-swing; otherwise the placement it stands on
    (:meth:`~dgraph.entities.walking.footsteps.FootstepPlan.foot_placement`), at rest.

    Parameters: ``side`` (``left`` or ``right``), ``height`` (m, default 0.05: the walking notes'
    §1.4 gap-filler, TSID's TALOS walking configuration; the thesis gives none), ``dt``.
    Input: ``plan`` (FootstepPlan).
    Outputs: ``position`` (3), ``orientation`` (quaternion xyzw), ``velocity`` (6, ``[p_dot,
    omega]``), ``acceleration`` (6, ``[p_ddot, omega_dot]``), world axes.
    """

    side = dg.Param(kind="str", choices=("left", "right"), doc="the foot: left or right")
    height = dg.Param(0.05, kind="float", minimum=0.0, doc="swing height in m above the higher of lift-off and "
                                                           "touch-down, at mid-swing")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, side: Literal["left", "right"], height: float = 0.05, dt: float | None = None,
        ) -> None: ...

    plan = dg.Input(dtype=FootstepPlan, doc="the footstep plan")

    def setup(self) -> None:
        """No sample yet; the swing paths are made per plan and phase when first needed."""
        self._last: tuple[int, FootstepPlan, Sample] | None = None  # the tick and plan of the last sample
        self._paths: dict[int, SwingPath] = {}

    def _sample(self, t: int) -> Sample:
        """Position, quaternion, velocity, acceleration at tick ``t``, computed once per tick and plan."""
        plan = self.plan(t)
        last = self._last
        if last is not None and last[0] == t and last[1] is plan:
            return last[2]
        if last is None or last[1] is not plan:
            self._paths = {}
        time = plan.time(t * self.dt)
        index, phase, progress = plan.phase_at(time)
        if phase.swing_side == self.side:
            path = self._paths.get(index)
            if path is None:
                path = self._paths[index] = SwingPath(phase.swing_from, phase.swing_to, phase.duration, self.height)
            sample = path.at(progress)
            values = (sample.position, np.array(matrix_to_quat(sample.rotation)), sample.velocity,
                      sample.acceleration)
        else:
            placement = plan.foot_placement(self.side, time)
            values = (placement[:3, 3].copy(), np.array(matrix_to_quat(placement[:3, :3])), _ZERO6, _ZERO6)
        self._last = (t, plan, values)
        return values

    @dg.output(shape=(3,), depends=("plan", "t"), labels=("x", "y", "z"))
    def position(self, t: int) -> np.ndarray:
        """Sole position p* (world)."""
        return self._sample(t)[0]

    @dg.output(shape=(4,), depends=("plan", "t"), labels=("qx", "qy", "qz", "qw"))
    def orientation(self, t: int) -> np.ndarray:
        """Sole orientation R* as a quaternion xyzw."""
        return self._sample(t)[1]

    @dg.output(shape=(6,), depends=("plan", "t"))
    def velocity(self, t: int) -> np.ndarray:
        """``[p_dot*, omega*]``, world axes."""
        return self._sample(t)[2]

    @dg.output(shape=(6,), depends=("plan", "t"))
    def acceleration(self, t: int) -> np.ndarray:
        """``[p_ddot*, omega_dot*]``, world axes."""
        return self._sample(t)[3]
