"""Swing-foot trajectories: the path of a sole from lift-off to touch-down (:class:`SwingPath`), the
:class:`SwingTrajectory` entity that samples it for one foot along a footstep plan, and the
clearance of swings over a terrain (:func:`swing_clearance`, :func:`swing_clearances`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.entities.references.minimum_jerk import minimum_jerk
from dgraph.entities.robot.rotations import matrix_to_quat
from dgraph.entities.walking.footsteps import FootstepPlan, SoleShape

if TYPE_CHECKING:  # terrain imports footsteps, as this module does
    from dgraph.entities.walking.terrain import Terrain

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
    ``duration`` s, ``height`` m above the higher of the two at mid-swing, lifting off along the
    start's normal and landing along the end's for the fraction ``lift`` of the swing at each end.

    With ``x = tau / T`` the swing's progress, ``s`` the minimum-jerk profile, ``b`` the bump
    (:func:`minimum_jerk`, :func:`bump`), ``p0``, ``R0``, ``n0`` (its z axis) the start's position,
    rotation and normal, ``p1``, ``R1``, ``n1`` the end's, ``l = lift`` in [0, 0.5)::

        sigma(x) = clip((x - l) / (1 - 2 l), 0, 1),      S(x) = s(sigma(x))
        p(x) = p0 + (p1 - p0) S(x) + ((1 - S(x)) n0 + S(x) n1) H b(x)
        R(x) = R0 exp3(S(x) w),                           w = log3(R0^T R1)
        H = (height + |z1 - z0| / 2) / ((n0_z + n1_z) / 2)

    so ``p(1/2)`` is ``height`` above ``max(z0, z1)`` (``S(1/2) = 1/2``, ``b(1/2) = 1``). For
    ``x`` in ``[0, l]``, ``S = 0``: the sole moves along ``n0`` only (``p - p0 = n0 H b``) and does
    not turn; for ``x`` in ``[1 - l, 1]``, ``S = 1``: it lands along ``n1`` (``p - p1 = n1 H b``)
    with the rotation ``R1``. The multicontact-locomotion-planning TALOS configurations move the
    foot normal to the surface for 0.2 s of a 1.4 s single support, 1.6 s on the stairs and the
    platforms (``l`` 0.125 to 0.14; walking notes §1.3); the thesis gives no swing. During the lift
    the sole rises ``H b(l)`` along ``n0`` (4.7 % of ``H`` at ``l = 0.1``, 13 % at 0.15). With
    ``l = 0`` and vertical normals this is the minimum-jerk swing with the vertical bump
    ``H b e_z`` of the flat walks, bit for bit on a floor of constant height.

    Derivatives in ``x`` (the time derivatives are these over ``T`` and ``T^2``), with ``dp = p1 -
    p0``, ``dn = n1 - n0``, ``S' = s'(sigma) / (1 - 2 l)``, ``S'' = s''(sigma) / (1 - 2 l)^2``
    (zero outside ``(l, 1 - l)``, where ``s'`` and ``s''`` vanish at both ends of ``sigma``)::

        p'  = dp S' + n0 H b' + dn H (S' b + S b')
        p'' = dp S'' + n0 H b'' + dn H (S'' b + 2 S' b' + S b'')

    All vanish at ``x = 0`` and ``x = 1``: the path leaves ``start`` and reaches ``end`` at rest.
    ``R`` turns about the fixed world axis ``R0 w``, so the world angular velocity and
    acceleration are exactly ``omega = R0 w S' / T`` and ``omega_dot = R0 w S'' / T^2``.

    ValueError for ``duration <= 0``, ``lift`` outside [0, 0.5), or normals whose mean does not
    point up (``n0_z + n1_z <= 0``).
    """

    def __init__(self, start: np.ndarray, end: np.ndarray, duration: float, height: float, lift: float = 0.0):
        if not duration > 0.0:
            raise ValueError(f"a swing lasts > 0 s, got {duration}")
        if not 0.0 <= lift < 0.5:
            raise ValueError(f"lift is a fraction of the swing in [0, 0.5), got {lift}")
        self.start, self.end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
        self.duration, self.lift = float(duration), float(lift)
        self._transfer = 1.0 - 2.0 * self.lift
        normal0, normal1 = self.start[:3, 2], self.end[:3, 2]
        mean_up = 0.5 * (normal0[2] + normal1[2])
        if not mean_up > 0.0:
            raise ValueError(f"the normals {normal0.tolist()} and {normal1.tolist()} do not point up on average")
        self._p0 = self.start[:3, 3]
        displacement = self.end[:3, 3] - self._p0
        self._rise = (float(height) + 0.5 * abs(displacement[2])) / mean_up
        self._r0 = self.start[:3, :3]
        self._w = pin.log3(self._r0.T @ self.end[:3, :3])
        # rows: dp, n0, dn, [0, R0 w]; at() weighs them for the position and the 6D derivatives
        self._basis = np.zeros((4, 6))
        self._basis[0, :3], self._basis[1, :3], self._basis[2, :3] = displacement, normal0, normal1 - normal0
        self._basis[3, 3:] = self._r0 @ self._w

    def at(self, x: float) -> SwingSample:
        """The sample at progress ``x`` (clipped to [0, 1])."""
        x = min(max(x, 0.0), 1.0)
        transfer = self._transfer
        s, ds, dds = minimum_jerk(min(max((x - self.lift) / transfer, 0.0), 1.0))
        ds, dds = ds / transfer, dds / (transfer * transfer)
        b, db, ddb = bump(x)
        rise, period = self._rise, self.duration
        hb, hdb, hddb = rise * b, rise * db, rise * ddb
        squared = period**2
        weights = np.array([[s, hb, s * hb, 0.0],
                            [ds / period, hdb / period, (ds * hb + s * hdb) / period, ds / period],
                            [dds / squared, hddb / squared, (dds * hb + 2.0 * ds * hdb + s * hddb) / squared,
                             dds / squared]])
        rows = weights @ self._basis
        return SwingSample(self._p0 + rows[0, :3], self._r0 @ pin.exp3(self._w * s), rows[1], rows[2])


