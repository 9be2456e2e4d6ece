"""Footstep plans: the :class:`FootstepPlan` value type (the footsteps, their timing, the phases,
the ZMP reference and the support polygons derived from them) and its builders
(:func:`straight_walk`, :func:`lateral_walk`, :func:`turning_walk`; :func:`terrain_walk`, a straight
walk put on a terrain).

Conventions: placements are 4x4 homogeneous transforms of a sole frame in the world (z up; the
frame's origin on the sole, its z axis the sole's normal; TALOS's ``left_sole_link`` and
``right_sole_link``); times are in seconds from the plan's start. One foot moves at a time: a
plan is an initial double support, then for each footstep a single support (its foot swings)
and a double support after its touch-down, the last one being the final double support
(walking notes §1.9, item 1: init DS -> SS -> DS -> ... -> final DS).

The thesis flat walks (thesis L4679-4686, L4716-4724): 6 steps forward plus a final step,
single support 0.9 s, double support 0.115 s, 0.2 m (1.2 m in total) or 0.6 m per step. Where
the thesis is silent the gap-fillers of the walking notes §1.4 apply: feet 0.17 m apart (TALOS
at half-sitting has its soles 0.17 m apart, so the builders' default, keeping the initial width,
gives it).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from dgraph.entities.references.minimum_jerk import minimum_jerk
from dgraph.signals.value_types import value_type

if TYPE_CHECKING:  # terrain imports this module
    from dgraph.entities.walking.terrain import Terrain

SIDES = ("left", "right")
"""The two feet, in the order of every per-foot pair."""

_RIGID_TOLERANCE = 1e-8
"""Largest error of ``R^T R = I`` accepted in a placement."""


def other_side(side: str) -> str:
    """The other foot: ``left`` <-> ``right``."""
    return "right" if side == "left" else "left"


def yaw_placement(position: Sequence[float], yaw: float = 0.0) -> np.ndarray:
    """The 4x4 placement at ``position`` (3) rotated by ``yaw`` (rad) about the vertical."""
    cos, sin = math.cos(yaw), math.sin(yaw)
    placement = np.eye(4)
    placement[:2, :2] = [[cos, -sin], [sin, cos]]
    placement[:3, 3] = position
    return placement


def rigid_transform_problem(placement: Any) -> str | None:
    """Why ``placement`` is not a proper rigid transform (4x4, finite, last row ``[0, 0, 0, 1]``,
    rotation orthonormal with determinant +1), or None if it is one."""
    matrix = np.asarray(placement, dtype=float)
    if matrix.shape != (4, 4):
        return f"a placement is a 4x4 matrix, got shape {matrix.shape}"
    if not np.isfinite(matrix).all():
        return "the placement is not finite"
    if np.abs(matrix[3] - [0.0, 0.0, 0.0, 1.0]).max() > 0.0:
        return f"the placement's last row must be [0, 0, 0, 1], got {matrix[3].tolist()}"
    rotation = matrix[:3, :3]
    if np.abs(rotation.T @ rotation - np.eye(3)).max() > _RIGID_TOLERANCE or np.linalg.det(rotation) < 0.0:
        return "the placement's rotation is not a rotation matrix (orthonormal, determinant +1)"
    return None


def frozen_array(array: Any) -> np.ndarray:
    """A read-only float copy of ``array``."""
    copy = np.array(array, dtype=float)
    copy.setflags(write=False)
    return copy


@dataclass(frozen=True)
class SoleShape:
    """The sole rectangle in its frame: ``front`` and ``back`` of the origin along x, ``half_width``
    along y (m). Defaults: TALOS, as Contact6d's."""

    front: float = 0.10
    back: float = 0.11
    half_width: float = 0.069

    def local_corners(self) -> np.ndarray:
        """(4, 3) corners in the sole frame, counter-clockwise seen from above."""
        front, back, half = self.front, self.back, self.half_width
        return np.array([[front, half, 0.0], [-back, half, 0.0], [-back, -half, 0.0], [front, -half, 0.0]])

    def center(self, placement: np.ndarray) -> np.ndarray:
        """(3,) the rectangle's centre in the world: ``p + R [(front - back) / 2, 0, 0]``."""
        return placement[:3, 3] + placement[:3, 0] * (0.5 * (self.front - self.back))

    def corners(self, placement: np.ndarray) -> np.ndarray:
        """(4, 3) the world corners: ``p + R c_k`` for the corners ``c_k`` of :meth:`local_corners`."""
        return placement[:3, 3] + self.local_corners() @ placement[:3, :3].T


@dataclass(frozen=True, eq=False)
class Footstep:
    """One step: the foot ``side`` swings for ``single_support`` s and touches down at
    ``placement`` (4x4), then both feet stand for ``double_support`` s."""

    side: str
    placement: np.ndarray
    single_support: float
    double_support: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "placement", frozen_array(self.placement))
        object.__setattr__(self, "single_support", float(self.single_support))
        object.__setattr__(self, "double_support", float(self.double_support))

    def problem(self) -> str | None:
        """What makes this step invalid (side, placement, durations), or None."""
        if self.side not in SIDES:
            return f"side must be 'left' or 'right', got {self.side!r}"
        if not self.single_support > 0.0:
            return f"single_support must be > 0, got {self.single_support}"
        if not self.double_support >= 0.0:
            return f"double_support must be >= 0, got {self.double_support}"
        return rigid_transform_problem(self.placement)


