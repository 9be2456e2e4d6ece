"""Terrain: surfaces, the terrain value type, and the builders' geometry against the walking notes §1.5
(the stairs and tilted platforms meshes of hpp-environments) and the MPTC report's obstacles (our
layout under the 20 cm walk's footsteps)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dgraph.entities.walking.footsteps import terrain_walk, yaw_placement
from dgraph.entities.walking.swing import SwingPath, swing_clearances
from dgraph.entities.walking.terrain import (
    FLOOR,
    TERRAINS,
    Surface,
    Terrain,
    flat,
    obstacles,
    stairs,
    tilted_platforms,
)
from dgraph.signals.value_types import VALUE_TYPES

SIN15, COS15 = math.sin(math.radians(15.0)), math.cos(math.radians(15.0))

MESH_PADS = {
    # name: x range, y range, z range of the top face, normal; measured from the vertices of
    # hpp-environments' meshes/multicontact/plateforme_surfaces.stl (its own frame)
    "flat_1": ((0.0, 0.30), (0.0, 0.50), (0.16, 0.16), (0.0, 0.0, 1.0)),
    "tilted_1": ((0.31, 0.61), (0.2875, 0.50), (0.09806, 0.155), (0.0, SIN15, COS15)),
    "tilted_2": ((0.322, 0.61178), (0.0, 0.23), (0.10335, 0.181), (SIN15, 0.0, COS15)),
    "tilted_3": ((0.61822, 0.908), (0.21, 0.50), (0.10335, 0.181), (-SIN15, 0.0, COS15)),
    "tilted_4": ((0.62, 0.92), (0.001, 0.19419), (0.103, 0.15476), (0.0, -SIN15, COS15)),
    "flat_2": ((0.93, 1.23), (0.0, 0.50), (0.16, 0.16), (0.0, 0.0, 1.0)),
}
NOTES_TABLE = {
    # the walking notes §1.5's table (pads 1-4, rounded to the centimetre) and its flat pads
    "tilted_1": ((0.31, 0.61), (0.29, 0.50), (0.0, 0.26, 0.97)),
    "tilted_2": ((0.32, 0.61), (0.00, 0.23), (0.26, 0.0, 0.97)),
    "tilted_3": ((0.62, 0.91), (0.21, 0.50), (-0.26, 0.0, 0.97)),
    "tilted_4": ((0.62, 0.92), (0.00, 0.19), (0.0, -0.26, 0.97)),
    "flat_1": ((0.0, 0.30), (0.0, 0.5), (0.0, 0.0, 1.0)),
    "flat_2": ((0.93, 1.23), (0.0, 0.5), (0.0, 0.0, 1.0)),
}


def ranges(surface: Surface) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The x, y and z ranges of a surface's corners."""
    corners = surface.corners()
    return tuple(np.array([corners[:, k].min(), corners[:, k].max()]) for k in range(3))


def tilted(name: str, center, roll: float = 0.0, pitch: float = 0.0, half=(0.2, 0.1)) -> Surface:
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    placement = np.eye(4)
    placement[:3, :3] = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]]) @ np.array([[cp, 0, sp], [0, 1, 0],
                                                                                     [-sp, 0, cp]])
    placement[:3, 3] = center
    return Surface(name, placement, half)