@dg.register
class SwingTrajectory(dg.Entity):
    """The reference of one sole along a footstep plan, for a FramePose feature's reference inputs
    (its error is ``[p - p*, log3(R R*^T)]`` with world axes, its reference velocity and
    acceleration ``[p_dot*, omega*]``, ``[p_ddot*, omega_dot*]``, world axes: the conventions
    here).

    Plan time ``s = t dt - plan.start``. While the foot swings (the single support of one of its
    footsteps, progress ``x``): the :class:`SwingPath` from its lift-off placement to its
    footstep's placement over the single-support duration, ``height`` m above the higher of the
    two at mid-swing, lifting off along the lift-off sole's normal and landing along the
    footstep's for the fraction ``lift`` of the swing at each end; otherwise the placement it
    stands on (:meth:`~dgraph.entities.walking.footsteps.FootstepPlan.foot_placement`), at rest.

    Parameters: ``side`` (``left`` or ``right``), ``height`` (m, default 0.05: the walking notes'
    §1.4 gap-filler, TSID's TALOS walking configuration; the thesis gives none), ``lift`` (a
    fraction of the swing in [0, 0.5), default 0: no normal phase, the flat walks' swing; mlp's
    0.2 s of normal motion in a 1.4-1.6 s single support is 0.125-0.14, walking notes §1.3;
    :func:`swing_clearance` checks a choice against a terrain), ``dt``.
    Input: ``plan`` (FootstepPlan).
    Outputs: ``position`` (3), ``orientation`` (quaternion xyzw), ``velocity`` (6, ``[p_dot,
    omega]``), ``acceleration`` (6, ``[p_ddot, omega_dot]``), world axes.
    """

    side = dg.Param(kind="str", choices=("left", "right"), doc="the foot: left or right")
    height = dg.Param(0.05, kind="float", minimum=0.0, doc="swing height in m above the higher of lift-off and "
                                                           "touch-down, at mid-swing")
    lift = dg.Param(0.0, kind="float", minimum=0.0, maximum=0.5, doc="fraction of the swing, at each end, in which "
                                                                     "the sole moves along its normal only (< 0.5)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, side: Literal["left", "right"], height: float = 0.05, lift: float = 0.0,
            dt: float | None = None,
        ) -> None: ...

    plan = dg.Input(dtype=FootstepPlan, doc="the footstep plan")

    def configure(self) -> None:
        """ParamError for ``lift = 0.5`` (a swing with no time to move across)."""
        if not self.lift < 0.5:
            raise dg.ParamError(f"{self.name}: parameter 'lift' must be < 0.5, got {self.lift}", entity=self.name)

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
                path = self._paths[index] = SwingPath(phase.swing_from, phase.swing_to, phase.duration, self.height,
                                                       self.lift)
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


def swing_clearance(path: SwingPath, terrain: Terrain, sole: SoleShape, samples: int = 200) -> float:
    """The least height (m) of the sole's four corners above the terrain while it swings along
    ``path``: at the progresses ``x = i / samples`` (``0 < i < samples``), each corner ``q`` of
    ``sole`` at the path's placement counts ``q_z - h(q_x, q_y)``, ``h`` the height of the surface
    under it (:meth:`Terrain.surface_under`; nothing under it: it does not count), except over
    the two contact surfaces, those under the sole's centre at lift-off and at touch-down, where
    the sole is meant to be close: there a corner counts only where it crosses onto or off the
    surface (the surface under it differs at the previous or next progress: the top edge of a
    step it passes over) or lies under it. ``math.inf`` if nothing counts (a swing over one surface
    that stays above it). Sampled: an edge under the middle of a sole whose corners are over
    lower ground, or crossed between two samples, is not seen; ``samples`` sets the spacing."""
    placements = [path.at(x) for x in np.linspace(0.0, 1.0, samples + 1)]
    contact = {terrain.surface_under(*sole.center(placement)[:2]) for placement in (path.start, path.end)}
    least = math.inf
    for local in sole.local_corners():
        corners = [sample.position + sample.rotation @ local for sample in placements]
        under = [terrain.surface_under(corner[0], corner[1]) for corner in corners]
        for i in range(1, samples):
            surface = under[i]
            if surface is None:
                continue
            gap = corners[i][2] - surface.height_at(corners[i][0], corners[i][1])
            crossing = surface is not under[i - 1] or surface is not under[i + 1]
            if surface not in contact or crossing or gap < 0.0:
                least = min(least, float(gap))
    return least


def swing_clearances(plan: FootstepPlan, terrain: Terrain, height: float, lift: float = 0.0,
                     samples: int = 200) -> list[float]:
    """:func:`swing_clearance` of each footstep's swing in ``plan`` (the :class:`SwingPath` that
    :class:`SwingTrajectory` follows with these ``height`` and ``lift``), with the plan's sole, in
    the order of the footsteps."""
    return [swing_clearance(SwingPath(phase.swing_from, phase.swing_to, phase.duration, height, lift), terrain,
                            plan.sole, samples)
            for phase in plan.phases if phase.kind == "single"]