@dataclass(frozen=True, eq=False)
class Phase:
    """One phase of a plan, from ``start`` to ``end`` (s): ``kind`` ``double`` or ``single``; the
    feet on the ground (``stance``); in single support the swinging foot, its lift-off and
    touch-down placements; the ZMP reference at the start and the end (linear in between)."""

    kind: str
    start: float
    end: float
    stance: tuple[str, ...]
    swing_side: str | None
    swing_from: np.ndarray | None
    swing_to: np.ndarray | None
    zmp_from: np.ndarray
    zmp_to: np.ndarray

    @property
    def duration(self) -> float:
        """``end - start`` (s)."""
        return self.end - self.start


@value_type
@dataclass(frozen=True, eq=False)
class FootstepPlan:
    """Where and when the feet step: the initial sole placements, the footsteps, the initial and
    final double supports (s), the sole shape and ``start``, the graph time (``t dt``, s) at which
    the plan's time 0 falls (:meth:`time`; every entity that follows the plan reads it there);
    derived: the ``phases`` and the ``duration``, in plan time.

    Phases: the initial double support ``[0, initial_double_support)``; per footstep ``i`` a single
    support (its foot swings, the other stands) then a double support of
    ``steps[i].double_support`` s; the last footstep's double support is the final one, so
    ``steps[-1].double_support == final_double_support`` (> 0) is required. After ``duration``
    the robot stands on its last placements.

    ZMP reference (piecewise linear, continuous): in single support the stance sole's centre; in
    double support linear from the previous support's centre to the next one's; the initial
    double support from the midpoint of the two sole centres to the first stance sole's centre,
    the final one from the last stance sole's centre to the final midpoint; after the end the
    final midpoint. The reference is a point in space (the sole centres with their heights): the
    MPC tracks its horizontal part; its height (:meth:`zmp_height`) is the plane the ZMP is
    constrained in. On flat ground that is the ground. In a double support between two heights
    (a stair, a pad) it is the horizontal plane through the point moving on the segment from
    the previous stance sole centre to the next, and the support polygon (:meth:`support_polygon`)
    is the convex hull of both soles projected onto it: the ZMP of contact forces normal to
    horizontal soles is the force-weighted mean of their points of application, inside that hull
    on any horizontal plane, and a tangential force ``f_t`` at a sole ``dz`` away from the plane
    moves it by ``f_t dz / f_n`` (at most ``mu dz``). The CoM is carried over
    :meth:`support_height`, a smooth profile of the stance heights.

    Raises ValueError (naming the step index) on construction for a bad side, a placement that is
    not a rigid transform, ``single_support <= 0``, ``double_support < 0``, a last double support
    other than ``final_double_support``, ``final_double_support <= 0``,
    ``initial_double_support < 0`` or a plan without footsteps.
    """

    initial_left: np.ndarray
    initial_right: np.ndarray
    steps: tuple[Footstep, ...]
    initial_double_support: float
    final_double_support: float
    sole: SoleShape = SoleShape()
    start: float = 0.0
    phases: tuple[Phase, ...] = field(init=False)
    duration: float = field(init=False)
    _feet: tuple[dict[str, np.ndarray], ...] = field(init=False, repr=False)
    _starts: list[float] = field(init=False, repr=False)
    _zmp_table: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] = field(init=False, repr=False)
    _polygons: dict[int, tuple[np.ndarray, np.ndarray, float]] = field(init=False, repr=False)
    _support_keyframes: tuple[list[float], list[float]] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        set_field = object.__setattr__
        set_field(self, "initial_left", frozen_array(self.initial_left))
        set_field(self, "initial_right", frozen_array(self.initial_right))
        set_field(self, "steps", tuple(self.steps))
        set_field(self, "initial_double_support", float(self.initial_double_support))
        set_field(self, "final_double_support", float(self.final_double_support))
        set_field(self, "start", float(self.start))
        self._validate()
        phases, feet = self._derive_phases()
        set_field(self, "phases", phases)
        set_field(self, "_feet", feet)
        set_field(self, "duration", phases[-1].end)
        set_field(self, "_starts", [phase.start for phase in phases])
        set_field(self, "_zmp_table", (np.array(self._starts), np.array([phase.end for phase in phases]),
                                       np.array([phase.zmp_from for phase in phases]),
                                       np.array([phase.zmp_to for phase in phases])))
        set_field(self, "_polygons", {})
        set_field(self, "_support_keyframes", self._keyframes())

    def _keyframes(self) -> tuple[list[float], list[float]]:
        """The keyframes of :meth:`support_height`: times (s, increasing) and heights (m)."""
        times, heights = [0.0], [float(self._midpoint(self._feet[0])[2])]
        for phase in self.phases:
            if phase.kind == "single":
                times.append(0.5 * (phase.start + phase.end))
                heights.append(float(phase.zmp_from[2]))
        times.append(self.duration)
        heights.append(float(self.final_midpoint()[2]))
        return times, heights

    def _validate(self) -> None:
        """ValueError on the first problem, naming the step (see the class docstring)."""
        for name in ("initial_left", "initial_right"):
            problem = rigid_transform_problem(getattr(self, name))
            if problem:
                raise ValueError(f"{name}: {problem}")
        if not self.steps:
            raise ValueError("a plan needs at least one footstep")
        if not self.start >= 0.0:
            raise ValueError(f"start must be >= 0, got {self.start}")
        if not self.initial_double_support >= 0.0:
            raise ValueError(f"initial_double_support must be >= 0, got {self.initial_double_support}")
        if not self.final_double_support > 0.0:
            raise ValueError(f"final_double_support must be > 0, got {self.final_double_support}")
        for index, step in enumerate(self.steps):
            if not isinstance(step, Footstep):
                raise ValueError(f"step {index}: expected a Footstep, got {type(step).__name__}")
            problem = step.problem()
            if problem:
                raise ValueError(f"step {index}: {problem}")
        last = self.steps[-1].double_support
        if last != self.final_double_support:
            raise ValueError(f"step {len(self.steps) - 1}: the double support after the last touch-down is the final "
                             f"one, final_double_support = {self.final_double_support}, got {last}")

    def _derive_phases(self) -> tuple[tuple[Phase, ...], tuple[dict[str, np.ndarray], ...]]:
        """The phases, and the placements of both feet during each (a swinging foot's: its lift-off)."""
        feet = {"left": self.initial_left, "right": self.initial_right}
        centre = self.sole.center
        start_midpoint = self._midpoint(feet)
        first_stance = centre(feet[other_side(self.steps[0].side)])
        time = self.initial_double_support
        phases = [Phase("double", 0.0, time, SIDES, None, None, None, start_midpoint, first_stance)]
        feet_per_phase = [dict(feet)]
        for index, step in enumerate(self.steps):
            stance = other_side(step.side)
            support = centre(feet[stance])
            phases.append(Phase("single", time, time + step.single_support, (stance,), step.side, feet[step.side],
                                step.placement, support, support))
            feet_per_phase.append(dict(feet))
            time += step.single_support
            feet[step.side] = step.placement
            if index + 1 < len(self.steps):
                next_support = centre(feet[other_side(self.steps[index + 1].side)])
            else:
                next_support = self._midpoint(feet)
            phases.append(Phase("double", time, time + step.double_support, SIDES, None, None, None, support,
                                next_support))
            feet_per_phase.append(dict(feet))
            time += step.double_support
        return tuple(phases), tuple(feet_per_phase)

    def _midpoint(self, feet: Mapping[str, np.ndarray]) -> np.ndarray:
        """(3,) the midpoint of the two sole centres."""
        return 0.5 * (self.sole.center(feet["left"]) + self.sole.center(feet["right"]))

    # -- queries -----------------------------------------------------------------------------
    def phase_index(self, time: float) -> int:
        """The index of the phase at ``time``: the last phase starting at or before it (so a
        zero-length double support is never current); 0 before the start."""
        return max(bisect.bisect_right(self._starts, time) - 1, 0)

    def phase_at(self, time: float) -> tuple[int, Phase, float]:
        """The phase at ``time``: its index, itself and the progress in [0, 1] (before 0: the
        first phase, progress 0; from ``duration`` on: the last one, progress 1)."""
        index = self.phase_index(time)
        phase = self.phases[index]
        if phase.duration > 0.0:
            progress = min(max((time - phase.start) / phase.duration, 0.0), 1.0)
        else:  # a zero-length first phase, before the start or at it
            progress = 0.0 if time < phase.start else 1.0
        return index, phase, progress

    def stance_placements(self, time: float) -> dict[str, np.ndarray]:
        """The feet on the ground at ``time`` (both in double support and after the end), side -> 4x4."""
        index = self.phase_index(time)
        feet = self._feet[index]
        return {side: feet[side] for side in self.phases[index].stance}

    def foot_placement(self, side: str, time: float) -> np.ndarray:
        """Where the foot ``side`` stands at ``time``, or, during its swing, where it lifted off."""
        return self._feet[self.phase_index(time)][side]

    def zmp_reference(self, times: np.ndarray) -> np.ndarray:
        """(n, 2) the ZMP reference at ``times`` (s): ``z_from + x (z_to - z_from)`` in the phase
        at each time, ``x`` its progress (see the class docstring)."""
        return self._zmp_points(times)[:, :2]

    def zmp_height(self, times: np.ndarray) -> np.ndarray:
        """(n,) the height of the plane the ZMP is in at ``times`` (s): that of the reference point
        moving on the segment between the phase's sole centres, as :meth:`zmp_reference` moves
        (in single support the stance sole centre's height; in a double support between two
        heights linear from the previous support's to the next one's; see the class docstring)."""
        return self._zmp_points(times)[:, 2]

    def zmp_height_at(self, time: float) -> tuple[float, float]:
        """:meth:`zmp_height` at one ``time`` (s) and its time derivative (m/s: the slope of a double
        support between two heights, else 0)."""
        phase = self.phases[self.phase_index(time)]
        rise = float(phase.zmp_to[2] - phase.zmp_from[2])
        if rise == 0.0 or phase.duration <= 0.0 or not phase.start <= time < phase.end:
            return float(phase.zmp_to[2] if time >= phase.end else phase.zmp_from[2]), 0.0
        return float(phase.zmp_from[2]) + rise * (time - phase.start) / phase.duration, rise / phase.duration

    def _zmp_points(self, times: np.ndarray) -> np.ndarray:
        """(n, 3) the reference point ``p_from + x (p_to - p_from)`` of the phase at each time."""
        times = np.asarray(times, dtype=float).reshape(-1)
        starts, ends, zmp_from, zmp_to = self._zmp_table
        index = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(starts) - 1)
        length = ends[index] - starts[index]
        reached = (times >= ends[index]).astype(float)  # the progress of a zero-length phase
        progress = np.clip(np.divide(times - starts[index], length, out=reached, where=length > 0.0), 0.0, 1.0)
        return zmp_from[index] + progress[:, None] * (zmp_to[index] - zmp_from[index])

    def support_height(self, time: float) -> tuple[float, float, float]:
        """The height ``g`` of the support the CoM is carried over at ``time`` (s), and its first
        two time derivatives: a minimum-jerk move between the keyframes ``(0, initial midpoint
        height)``, ``(middle of each single support, stance sole centre height)`` and ``(duration,
        final midpoint height)``, constant before the first and after the last. The CoM rises or
        descends with it from the middle of one single support to the middle of the next, so over
        a 10 cm stair with 1.6 s single and 0.3 s double supports its vertical acceleration stays
        below 5.8 x 0.1 / 1.9^2 = 0.16 m/s^2 (1.6 % of g, which the LIPM neglects)."""
        times, heights = self._support_keyframes
        k = bisect.bisect_right(times, time)
        if k == 0:
            return float(heights[0]), 0.0, 0.0
        if k == len(times):
            return float(heights[-1]), 0.0, 0.0
        span = times[k] - times[k - 1]
        change = heights[k] - heights[k - 1]
        s, ds, dds = minimum_jerk((time - times[k - 1]) / span)
        return float(heights[k - 1] + change * s), float(change * ds / span), float(change * dds / span**2)

    def support_polygon(self, time: float, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Half-planes ``(A (m, 2), b (m,))``, ``A z <= b``, of the support polygon at ``time``: the
        convex hull of the horizontal projections of the corners of the soles on the ground, each
        edge moved inwards by ``margin`` (m). Rows have unit norm, so ``b - A z`` is the distance
        of ``z`` to each edge. ValueError if ``margin < 0`` or if the shrunk polygon is empty
        (``margin`` at least the radius of the largest disc inside the polygon)."""
        if margin < 0.0:
            raise ValueError(f"margin must be >= 0, got {margin}")
        index = self.phase_index(time)
        if index not in self._polygons:
            self._polygons[index] = self._polygon(index)
        normals, offsets, inradius = self._polygons[index]
        if margin >= inradius:
            raise ValueError(f"margin {margin} m leaves nothing of the support polygon at t = {time} s "
                             f"(its largest inscribed disc has radius {inradius:.4f} m)")
        return normals, offsets - margin

    def _polygon(self, index: int) -> tuple[np.ndarray, np.ndarray, float]:
        """The hull's half-planes for phase ``index`` and the radius of its largest inscribed disc."""
        feet = self._feet[index]
        points = np.vstack([self.sole.corners(feet[side])[:, :2] for side in self.phases[index].stance])
        hull = convex_hull(points)
        edges = np.roll(hull, -1, axis=0) - hull
        normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.linalg.norm(edges, axis=1)[:, None]
        offsets = np.einsum("ij,ij->i", normals, hull)
        normals.setflags(write=False)
        return normals, offsets, inscribed_radius(normals, offsets)

    def time(self, seconds: float) -> float:
        """Plan time (s, what the phases count in) at graph time ``seconds`` (``t dt``): ``seconds - start``."""
        return seconds - self.start

    def ground_height(self) -> float:
        """The mean height of the two initial soles: the ground the CoM height is counted from."""
        return 0.5 * float(self.initial_left[2, 3] + self.initial_right[2, 3])

    def final_midpoint(self) -> np.ndarray:
        """(3,) the midpoint of the two final sole centres (where the robot ends)."""
        feet = self._feet[-1]
        return 0.5 * (self.sole.center(feet["left"]) + self.sole.center(feet["right"]))

    # -- plain data --------------------------------------------------------------------------
    def to_plain(self) -> dict[str, Any]:
        """The plan as plain data (lists, numbers, strings) that :meth:`from_plain` reads back."""
        return {"initial_left": self.initial_left.tolist(), "initial_right": self.initial_right.tolist(),
                "steps": [{"side": s.side, "placement": s.placement.tolist(), "single_support": s.single_support,
                           "double_support": s.double_support} for s in self.steps],
                "initial_double_support": self.initial_double_support,
                "final_double_support": self.final_double_support,
                "sole": {"front": self.sole.front, "back": self.sole.back, "half_width": self.sole.half_width},
                "start": self.start}

    @classmethod
    def from_plain(cls, value: Any) -> FootstepPlan:
        """A plan from plain data (a graph file's mapping): ``initial_left``, ``initial_right``
        (placements), ``steps`` (a list of footsteps: ``side``, a placement, ``single_support``,
        ``double_support``, optional for the last step, which takes ``final_double_support``),
        ``initial_double_support``, ``final_double_support``, optional ``sole`` (``front``,
        ``back``, ``half_width``) and ``start`` (s, default 0). A placement is a 4x4 nested list (``placement``), or
        ``position`` [x, y, z] with an optional ``yaw`` (rad, default 0). TypeError or ValueError
        (naming the step) on anything else."""
        known = {"initial_left", "initial_right", "steps", "initial_double_support", "final_double_support", "sole",
                 "start"}
        mapping = plain_mapping(value, "a footstep plan", known)
        missing = sorted(known - {"sole", "start"} - set(mapping))
        if missing:
            raise ValueError(f"a footstep plan needs {', '.join(missing)}")
        final = plain_number(mapping["final_double_support"], "final_double_support")
        plain_steps = mapping["steps"]
        if isinstance(plain_steps, (str, Mapping)) or not isinstance(plain_steps, Sequence):
            raise TypeError("steps must be a list of footsteps")
        steps = [footstep_from_plain(step, index, double_support=final if index == len(plain_steps) - 1 else None)
                 for index, step in enumerate(plain_steps)]
        sole = SoleShape(**{key: plain_number(number, f"sole.{key}") for key, number in
                            plain_mapping(mapping.get("sole", {}), "sole", {"front", "back", "half_width"}).items()})
        return cls(placement_from_plain(mapping["initial_left"], "initial_left"),
                   placement_from_plain(mapping["initial_right"], "initial_right"), tuple(steps),
                   plain_number(mapping["initial_double_support"], "initial_double_support"), final, sole,
                   plain_number(mapping.get("start", 0.0), "start"))


def footstep_from_plain(value: Any, index: int, single_support: float | None = None,
                        double_support: float | None = None) -> Footstep:
    """Footstep ``index`` from a mapping: ``side``; ``placement`` (4x4) or ``position`` [x, y, z]
    and ``yaw`` (rad, default 0); ``single_support`` and ``double_support`` (s; the arguments
    are the defaults when the mapping has none). ValueError or TypeError naming the step."""
    where = f"step {index}"
    mapping = plain_mapping(value, where, {"side", "placement", "position", "yaw", "single_support", "double_support"})
    durations = {"single_support": single_support, "double_support": double_support}
    for key in durations:
        if key in mapping:
            durations[key] = plain_number(mapping[key], f"{where}: {key}")
        elif durations[key] is None:
            raise ValueError(f"{where}: {key} is missing")
    if "side" not in mapping:
        raise ValueError(f"{where}: side is missing")
    placement = placement_from_plain({k: mapping[k] for k in ("placement", "position", "yaw") if k in mapping},
                                     where)
    step = Footstep(mapping["side"], placement, durations["single_support"], durations["double_support"])
    problem = step.problem()
    if problem:
        raise ValueError(f"{where}: {problem}")
    return step


def placement_from_plain(value: Any, where: str) -> np.ndarray:
    """A 4x4 placement from a nested list, or a mapping with ``placement`` (4x4) or ``position``
    [x, y, z] and an optional ``yaw`` (rad)."""
    if isinstance(value, Mapping):
        if "placement" in value:
            if set(value) != {"placement"}:
                raise ValueError(f"{where}: give a placement or a position and a yaw, not both")
            return placement_from_plain(value["placement"], where)
        if "position" not in value:
            raise ValueError(f"{where}: a placement (4x4) or a position [x, y, z] is missing")
        position = np.asarray(value["position"], dtype=float)
        if position.shape != (3,):
            raise ValueError(f"{where}: position must be [x, y, z], got {value['position']!r}")
        return yaw_placement(position, plain_number(value.get("yaw", 0.0), f"{where}: yaw"))
    placement = np.asarray(value, dtype=float)
    problem = rigid_transform_problem(placement)
    if problem:
        raise ValueError(f"{where}: {problem}")
    return placement


def plain_mapping(value: Any, where: str, known: set[str]) -> Mapping[str, Any]:
    """``value`` if it is a mapping with only ``known`` keys (TypeError, ValueError otherwise)."""
    if not isinstance(value, Mapping):
        raise TypeError(f"{where} must be a mapping, got {type(value).__name__}")
    unknown = sorted(set(value) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(map(str, unknown))} (known: {', '.join(sorted(known))})")
    return value


def plain_number(value: Any, where: str) -> float:
    """``value`` as a finite float (TypeError for a non-number, ValueError for a non-finite one)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{where} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{where} must be finite, got {value}")
    return float(value)


# -- geometry ---------------------------------------------------------------------------------
def convex_hull(points: np.ndarray) -> np.ndarray:
    """(k, 2) the vertices of the convex hull of ``points`` (n, 2), counter-clockwise, without
    collinear points (Andrew's monotone chain)."""
    ordered = sorted(map(tuple, np.asarray(points, dtype=float)))

    def half(sequence: list[tuple[float, float]]) -> list[tuple[float, float]]:
        chain: list[tuple[float, float]] = []
        for point in sequence:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], point) <= 0.0:
                chain.pop()
            chain.append(point)
        return chain[:-1]

    return np.array(half(ordered) + half(ordered[::-1]))