# -- the builders against the sources ---------------------------------------------------------
def test_the_stairs_are_six_10cm_rises_over_30cm_treads_1m_wide_to_a_landing_at_0_6m():
    terrain = stairs(start=0.15)
    names = [s.name for s in terrain.surfaces]
    assert names == ["step_1", "step_2", "step_3", "step_4", "step_5", "landing"] and terrain.floor
    heights = [s.center[2] for s in terrain.surfaces]
    assert np.diff([0.0, *heights]) == pytest.approx([0.10] * 6, abs=1e-12)  # six rises, the first from the floor
    for k, tread in enumerate(terrain.surfaces[:5]):
        x, y, z = ranges(tread)
        # the mesh's treads, x in [0.23 + 0.3 (k - 1), ...], y in [0.3, 1.3], moved by (-0.08, -0.8)
        assert x == pytest.approx([0.15 + 0.30 * k, 0.45 + 0.30 * k], abs=1e-12)
        assert y == pytest.approx([-0.5, 0.5], abs=1e-12) and z == pytest.approx([0.1 * (k + 1)] * 2, abs=1e-12)
        assert tread.normal == pytest.approx([0.0, 0.0, 1.0])
    x, y, z = ranges(terrain.surface("landing"))
    assert x == pytest.approx([1.65, 2.65], abs=1e-12) and y == pytest.approx([-1.0, 1.0], abs=1e-12)
    assert z == pytest.approx([0.6, 0.6], abs=1e-12)
    # one riser per 0.30 m: the edges the robot meets and the heights beyond them
    assert [terrain.height_at(0.15 + 0.3 * k + 1e-6, 0.0) for k in range(6)] == pytest.approx(
        [0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    assert terrain.height_at(0.149, 0.0) == 0.0 and terrain.height_at(1.0, 0.51) == 0.0  # the floor beside


def test_the_stairs_arguments():
    terrain = stairs(steps=3, rise=0.15, tread=0.25, width=0.8, start=0.5, landing=(0.5, 0.8))
    assert [s.center[2] for s in terrain.surfaces] == pytest.approx([0.15, 0.30, 0.45])
    assert ranges(terrain.surface("landing"))[0] == pytest.approx([1.0, 1.5])
    assert [s.name for s in stairs(steps=1).surfaces] == ["landing"]
    for kwargs, message in [({"steps": 0}, "steps must be an integer >= 1"), ({"steps": 2.0}, "steps must be"),
                            ({"rise": 0.0}, "rise must be a finite number > 0"), ({"tread": -0.3}, "tread must"),
                            ({"width": math.inf}, "width must"), ({"landing": (1.0,)}, "landing must be"),
                            ({"landing": (1.0, 0.0)}, "landing width must")]:
        with pytest.raises(ValueError, match=message):
            stairs(**kwargs)
    with pytest.raises(TypeError, match="start must be a number"):
        stairs(start="0.1")


def test_the_platforms_are_the_measured_mesh_moved_to_the_robots_frame():
    start = 0.15
    terrain = tilted_platforms(start=start)
    assert [s.name for s in terrain.surfaces] == list(MESH_PADS) and terrain.floor
    shift = np.array([start, -0.25, 0.0])  # the first pad's edge at start, the centre line on y = 0
    for surface in terrain.surfaces:
        x_range, y_range, z_range, normal = MESH_PADS[surface.name]
        x, y, z = ranges(surface)
        assert x - shift[0] == pytest.approx(x_range, abs=1e-3)
        assert y - shift[1] == pytest.approx(y_range, abs=1e-3)
        assert z == pytest.approx(z_range, abs=1e-3)
        assert surface.normal == pytest.approx(normal, abs=1e-3)
        tilt = math.degrees(math.acos(surface.normal[2]))
        assert tilt == pytest.approx(0.0 if surface.name.startswith("flat") else 15.0, abs=1e-9)
        # the notes' table: the same numbers to its rounding (half a centimetre, half a hundredth)
        notes_x, notes_y, notes_normal = NOTES_TABLE[surface.name]
        assert x - shift[0] == pytest.approx(notes_x, abs=5e-3) and y - shift[1] == pytest.approx(notes_y, abs=5e-3)
        assert surface.normal == pytest.approx(notes_normal, abs=5e-3)
    true_sizes = {s.name: [2 * e for e in s.half_extents] for s in terrain.surfaces}
    assert true_sizes == {"flat_1": pytest.approx([0.30, 0.50]), "tilted_1": pytest.approx([0.30, 0.22]),
                          "tilted_2": pytest.approx([0.30, 0.23]), "tilted_3": pytest.approx([0.30, 0.29]),
                          "tilted_4": pytest.approx([0.30, 0.20]), "flat_2": pytest.approx([0.30, 0.50])}
    # the left foot (y = +0.085) crosses tilted 1 and 3, the right one (y = -0.085) tilted 2 and 4
    assert [terrain.surface_under(x, 0.085).name for x in (0.3, 0.61, 0.91, 1.23)] == [
        "flat_1", "tilted_1", "tilted_3", "flat_2"]
    assert [terrain.surface_under(x, -0.085).name for x in (0.61, 0.92)] == ["tilted_2", "tilted_4"]


def test_the_platforms_keep_their_relative_geometry_when_moved_and_stay_above_the_floor():
    reference, moved = tilted_platforms(), tilted_platforms(start=0.4, height=0.10)
    for a, b in zip(reference.surfaces, moved.surfaces, strict=True):
        assert b.corners() - a.corners() == pytest.approx(np.tile([0.25, 0.0, -0.06], (4, 1)), abs=1e-12)
        assert b.normal == pytest.approx(a.normal, abs=1e-15)
    assert tilted_platforms(height=0.062).surfaces  # the lowest edge (0.16 - 0.0981 under the flat pads) 0.1 mm up
    with pytest.raises(ValueError, match="height 0.06 m puts the lowest pad edge at -0.0019 m"):
        tilted_platforms(height=0.06)


STANDING_LEFT, STANDING_RIGHT = yaw_placement([-0.009, 0.085, 0.0]), yaw_placement([-0.009, -0.085, 0.0])
"""TALOS's soles at half-sitting: their centres (0.5 cm behind the origins) at (-0.014, +-0.085)."""


def test_the_obstacles_are_boards_of_at_most_2cm_in_the_feets_lanes():
    terrain = obstacles()
    assert [s.name for s in terrain.surfaces] == ["obstacle_1", "obstacle_2", "obstacle_3"] and terrain.floor
    assert [s.center[2] for s in terrain.surfaces] == pytest.approx([0.01, 0.02, 0.01], abs=1e-15)
    assert max(s.center[2] for s in terrain.surfaces) == pytest.approx(0.02)  # the MPTC report's maximum
    for k, (board, lane) in enumerate(zip(terrain.surfaces, (-0.085, 0.085, -0.085), strict=True)):
        x, y, _ = ranges(board)  # 0.25 m deep, 0.16 m wide, centred on the 20 cm walk's footstep k + 1
        assert x == pytest.approx([0.261 + 0.2 * k, 0.511 + 0.2 * k], abs=1e-12)
        assert y == pytest.approx([lane - 0.08, lane + 0.08], abs=1e-12) and board.normal == pytest.approx([0, 0, 1])
    # the lanes are 1 cm apart across the path's line; the robot's standing toes (x 0.091) well before
    assert terrain.surface_under(0.5, 0.0051).name == "obstacle_2" and terrain.surface_under(0.5, 0.0).name == "floor"
    assert terrain.surface_under(0.5, -0.0051).name == "obstacle_1"
    assert {terrain.surface_under(x, y).name for x in (0.0, 0.26) for y in (-0.165, 0.165)} == {"floor"}


def test_the_obstacles_arguments():
    custom = obstacles(heights=[0.005, 0.015], first_center_x=1.0, spacing=0.3, depth=0.2, width=0.1,
                       lane_half_distance=0.1, first_side="left")
    assert [ranges(s)[:2] for s in custom.surfaces] == [
        (pytest.approx([0.9, 1.1]), pytest.approx([0.05, 0.15])),
        (pytest.approx([1.2, 1.4]), pytest.approx([-0.15, -0.05]))]
    across = obstacles(heights=[0.01, 0.02], lane_half_distance=0.0, spacing=0.3, depth=0.3, width=0.6)  # old style
    assert [ranges(s)[1] for s in across.surfaces] == [pytest.approx([-0.3, 0.3])] * 2
    assert obstacles(heights=[0.01, 0.02], spacing=0.1).surfaces  # in two lanes apart, boards may overlap along x
    for kwargs, message in [({"heights": []}, "heights must be a non-empty list"),
                            ({"heights": [0.01, -0.02]}, "obstacle 2 height must be a finite number > 0"),
                            ({"heights": [True]}, "obstacle 1 height must"), ({"spacing": 0.0}, "spacing must"),
                            ({"depth": 0.0}, "depth must"), ({"width": -0.1}, "width must"),
                            ({"lane_half_distance": -0.01}, "lane_half_distance must be >= 0"),
                            ({"first_side": "middle"}, "first_side must be 'left' or 'right'"),
                            ({"spacing": 0.12}, "spacing 0.12 m makes boards 0.25 m deep"),  # one lane: 0.24 < 0.25
                            ({"width": 0.18, "spacing": 0.2}, r"and 0.18 m wide overlap \(lanes 0.17 m apart\)")]:
        with pytest.raises(ValueError, match=message):
            obstacles(**kwargs)
    with pytest.raises(TypeError, match="first_center_x must be a number"):
        obstacles(first_center_x="0.4")


def test_the_20cm_walk_steps_on_each_obstacle_and_off_it():
    terrain = obstacles()
    plan = terrain_walk(terrain, STANDING_LEFT, STANDING_RIGHT, steps=6, length=0.2)  # no sole straddles an edge
    centres = [plan.sole.center(step.placement) for step in plan.steps]
    assert [step.side for step in plan.steps] == ["left", "right"] * 3 + ["left"]
    assert [c[0] for c in centres] == pytest.approx([0.186, 0.386, 0.586, 0.786, 0.986, 1.186, 1.186], abs=1e-12)
    assert [c[2] for c in centres] == pytest.approx([0.0, 0.01, 0.02, 0.01, 0.0, 0.0, 0.0], abs=1e-15)
    assert [terrain.surface_under(c[0], c[1]).name for c in centres] == [
        "floor", "obstacle_1", "obstacle_2", "obstacle_3", "floor", "floor", "floor"]
    # the margins of a sole on its board: 2 cm along x, 1.1 cm across
    for step, board in zip(plan.steps[1:4], terrain.surfaces, strict=True):
        x, y, _ = ranges(board)
        corners = plan.sole.corners(step.placement)
        assert corners[:, 0].min() - x[0] == pytest.approx(0.02) and x[1] - corners[:, 0].max() == pytest.approx(0.02)
        assert corners[:, 1].min() - y[0] == pytest.approx(0.011) and y[1] - corners[:, 1].max() == pytest.approx(0.011)
    # a fourth board in the left lane under footstep 4 would be under the closing footstep's heel
    with pytest.raises(ValueError, match=r"step 6: .* corner \(1.0810, 0.1540\) is over 'obstacle_4'"):
        terrain_walk(obstacles(heights=(0.01, 0.02, 0.01, 0.02)), STANDING_LEFT, STANDING_RIGHT, steps=6, length=0.2)


def lateral_gap(corners: np.ndarray, board: Surface) -> float:
    """How far (m) across the path a horizontal sole's ``corners`` are from a horizontal board's
    rectangle where they overlap it along x; inf where they do not."""
    x, y, _ = ranges(board)
    if corners[:, 0].max() < x[0] or corners[:, 0].min() > x[1]:
        return math.inf
    return max(y[0] - corners[:, 1].max(), corners[:, 1].min() - y[1])


def test_a_swinging_foot_passes_the_boards_of_the_other_lane_2cm_beside_them():
    """Every swing of the 20 cm walk (:class:`SwingPath`, the flat walk's 5 cm apex), sampled every
    1 % of the swing: beside each board that is not its lift-off's or touch-down's, the sole keeps
    at least 1.5 cm across the path from it (2.1 cm: 0.085 - 0.069 + 0.085 - 0.08), and over the
    boards it steps onto or off its corners clear their edges."""
    terrain = obstacles()
    plan = terrain_walk(terrain, STANDING_LEFT, STANDING_RIGHT, steps=6, length=0.2)
    least_gaps = []  # per swing, across the path from the boards it passes
    for phase in (p for p in plan.phases if p.kind == "single"):
        path = SwingPath(phase.swing_from, phase.swing_to, phase.duration, 0.05)
        contacts = {terrain.surface_under(*plan.sole.center(p)[:2]).name for p in (phase.swing_from, phase.swing_to)}
        gaps = []
        for x in np.linspace(0.0, 1.0, 101):
            sample = path.at(x)
            corners = sample.position + plan.sole.local_corners() @ sample.rotation.T
            gaps += [lateral_gap(corners, board) for board in terrain.surfaces if board.name not in contacts]
        least_gaps.append(min(gaps))
    assert all(gap >= 0.015 for gap in least_gaps)  # every swing passes a board of the other lane (a finite gap)
    assert least_gaps == pytest.approx([0.021] * 7, abs=1e-12)
    clearances = swing_clearances(plan, terrain, 0.05)
    assert [math.isinf(c) for c in clearances] == [True, False, False, False, False, False, True]
    assert min(clearances) > 0.01  # the corners cross the boards' edges more than 1 cm above them


def test_flat_and_the_named_terrains():
    assert flat().surfaces == () and flat().floor
    assert set(TERRAINS) == {"flat", "stairs10", "platforms", "obstacles"}
    assert TERRAINS["stairs10"]().to_plain() == stairs().to_plain()
    assert TERRAINS["platforms"]().to_plain() == tilted_platforms().to_plain()


# -- surfaces -----------------------------------------------------------------------------------
def test_a_tilted_surface_height_containment_and_corners():
    pitch = math.radians(15.0)
    surface = tilted("ramp", (1.0, 0.5, 0.2), pitch=pitch, half=(0.3, 0.1))
    assert surface.normal == pytest.approx([SIN15, 0.0, COS15])
    # pitched about y by +15 degrees: the plane falls along +x at tan 15
    assert surface.height_at(1.0, 0.5) == pytest.approx(0.2)
    assert surface.height_at(1.1, 9.0) == pytest.approx(0.2 - 0.1 * math.tan(pitch))
    corners = surface.corners()
    assert [surface.height_at(x, y) for x, y, _ in corners] == pytest.approx(corners[:, 2])
    assert np.linalg.norm(corners[0] - corners[1]) == pytest.approx(0.6)  # along the slope, not its projection
    edges = np.roll(corners, -1, axis=0) - corners
    assert (np.cross(edges, np.roll(edges, -1, axis=0)) @ surface.normal > 0).all()  # counter-clockwise
    half_run = 0.3 * math.cos(pitch)  # the projection of its half length
    assert surface.contains(1.0 + half_run - 1e-6, 0.5) and not surface.contains(1.0 + half_run + 1e-6, 0.5)
    assert surface.contains(1.0, 0.59) and not surface.contains(1.0, 0.59, margin=0.02)
    assert surface.contains(*corners[2, :2])  # an edge is on the surface despite rounding


def test_a_surface_refuses_what_is_not_a_walkable_rectangle():
    with pytest.raises(ValueError, match="a surface needs a name"):
        Surface("", np.eye(4), (0.1, 0.1))
    skewed = np.eye(4)
    skewed[0, 1] = 0.1
    with pytest.raises(ValueError, match="surface 'a': the placement's rotation is not a rotation matrix"):
        Surface("a", skewed, (0.1, 0.1))
    with pytest.raises(ValueError, match="surface 'a': a placement is a 4x4 matrix"):
        Surface("a", np.eye(3), (0.1, 0.1))
    for extents in [(0.1,), (0.1, 0.0), (0.1, math.nan), (True, 0.1), "ab"]:
        with pytest.raises(ValueError, match="surface 'a': half_extents must be two numbers > 0"):
            Surface("a", np.eye(4), extents)
    with pytest.raises(ValueError, match="surface 'wall': its normal .* does not point up"):
        tilted("wall", (0, 0, 1), pitch=math.radians(100.0))
    with pytest.raises(ValueError, match="surface 'floor' is unbounded: it has no corners"):
        FLOOR.corners()


# -- the terrain ----------------------------------------------------------------------------------
def test_the_surface_under_a_point_is_the_highest_containing_it_else_the_floor():
    low = tilted("low", (0.0, 0.0, 0.1), half=(1.0, 1.0))
    high = tilted("high", (0.5, 0.0, 0.3), roll=math.radians(10.0), half=(0.2, 0.2))
    below = tilted("below", (0.0, 2.0, -0.2), half=(0.5, 0.5))
    terrain = Terrain((low, high, below))
    assert terrain.surface_under(0.5, 0.0) is high and terrain.height_at(0.5, 0.0) == pytest.approx(0.3)
    assert terrain.normal_at(0.5, 0.1) == pytest.approx([0.0, -math.sin(math.radians(10.0)), math.cos(0.1745329)])
    assert terrain.surface_under(-0.5, 0.0) is low
    assert terrain.surface_under(0.0, 2.0) is FLOOR and terrain.height_at(0.0, 2.0) == 0.0  # the floor is higher
    assert terrain.surface_under(5.0, 5.0) is FLOOR and terrain.normal_at(5.0, 5.0) == pytest.approx([0, 0, 1])
    tie = Terrain((tilted("first", (0, 0, 0.1)), tilted("second", (0, 0, 0.1))))
    assert tie.surface_under(0.0, 0.0).name == "first"
    bare = Terrain((below,), floor=False)
    assert bare.surface_under(0.0, 2.0) is below and bare.height_at(0.0, 2.0) == pytest.approx(-0.2)
    assert bare.surface_under(5.0, 5.0) is None
    with pytest.raises(ValueError, match=r"no surface under \(5.0, 5.0\) and the terrain has no floor"):
        bare.height_at(5.0, 5.0)
    with pytest.raises(ValueError, match="no surface under"):
        bare.normal_at(5.0, 5.0)
    assert terrain.surface("high") is high and terrain.surface("floor") is FLOOR
    with pytest.raises(ValueError, match="no surface named 'floor' in the terrain .*floor: False"):
        bare.surface("floor")


def test_a_terrain_refuses_duplicate_names_the_floors_name_and_other_objects():
    pad = tilted("pad", (0, 0, 0.1))
    with pytest.raises(ValueError, match="surface 1: two surfaces are named 'pad'"):
        Terrain((pad, pad))
    with pytest.raises(ValueError, match="surface 0: the name 'floor' is the floor's"):
        Terrain((tilted("floor", (0, 0, 0.1)),))
    with pytest.raises(ValueError, match="surface 0: expected a Surface, got dict"):
        Terrain(({"name": "pad"},))


# -- plain data ---------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(TERRAINS))
def test_plain_data_round_trip(name):
    terrain = TERRAINS[name]()
    plain = terrain.to_plain()
    again = Terrain.from_plain(plain)
    assert again.to_plain() == plain and again.floor == terrain.floor
    for a, b in zip(terrain.surfaces, again.surfaces, strict=True):
        assert a.name == b.name and np.array_equal(a.placement, b.placement) and a.half_extents == b.half_extents
    assert Terrain.from_plain(name).to_plain() == plain  # by name: the builder's defaults, the scene's terrain


def test_plain_data_forms_and_named_errors():
    assert VALUE_TYPES["Terrain"] is Terrain
    terrain = Terrain.from_plain({"surfaces": [{"name": "pad", "position": [1.0, 0.0, 0.05], "yaw": math.pi / 2,
                                                "half_extents": [0.2, 0.1]}]})
    assert terrain.floor and terrain.height_at(1.0, 0.15) == pytest.approx(0.05)  # yawed: 0.2 along y
    assert terrain.surface_under(1.15, 0.0).name == "floor"
    assert not Terrain.from_plain({"floor": False, "surfaces": []}).floor
    cases = [
        ("stairs", ValueError, "unknown terrain 'stairs'; known: flat, stairs10, platforms, obstacles"),
        ([], TypeError, "a terrain must be a mapping"),
        ({"surfaces": [], "slope": 1}, ValueError, "unknown key"),
        ({"floor": True}, ValueError, "a terrain needs surfaces"),
        ({"surfaces": "pad"}, TypeError, "surfaces must be a list"),
        ({"floor": "yes", "surfaces": []}, TypeError, "floor must be true or false"),
        ({"surfaces": [{"name": "pad", "position": [0, 0, 0.1]}]}, ValueError, "surface 0: half_extents is missing"),
        ({"surfaces": [{"name": "pad", "half_extents": [0.1, 0.1]}]}, ValueError, "surface 0: a placement"),
        ({"surfaces": [{"name": "pad", "position": [0, 0, 0.1], "half_extents": [0.1]}]}, ValueError,
         r"surface 0: half_extents must be \[a, b\]"),
        ({"surfaces": [{"name": "pad", "position": [0, 0, 0.1], "half_extents": [0.1, math.inf]}]}, ValueError,
         "surface 0: half_extents must be finite"),
        ({"surfaces": [{"name": "pad", "position": [0, 0, 0.1], "half_extents": [0.1, -1.0]}]}, ValueError,
         "surface 0: surface 'pad': half_extents must be two numbers > 0"),
        ({"surfaces": [{"name": "a", "position": [0, 0, 0.1], "half_extents": [1, 1]},
                       {"name": "a", "position": [0, 0, 0.1], "half_extents": [1, 1]}]}, ValueError,
         "surface 1: two surfaces are named 'a'"),
    ]
    for plain, error, message in cases:
        with pytest.raises(error, match=message):
            Terrain.from_plain(plain)


def box_corners(centre: np.ndarray, half_sizes: np.ndarray, rotation: np.ndarray, face: float) -> np.ndarray:
    """(4, 3) the corners of a box's top (``face`` 1) or bottom (-1) face, world axes."""
    local = np.array([[x, y, face] for x in (-1.0, 1.0) for y in (-1.0, 1.0)]) * half_sizes
    return centre + local @ rotation.T


@pytest.mark.parametrize("name", ["stairs10", "platforms", "obstacles"])
def test_the_box_of_each_surface_has_it_as_top_face_and_reaches_the_floor(name):
    for surface in TERRAINS[name]().surfaces:
        centre, half_sizes, rotation = surface.box()
        np.testing.assert_array_equal(rotation, surface.placement[:3, :3])
        np.testing.assert_allclose(half_sizes[:2], surface.half_extents, atol=1e-15)
        top, corners = box_corners(centre, half_sizes, rotation, 1.0), surface.corners()
        np.testing.assert_allclose(top[np.lexsort(top.T)], corners[np.lexsort(corners.T)], atol=1e-12)
        assert box_corners(centre, half_sizes, rotation, -1.0)[:, 2].max() == pytest.approx(0.0, abs=1e-12)


def test_the_box_of_a_surface_not_above_the_floor_is_its_rectangle():
    sunk = tilted("sunk", [0.0, 0.0, -0.05], pitch=0.2)
    centre, half_sizes, _ = sunk.box()
    assert half_sizes[2] == 0.0
    np.testing.assert_array_equal(centre, sunk.center)
