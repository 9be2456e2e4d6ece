"""Terrain: the walkable surfaces around the robot, as data that the planners and the MuJoCo scenes
share (issue 14: stairs, tilted platforms, small obstacles).

A :class:`Surface` is a rectangle: its ``placement`` (4x4) puts its centre in the world with its z
axis the outward normal of the walkable face; ``half_extents`` are its half sizes along its own x
and y. A :class:`Terrain` (a value type) is surfaces in order, over a floor (the plane z = 0) or
not. :mod:`dgraph_sim.scenes` builds its terrain scenes from the builders below (one box per
surface, whose top face is the surface), so the planners and the simulator walk on one geometry.

The builders place their terrain in the robot's frame at its start: TALOS at the origin facing +x,
z up (its sole centres at about (-0.014, +-0.085, 0) at half-sitting); ``start`` is the x of the
first edge the robot meets. :data:`TERRAINS` names them as the scenes do:

- ``flat``: :func:`flat`, the floor alone.
- ``stairs10``: :func:`stairs`, six 10 cm rises over 30 cm treads (thesis L4839), 1.0 m wide,
  a landing at 0.60 m (walking notes §1.5: hpp-environments' ``bauzil_stairs_10cm.stl``, the mesh
  of mlp's "stairs 10 cm" scenario).
- ``platforms``: :func:`tilted_platforms`, two flat pads at 0.16 m and four pads tilted by 15
  degrees (walking notes §1.5: ``plateforme_surfaces.stl``, mlp's ``talos_plateformes.py``).
- ``obstacles``: :func:`obstacles`, boards of 1 and 2 cm in the feet's lanes under the 20 cm
  walk's footsteps (the MPTC report's uneven terrain, "obstacles with a maximum height of 2cm",
  seed 000 L299-304; the layout is ours).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from dgraph.entities.walking.footsteps import (
    SIDES,
    frozen_array,
    placement_from_plain,
    plain_mapping,
    plain_number,
    rigid_transform_problem,
)
from dgraph.signals.value_types import value_type

FLOOR_NAME = "floor"
"""The name of the floor (the plane z = 0) that :meth:`Terrain.surface_under` returns; no surface takes it."""

_EDGE_TOLERANCE = 1e-9
"""Distance (m) by which a point may be outside a surface's edge and still be on it (rounding)."""