def _cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    """The z of ``(a - o) x (b - o)``: > 0 for a left turn."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def inscribed_radius(normals: np.ndarray, offsets: np.ndarray) -> float:
    """The radius of the largest disc inside ``{z : A z <= b}`` (unit rows): ``max r`` subject to
    ``A z + r <= b``. Its optimum has three active constraints, so it is the best feasible
    solution of the 3x3 systems ``A_i z + r = b_i`` over the triples of edges."""
    best = 0.0
    count = len(offsets)
    system = np.ones((3, 3))
    for i in range(count):
        for j in range(i + 1, count):
            for k in range(j + 1, count):
                system[:, :2] = normals[[i, j, k]]
                if abs(np.linalg.det(system)) < 1e-12:
                    continue
                solution = np.linalg.solve(system, offsets[[i, j, k]])
                if solution[2] > best and (normals @ solution[:2] + solution[2] <= offsets + 1e-12).all():
                    best = float(solution[2])
    return best


# -- builders ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class _WalkFrame:
    """The frame a walk is laid out in: origin between the initial sole origins, x along their
    mean heading; ``width`` the lateral distance between the soles."""

    origin: np.ndarray
    yaw: float
    width: float

    @classmethod
    def of(cls, initial_left: np.ndarray, initial_right: np.ndarray, width: float | None) -> _WalkFrame:
        left, right = np.asarray(initial_left, dtype=float), np.asarray(initial_right, dtype=float)
        heading = left[:2, 0] + right[:2, 0]
        yaw = math.atan2(heading[1], heading[0])
        origin = 0.5 * (left[:3, 3] + right[:3, 3])
        lateral = np.array([-math.sin(yaw), math.cos(yaw)])
        frame = cls(origin, yaw, float(lateral @ (left[:2, 3] - right[:2, 3])) if width is None else float(width))
        if not frame.width > 0.0:
            raise ValueError(f"the feet must be apart, left of right: width {frame.width} m")
        return frame

    def along(self, placement: np.ndarray) -> float:
        """The coordinate of a sole origin along the walk's heading."""
        return float(np.array([math.cos(self.yaw), math.sin(self.yaw)]) @ (placement[:2, 3] - self.origin[:2]))

    def sole(self, side: str, x: float = 0.0, y: float = 0.0, yaw: float = 0.0) -> np.ndarray:
        """The placement of foot ``side`` on the path point ``(x, y)`` of the walk frame, whose
        heading is turned by ``yaw``: the foot ``width / 2`` to its side of the path, yawed with it."""
        offset = (0.5 if side == "left" else -0.5) * self.width
        x, y = x - math.sin(yaw) * offset, y + math.cos(yaw) * offset
        cos, sin = math.cos(self.yaw), math.sin(self.yaw)
        return yaw_placement(self.origin + np.array([cos * x - sin * y, sin * x + cos * y, 0.0]), self.yaw + yaw)


def _plan(initial_left: np.ndarray, initial_right: np.ndarray, targets: Sequence[tuple[str, np.ndarray]],
          single_support: float, double_support: float, initial_double_support: float,
          final_double_support: float, sole: SoleShape) -> FootstepPlan:
    """The plan stepping to ``targets`` (side, placement) in turn, every step with the same
    durations, the last one followed by the final double support."""
    last = len(targets) - 1
    steps = tuple(Footstep(side, placement, single_support, final_double_support if i == last else double_support)
                  for i, (side, placement) in enumerate(targets))
    return FootstepPlan(initial_left, initial_right, steps, initial_double_support, final_double_support, sole)


def _check_count(steps: int) -> None:
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")


def _check_side(side: str) -> None:
    if side not in SIDES:
        raise ValueError(f"first_side must be 'left' or 'right', got {side!r}")


def straight_walk(initial_left: np.ndarray, initial_right: np.ndarray, *, steps: int = 6, length: float = 0.2,
                  width: float | None = None, first_side: str = "left", half_first: bool = True,
                  half_last: bool = True, single_support: float = 0.9, double_support: float = 0.115,
                  initial_double_support: float = 1.0, final_double_support: float = 1.0,
                  sole: SoleShape = SoleShape()) -> FootstepPlan:
    """A straight walk along the initial feet's mean heading: ``steps`` steps of ``length`` (m)
    and a closing step, ``steps + 1`` footsteps in all, the feet alternating from ``first_side``.

    Rule (by the distance each foot travels along the heading): a regular step is a stride of
    ``2 length`` (the foot lands ``length`` ahead of the other one, the robot advancing
    ``length``); a half step is a stride of ``length`` (the robot advancing ``length / 2``).
    The first step is a half step if ``half_first``, the closing step (the trailing foot) one if
    ``half_last``, which puts it beside the leading foot; every other step is regular. From the
    feet side by side with both halves (the defaults) the footprints land at ``length``,
    ``2 length``, ..., ``steps length`` ahead and the closing step beside the last one: the robot
    advances ``steps length`` (6 x 0.2 m: 1.2 m, the thesis' 20 cm walk of 6 steps and a final
    step, L4679-4686; 6 x 0.6 m its 60 cm walk, L4716-4724). ``half_first = False`` suits a start
    with the first foot ``length`` behind the other (where a plan with ``half_last = False``
    ends: its trailing foot lands ``length`` ahead instead of beside).

    Feet ``width`` apart (default: their initial lateral distance; 0.17 m on TALOS, the walking
    notes' §1.4 gap-filler), flat (yaw of the heading only), at the height of the initial
    midpoint. Timing: every step ``single_support`` then ``double_support`` (s), the last followed
    by ``final_double_support``; ``initial_double_support`` before the first lift-off.
    """
    targets = _straight_targets(initial_left, initial_right, steps, length, width, first_side, half_first, half_last)
    return _plan(initial_left, initial_right, targets, single_support, double_support, initial_double_support,
                 final_double_support, sole)