def _is_number(value: Any) -> bool:
    """True for an int or a float (numpy's too), not a bool."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _positive(value: Any, name: str) -> float:
    """``value`` as a float if it is a finite number > 0, else ValueError naming it."""
    if not (_is_number(value) and math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


@dataclass(frozen=True, eq=False)
class Surface:
    """A walkable rectangle named ``name``: ``placement`` (4x4) is its centre ``c`` and rotation
    ``R``, whose z column is the outward normal ``n`` of the walkable face (pointing up, ``n_z >
    0``); ``half_extents`` ``(a, b)`` its half sizes along ``R``'s x and y columns (m; ``inf``: an
    unbounded plane, as the floor).

    Its plane is ``n . (p - c) = 0``, so above the horizontal point ``(x, y)`` it is at height
    ``z(x, y) = c_z - (n_x (x - c_x) + n_y (y - c_y)) / n_z`` (:meth:`height_at`).

    ValueError, naming the surface, for an empty name, a placement that is not a rigid transform,
    half extents that are not two numbers > 0, or a normal that does not point up.
    """

    name: str
    placement: np.ndarray
    half_extents: tuple[float, float]

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"a surface needs a name (a non-empty string), got {self.name!r}")
        problem = rigid_transform_problem(self.placement)
        if problem:
            raise ValueError(f"surface {self.name!r}: {problem}")
        object.__setattr__(self, "placement", frozen_array(self.placement))
        extents = tuple(self.half_extents) if isinstance(self.half_extents, (Sequence, np.ndarray)) else ()
        if len(extents) != 2 or not all(_is_number(e) and e > 0.0 for e in extents):
            raise ValueError(f"surface {self.name!r}: half_extents must be two numbers > 0, got {self.half_extents!r}")
        object.__setattr__(self, "half_extents", (float(extents[0]), float(extents[1])))
        if not self.normal[2] > 0.0:
            raise ValueError(f"surface {self.name!r}: its normal {self.normal.tolist()} does not point up "
                             "(a walkable face has n_z > 0)")

    @property
    def center(self) -> np.ndarray:
        """(3,) the centre of the face in the world."""
        return self.placement[:3, 3]

    @property
    def normal(self) -> np.ndarray:
        """(3,) the outward unit normal of the face (the placement's z axis)."""
        return self.placement[:3, 2]

    @property
    def bounded(self) -> bool:
        """False for an unbounded plane (an infinite half extent)."""
        return all(math.isfinite(e) for e in self.half_extents)

    def height_at(self, x: float, y: float) -> float:
        """The height (m) of the surface's plane above ``(x, y)``, inside the rectangle or not
        (the class docstring's ``z(x, y)``)."""
        c, n = self.center, self.normal
        return float(c[2] - (n[0] * (x - c[0]) + n[1] * (y - c[1])) / n[2])

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        """True if the vertical through ``(x, y)`` meets the rectangle at least ``margin`` (m,
        along the surface) inside its edges: the point ``p = (x, y, z(x, y))`` of the plane has
        local coordinates ``u = R^T (p - c)`` with ``|u_x| <= a - margin``, ``|u_y| <= b - margin``."""
        local = self.placement[:3, :3].T @ (np.array([x, y, self.height_at(x, y)]) - self.center)
        return bool(abs(local[0]) <= self.half_extents[0] - margin + _EDGE_TOLERANCE
                    and abs(local[1]) <= self.half_extents[1] - margin + _EDGE_TOLERANCE)

    def corners(self) -> np.ndarray:
        """(4, 3) the world corners ``c + R (+-a, +-b, 0)``, counter-clockwise seen from above the
        face (as :meth:`SoleShape.local_corners`). ValueError for an unbounded plane."""
        if not self.bounded:
            raise ValueError(f"surface {self.name!r} is unbounded: it has no corners")
        a, b = self.half_extents
        local = np.array([[a, b, 0.0], [-a, b, 0.0], [-a, -b, 0.0], [a, -b, 0.0]])
        return self.center + local @ self.placement[:3, :3].T

    def box(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The box whose top face is this bounded surface and which reaches the floor (z = 0)
        under all of it, as the MuJoCo scenes build it and the recordings draw it: its centre (3,),
        half sizes (3,) and rotation (3, 3). Rotation ``R`` (the surface's), half sizes ``(a, b,
        d / 2)``, depth ``d = max_k z_k / n_z`` (``z_k`` the corners' heights, ``n`` the normal:
        the bottom face's highest corner on z = 0), centre ``c - (d / 2) n``; a surface not above
        the floor is its rectangle alone (``d = 0``)."""
        depth = max(float(self.corners()[:, 2].max()), 0.0) / self.normal[2]
        half_sizes = np.array([*self.half_extents, 0.5 * depth])
        return self.center - 0.5 * depth * self.normal, half_sizes, self.placement[:3, :3].copy()

    def to_plain(self) -> dict[str, Any]:
        """The surface as plain data that :meth:`from_plain` reads back."""
        return {"name": self.name, "placement": self.placement.tolist(), "half_extents": list(self.half_extents)}

    @classmethod
    def from_plain(cls, value: Any, where: str = "surface") -> Surface:
        """A surface from a mapping: ``name``, ``half_extents`` ``[a, b]`` (m) and ``placement``
        (4x4) or ``position`` ``[x, y, z]`` with an optional ``yaw`` (rad; a horizontal surface).
        TypeError or ValueError, naming ``where``, on anything else."""
        mapping = plain_mapping(value, where, {"name", "placement", "position", "yaw", "half_extents"})
        for key in ("name", "half_extents"):
            if key not in mapping:
                raise ValueError(f"{where}: {key} is missing")
        extents = mapping["half_extents"]
        if isinstance(extents, (str, Mapping)) or not isinstance(extents, Sequence) or len(extents) != 2:
            raise ValueError(f"{where}: half_extents must be [a, b], got {extents!r}")
        placement = placement_from_plain({k: mapping[k] for k in ("placement", "position", "yaw") if k in mapping},
                                         where)
        try:
            return cls(mapping["name"], placement, tuple(plain_number(e, f"{where}: half_extents") for e in extents))
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None


FLOOR = Surface(FLOOR_NAME, np.eye(4), (math.inf, math.inf))
"""The floor: the plane z = 0, unbounded."""


@value_type
@dataclass(frozen=True, eq=False)
class Terrain:
    """Walkable surfaces in order (``surfaces``) over the floor, the plane z = 0 (``floor``), or
    over nothing.

    Above a horizontal point ``(x, y)`` the robot stands on :meth:`surface_under`: the highest
    surface whose rectangle the vertical through the point meets (the largest
    :meth:`Surface.height_at` among those that :meth:`Surface.contains` it; the first in order on
    a tie), the floor counting as one (:data:`FLOOR`, under every point) if the terrain has it.

    ValueError for a surface that is not a :class:`Surface`, two surfaces of the same name, or a
    surface named ``floor``.
    """

    surfaces: tuple[Surface, ...] = ()
    floor: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "surfaces", tuple(self.surfaces))
        object.__setattr__(self, "floor", bool(self.floor))
        names: set[str] = set()
        for index, surface in enumerate(self.surfaces):
            if not isinstance(surface, Surface):
                raise ValueError(f"surface {index}: expected a Surface, got {type(surface).__name__}")
            if surface.name == FLOOR_NAME:
                raise ValueError(f"surface {index}: the name {FLOOR_NAME!r} is the floor's")
            if surface.name in names:
                raise ValueError(f"surface {index}: two surfaces are named {surface.name!r}")
            names.add(surface.name)

    def surface(self, name: str) -> Surface:
        """The surface named ``name`` (``floor``: :data:`FLOOR`, if the terrain has it); ValueError
        listing the names otherwise."""
        for surface in (*self.surfaces, *((FLOOR,) if self.floor else ())):
            if surface.name == name:
                return surface
        known = ", ".join(s.name for s in self.surfaces) or "none"
        raise ValueError(f"no surface named {name!r} in the terrain (surfaces: {known}; floor: {self.floor})")

    def surface_under(self, x: float, y: float) -> Surface | None:
        """The surface the robot stands on above ``(x, y)`` (see the class docstring), or None
        if there is none (a point off every surface of a terrain without a floor)."""
        best, best_height = None, -math.inf
        for surface in (*self.surfaces, *((FLOOR,) if self.floor else ())):
            if surface.contains(x, y):
                height = surface.height_at(x, y)
                if height > best_height:
                    best, best_height = surface, height
        return best

    def _under(self, x: float, y: float) -> Surface:
        """:meth:`surface_under`, ValueError naming the point if there is none."""
        surface = self.surface_under(x, y)
        if surface is None:
            raise ValueError(f"no surface under ({x}, {y}) and the terrain has no floor")
        return surface

    def height_at(self, x: float, y: float) -> float:
        """The height (m) of :meth:`surface_under` above ``(x, y)``; ValueError if there is none."""
        return self._under(x, y).height_at(x, y)

    def normal_at(self, x: float, y: float) -> np.ndarray:
        """(3,) the unit normal of :meth:`surface_under` at ``(x, y)``; ValueError if there is none."""
        return self._under(x, y).normal.copy()

    def to_plain(self) -> dict[str, Any]:
        """The terrain as plain data that :meth:`from_plain` reads back."""
        return {"floor": self.floor, "surfaces": [surface.to_plain() for surface in self.surfaces]}

    @classmethod
    def from_plain(cls, value: Any) -> Terrain:
        """A terrain from plain data: the name of a terrain of :data:`TERRAINS` (with its
        builder's defaults, as the scene of the same name), or a mapping with ``surfaces`` (a list
        of :meth:`Surface.from_plain` mappings) and optional ``floor`` (default true). TypeError or
        ValueError, naming the surface, on anything else."""
        if isinstance(value, str):
            if value not in TERRAINS:
                raise ValueError(f"unknown terrain {value!r}; known: {', '.join(TERRAINS)}")
            return TERRAINS[value]()
        mapping = plain_mapping(value, "a terrain", {"floor", "surfaces"})
        if "surfaces" not in mapping:
            raise ValueError("a terrain needs surfaces (a list, empty for the floor alone)")
        plain = mapping["surfaces"]
        if isinstance(plain, (str, Mapping)) or not isinstance(plain, Sequence):
            raise TypeError("surfaces must be a list of surfaces")
        floor = mapping.get("floor", True)
        if not isinstance(floor, bool):
            raise TypeError(f"floor must be true or false, got {floor!r}")
        return cls(tuple(Surface.from_plain(s, f"surface {i}") for i, s in enumerate(plain)), floor)


# -- builders ---------------------------------------------------------------------------------
def _rotation(roll: float, pitch: float) -> np.ndarray:
    """``Rx(roll) Ry(pitch)`` (rad)."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    about_x = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    about_y = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    return about_x @ about_y


def _placement(center: Sequence[float], roll: float = 0.0, pitch: float = 0.0) -> np.ndarray:
    """The 4x4 placement at ``center`` rotated by ``Rx(roll) Ry(pitch)``."""
    placement = np.eye(4)
    placement[:3, :3] = _rotation(roll, pitch)
    placement[:3, 3] = center
    return placement


def _box_top(name: str, x_range: tuple[float, float], y_range: tuple[float, float], height: float) -> Surface:
    """The horizontal rectangle ``x_range`` x ``y_range`` at ``height``."""
    center = (0.5 * (x_range[0] + x_range[1]), 0.5 * (y_range[0] + y_range[1]), height)
    return Surface(name, _placement(center), (0.5 * (x_range[1] - x_range[0]), 0.5 * (y_range[1] - y_range[0])))


def flat() -> Terrain:
    """The floor alone."""
    return Terrain()


FIRST_EDGE = 0.15
"""Default ``start`` (m): the first edge half a 0.30 m tread ahead of the robot. The stairs mesh's
start floor is one tread deep (x in [-0.07, 0.23], walking notes §1.5): the robot stands centred on
it as on every tread."""


def stairs(steps: int = 6, rise: float = 0.10, tread: float = 0.30, width: float = 1.0, start: float = FIRST_EDGE,
           landing: tuple[float, float] = (1.0, 2.0)) -> Terrain:
    """Stairs going up along +x, centred on y = 0, over the floor: ``steps`` rises of ``rise`` (m),
    the first riser at ``x = start``. Surface ``step_k`` (k = 1 .. steps - 1) is the tread at
    height ``k rise``, ``x`` in ``[start + (k - 1) tread, start + k tread]``, ``width`` wide; the
    last rise leads to the ``landing`` (``(depth, width)``, m) at height ``steps rise``, from
    ``x = start + (steps - 1) tread``.

    Defaults (walking notes §1.5, ``bauzil_stairs_10cm.stl``; thesis L4839: "6 stairs of 10cm
    height and 30cm long"): treads at 0.10 .. 0.50 m, 0.30 m deep, 1.0 m wide; the landing at 0.60 m,
    1.0 m deep and 2.0 m wide. The mesh's landing is 0.1 m off the treads' axis (y in [-0.3, 1.7]
    beside treads in [0.3, 1.3]); here it is centred. ValueError naming a bad argument.
    """
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    rise, tread, width = _positive(rise, "rise"), _positive(tread, "tread"), _positive(width, "width")
    if isinstance(landing, (str, Mapping)) or not isinstance(landing, Sequence) or len(landing) != 2:
        raise ValueError(f"landing must be (depth, width), got {landing!r}")
    depth, landing_width = _positive(landing[0], "landing depth"), _positive(landing[1], "landing width")
    start = plain_number(start, "start")
    treads = [_box_top(f"step_{k}", (start + (k - 1) * tread, start + k * tread), (-width / 2, width / 2), k * rise)
              for k in range(1, steps)]
    top = start + (steps - 1) * tread
    return Terrain((*treads, _box_top("landing", (top, top + depth), (-landing_width / 2, landing_width / 2),
                                      steps * rise)))


class PlatformPad(NamedTuple):
    """A pad of the platforms mesh: its top face's centre in the mesh frame (m), its half sizes
    along the face (m), and its tilt: roll about x, pitch about y (degrees)."""

    name: str
    center: tuple[float, float, float]
    half_extents: tuple[float, float]
    roll: float
    pitch: float


PLATFORM_PADS = (
    PlatformPad("flat_1", (0.15, 0.25, 0.16), (0.15, 0.25), 0.0, 0.0),
    PlatformPad("tilted_1", (0.46, 0.39375, 0.12653), (0.15, 0.11), -15.0, 0.0),
    PlatformPad("tilted_2", (0.46689, 0.115, 0.14218), (0.15, 0.115), 0.0, 15.0),
    PlatformPad("tilted_3", (0.76311, 0.355, 0.14218), (0.15, 0.145), 0.0, -15.0),
    PlatformPad("tilted_4", (0.77, 0.09759, 0.12888), (0.15, 0.10), 15.0, 0.0),
    PlatformPad("flat_2", (1.08, 0.25, 0.16), (0.15, 0.25), 0.0, 0.0),
)
"""The six pads of hpp-environments' ``plateforme_surfaces.stl`` in its frame, in walking order
(walking notes §1.5; centres, sizes and tilts measured here from its vertices: the notes' table,
pads 1-4, is them rounded to the centimetre). The set is 1.23 x 0.50 m; the flat pads, 0.30 x
0.50 m at z = 0.16, span x in [0, 0.30] and [0.93, 1.23]; the tilted pads are 0.30 m along x by
0.22, 0.23, 0.29 and 0.20 m, tilted by 15 degrees, normals (0, +sin 15, cos 15), (+sin 15, 0,
cos 15), (-sin 15, 0, cos 15), (0, -sin 15, cos 15)."""

_PADS_FLAT_HEIGHT = 0.16
"""The flat pads' height in the mesh frame (m)."""
_PADS_CENTRE_LINE = 0.25
"""The y of the platforms mesh's centre line (its pads span y in [0, 0.5])."""


def tilted_platforms(start: float = FIRST_EDGE, height: float = _PADS_FLAT_HEIGHT) -> Terrain:
    """The tilted platforms of mlp's ``talos_plateformes.py`` (:data:`PLATFORM_PADS`) over the
    floor, approached from the floor: the mesh translated, not turned, so that its first flat pad's
    front edge (mesh x = 0) is at ``x = start``, its centre line (mesh y = 0.25) on y = 0 and its
    flat pads at ``height`` (m; default 0.16, the mesh's heights unchanged). The robot steps up
    onto ``flat_1`` from the floor, crosses ``tilted_1`` and ``tilted_3`` with its left foot
    (y > 0), ``tilted_2`` and ``tilted_4`` with its right foot, and ends on ``flat_2``.

    ValueError if ``height`` puts a pad's lowest edge at or under the floor (below 0.0619 m)."""
    start, height = plain_number(start, "start"), plain_number(height, "height")
    shift = np.array([start, -_PADS_CENTRE_LINE, height - _PADS_FLAT_HEIGHT])
    surfaces = tuple(Surface(pad.name, _placement(np.add(pad.center, shift), math.radians(pad.roll),
                                                  math.radians(pad.pitch)), pad.half_extents)
                     for pad in PLATFORM_PADS)
    lowest = min(surface.corners()[:, 2].min() for surface in surfaces)
    if lowest <= 0.0:
        raise ValueError(f"height {height} m puts the lowest pad edge at {lowest:.4f} m, not above the floor")
    return Terrain(surfaces)


OBSTACLE_HEIGHTS = (0.01, 0.02, 0.01)
"""The default obstacle heights (m): at most 2 cm, the MPTC report's largest (seed 000 L299-304);
one per footstep of the 20 cm walk that stands on a board (see :func:`obstacles`)."""


def obstacles(heights: Sequence[float] = OBSTACLE_HEIGHTS, first_center_x: float = 0.386, spacing: float = 0.2,
              depth: float = 0.25, width: float = 0.16, lane_half_distance: float = 0.085,
              first_side: str = "right") -> Terrain:
    """A flat floor with low boards in the feet's lanes: board ``obstacle_k`` (k from 1) is
    ``heights[k - 1]`` high (m), ``depth`` along x by ``width`` across (m), centred on
    ``x = first_center_x + (k - 1) spacing``, ``y = +-lane_half_distance`` (``+`` the left lane),
    the lanes alternating from ``first_side``'s.

    The MPTC report places "obstacles with a maximum height of 2cm" along the walking path and
    shows them only in a figure (seed 000 L299-304); the layout is ours, made for the 20 cm
    straight walk of :func:`straight_walk` from TALOS's standing soles (centres at x = -0.014 +
    0.2 k, y = +-0.085, the left foot first): ``obstacle_k`` under footstep k, counting from 0 (the
    right foot at 0.386 m, the left at 0.586, the right at 0.786), the first footstep (the left
    foot at 0.186) and the last three (0.986, 1.186, 1.186) on the floor. Footsteps 0 and 4
    cannot stand on a board: a foot's placements 0.2 m apart (footstep 0 and the standing left
    sole, footstep 4 and the closing footstep 6) overlap by 1 cm along the 0.21 m sole, so a board
    under one would be under the other's heel or toes; footstep 5 stays on the floor so that the
    robot ends on the floor, as it starts. The 0.21 x 0.138 m sole lies 2 cm
    inside its board's front and back edges and 1.1 cm inside its sides; the foot swinging past a
    board in the other lane passes 2.1 cm beside it (its inner edge 0.016 m from the path's line,
    the board's 0.005 m on the other side). Boards of consecutive footsteps overlap along x, not
    across: in the double supports after footsteps 1 to 4 one foot stands 1 cm higher than the other.

    ValueError naming a bad argument, and naming ``spacing`` if two boards would overlap
    (:func:`_boards_overlap`)."""
    if isinstance(heights, (str, Mapping)) or not isinstance(heights, Sequence) or not heights:
        raise ValueError(f"heights must be a non-empty list of heights, got {heights!r}")
    heights = [_positive(h, f"obstacle {k} height") for k, h in enumerate(heights, start=1)]
    first_center_x, spacing = plain_number(first_center_x, "first_center_x"), _positive(spacing, "spacing")
    depth, width = _positive(depth, "depth"), _positive(width, "width")
    lane_half_distance = plain_number(lane_half_distance, "lane_half_distance")
    if lane_half_distance < 0.0:
        raise ValueError(f"lane_half_distance must be >= 0, got {lane_half_distance}")
    if first_side not in SIDES:
        raise ValueError(f"first_side must be 'left' or 'right', got {first_side!r}")
    if _boards_overlap(len(heights), spacing, depth, width, lane_half_distance):
        raise ValueError(f"spacing {spacing} m makes boards {depth} m deep and {width} m wide overlap "
                         f"(lanes {2.0 * lane_half_distance} m apart)")
    first_lane = lane_half_distance if first_side == "left" else -lane_half_distance
    boards = []
    for k, height in enumerate(heights):
        center_x, center_y = first_center_x + k * spacing, first_lane * (-1) ** k
        boards.append(_box_top(f"obstacle_{k + 1}", (center_x - depth / 2, center_x + depth / 2),
                               (center_y - width / 2, center_y + width / 2), height))
    return Terrain(tuple(boards))


def _boards_overlap(count: int, spacing: float, depth: float, width: float, lane_half_distance: float) -> bool:
    """True if two of ``count`` boards of :func:`obstacles` overlap: consecutive ones (in the two
    lanes) if ``spacing < depth`` and ``2 lane_half_distance < width``, the next but one (in one
    lane) if ``2 spacing < depth``."""
    consecutive = count > 1 and spacing < depth and 2.0 * lane_half_distance < width
    return consecutive or (count > 2 and 2.0 * spacing < depth)


TERRAINS: dict[str, Callable[[], Terrain]] = {"flat": flat, "stairs10": stairs, "platforms": tilted_platforms,
                                              "obstacles": obstacles}
"""The terrains by name, with their builders' defaults: the scenes of the same name in
:mod:`dgraph_sim.scenes` are built from them."""