def _straight_targets(initial_left: np.ndarray, initial_right: np.ndarray, steps: int, length: float,
                      width: float | None, first_side: str, half_first: bool, half_last: bool,
                      lateral_offset: float = 0.0) -> list[tuple[str, np.ndarray]]:
    """The footsteps (side, flat placement) of :func:`straight_walk`, in order, on a path
    ``lateral_offset`` (m) to the left of the initial feet's midline."""
    _check_count(steps)
    _check_side(first_side)
    frame = _WalkFrame.of(initial_left, initial_right, width)
    along = {"left": frame.along(initial_left), "right": frame.along(initial_right)}
    targets = []
    side = first_side
    for index in range(steps):
        along[side] += length if index == 0 and half_first else 2.0 * length
        targets.append((side, frame.sole(side, along[side], lateral_offset)))
        side = other_side(side)
    along[side] = along[other_side(side)] + (0.0 if half_last else length)
    targets.append((side, frame.sole(side, along[side], lateral_offset)))
    return targets


GAITS = ("alternate", "step_to")
"""How :func:`terrain_walk` lays its footsteps: those of :func:`straight_walk`, or a step-to gait."""


def terrain_walk(terrain: Terrain, initial_left: np.ndarray, initial_right: np.ndarray, *, steps: int = 6,
                 length: float = 0.2, width: float | None = None, first_side: str = "left", half_first: bool = True,
                 half_last: bool = True, single_support: float = 0.9, double_support: float = 0.115,
                 initial_double_support: float = 1.0, final_double_support: float = 1.0,
                 sole: SoleShape = SoleShape(), margin: float = 0.0, gait: str = "alternate",
                 lateral_offset: float = 0.0) -> FootstepPlan:
    """:func:`straight_walk` on a terrain: the same footsteps in the horizontal plane and the same
    timing (every argument but ``terrain``, ``margin`` and ``gait`` as there), each footstep put on
    the surface under its sole centre (:meth:`Terrain.surface_under`).

    ``gait``: ``alternate`` (:func:`straight_walk`'s footsteps, the feet passing each other, so
    on stairs one tread per footstep and two per stride) or ``step_to`` (``steps`` times: the
    ``first_side`` foot moves ``length`` ahead of both, then the other joins it side by side;
    ``2 steps`` footsteps, on stairs one tread per pair, the way a careful climber goes:
    ``half_first`` and ``half_last`` are not read). ``lateral_offset`` (m) moves every footstep
    that far to the left of the walk's line (the first steps step sideways by it): the tilted
    platforms' pads are not symmetric about the robot's path.

    A flat footstep of heading ``h`` (its x axis) and sole centre ``(c_x, c_y)``
    (:meth:`SoleShape.center`) on the surface of normal ``n`` becomes the sole frame ``R = [x, y, n]``
    with ``x = (h - (h . n) n) / |h - (h . n) n|`` (the heading projected onto the surface's
    plane), ``y = n x x``, its centre ``c = (c_x, c_y, z(c_x, c_y))`` on the plane (the height of
    :meth:`Surface.height_at`) and its origin ``c - x (front - back) / 2``. On a floor at the
    initial feet's height the plan is :func:`straight_walk`'s.

    ValueError naming the step index and the surface if the four sole corners of a footstep are
    not all on that surface, at least ``margin`` (m) inside its edges (:meth:`Surface.contains`)
    with no higher surface over any of them (the foot straddles an edge, e.g. a stair's: change
    ``length`` or the terrain's ``start``), or if there is no surface under a sole centre.
    """
    if gait == "step_to":
        targets = _step_to_targets(initial_left, initial_right, steps, length, width, first_side, lateral_offset)
    elif gait == "alternate":
        targets = _straight_targets(initial_left, initial_right, steps, length, width, first_side, half_first,
                                    half_last, lateral_offset)
    else:
        raise ValueError(f"gait must be one of {', '.join(GAITS)}, got {gait!r}")
    on_terrain = [(side, _on_surface(terrain, placement, sole, margin, index))
                  for index, (side, placement) in enumerate(targets)]
    return _plan(initial_left, initial_right, on_terrain, single_support, double_support, initial_double_support,
                 final_double_support, sole)


def _step_to_targets(initial_left: np.ndarray, initial_right: np.ndarray, steps: int, length: float,
                     width: float | None, first_side: str, lateral_offset: float) -> list[tuple[str, np.ndarray]]:
    """The footsteps (side, flat placement) of a step-to gait: ``steps`` times the ``first_side``
    foot ``length`` ahead of the foremost foot, then the other beside it, on a path
    ``lateral_offset`` (m) to the left of the initial feet's midline."""
    _check_count(steps)
    _check_side(first_side)
    frame = _WalkFrame.of(initial_left, initial_right, width)
    along = max(frame.along(initial_left), frame.along(initial_right))
    targets = []
    for _ in range(steps):
        along += length
        targets += [(side, frame.sole(side, along, lateral_offset)) for side in (first_side, other_side(first_side))]
    return targets


def _on_surface(terrain: Terrain, placement: np.ndarray, sole: SoleShape, margin: float, index: int) -> np.ndarray:
    """The flat ``placement`` of footstep ``index`` put on the surface under its sole centre (see
    :func:`terrain_walk`); ValueError naming the step and the surface if the sole is not wholly on it."""
    centre = sole.center(placement)
    surface = terrain.surface_under(centre[0], centre[1])
    if surface is None:
        raise ValueError(f"step {index}: no surface under the sole centre ({centre[0]:.4f}, {centre[1]:.4f})")
    normal = surface.normal
    heading = placement[:3, 0] - (placement[:3, 0] @ normal) * normal
    heading /= np.linalg.norm(heading)
    on_surface = np.eye(4)
    on_surface[:3, :3] = np.column_stack([heading, np.cross(normal, heading), normal])
    on_surface[:3, 3] = [centre[0], centre[1], surface.height_at(centre[0], centre[1])]
    on_surface[:3, 3] -= heading * (0.5 * (sole.front - sole.back))
    for corner in sole.corners(on_surface):
        under = terrain.surface_under(corner[0], corner[1])
        if not surface.contains(corner[0], corner[1], margin) or under is None or under.name != surface.name:
            where = ("off every surface" if under is None else f"over {under.name!r}" if under.name != surface.name
                     else f"within {margin} m of its edge")
            raise ValueError(f"step {index}: the sole is not wholly on surface {surface.name!r} (margin {margin} m): "
                             f"its corner ({corner[0]:.4f}, {corner[1]:.4f}) is {where}")
    return on_surface


def lateral_walk(initial_left: np.ndarray, initial_right: np.ndarray, *, steps: int, length: float,
                 width: float | None = None, single_support: float = 0.9, double_support: float = 0.115,
                 initial_double_support: float = 1.0, final_double_support: float = 1.0,
                 sole: SoleShape = SoleShape()) -> FootstepPlan:
    """A sideways walk of ``steps`` steps of ``length`` (m, signed: > 0 to the left of the
    initial heading): each step moves the foot on the side of the motion ``length`` sideways,
    then the other foot ``length`` too, so ``2 steps`` footsteps in all, the robot moving
    ``steps length`` sideways with the feet ``width`` apart (default: their initial lateral
    distance), flat, each foot keeping its initial position along the heading. Timing as
    :func:`straight_walk`.
    """
    _check_count(steps)
    frame = _WalkFrame.of(initial_left, initial_right, width)
    along = {"left": frame.along(initial_left), "right": frame.along(initial_right)}
    leading = "left" if length >= 0.0 else "right"
    targets = []
    for index in range(1, steps + 1):
        for side in (leading, other_side(leading)):
            targets.append((side, frame.sole(side, along[side], index * length)))
    return _plan(initial_left, initial_right, targets, single_support, double_support, initial_double_support,
                 final_double_support, sole)


def turning_walk(initial_left: np.ndarray, initial_right: np.ndarray, *, steps: int, angle_per_step: float,
                 length: float = 0.0, width: float | None = None, first_side: str | None = None,
                 single_support: float = 0.9, double_support: float = 0.115, initial_double_support: float = 1.0,
                 final_double_support: float = 1.0, sole: SoleShape = SoleShape()) -> FootstepPlan:
    """A walk along an arc (a turn in place for ``length = 0``): the path point starts between
    the initial soles with their mean heading and, per step, advances ``length`` (m) along its
    heading then turns by ``angle_per_step`` (rad, > 0 to the left). Footstep ``k = 1..steps``
    puts its foot on the path point ``k``, ``width / 2`` to its side and yawed with the path (the
    feet alternate from ``first_side``, default the side of the turn: the left foot first for a
    left turn, so the feet open away from each other); a closing step puts the other foot on the
    last path point: ``steps + 1`` footsteps, a heading change of ``steps angle_per_step``. With
    ``angle_per_step = 0`` the footprints are those of :func:`straight_walk`'s defaults. Width,
    flatness and timing as :func:`straight_walk`.
    """
    _check_count(steps)
    first_side = first_side or ("left" if angle_per_step >= 0.0 else "right")
    _check_side(first_side)
    frame = _WalkFrame.of(initial_left, initial_right, width)
    x = y = heading = 0.0
    targets = []
    side = first_side
    for _ in range(steps):
        x, y = x + length * math.cos(heading), y + length * math.sin(heading)
        heading += angle_per_step
        targets.append((side, frame.sole(side, x, y, heading)))
        side = other_side(side)
    targets.append((side, frame.sole(side, x, y, heading)))
    return _plan(initial_left, initial_right, targets, single_support, double_support, initial_double_support,
                 final_double_support, sole)
