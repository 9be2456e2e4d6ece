"""The walking scenes (stairs10, platforms, obstacles) are the planners' terrains: rays cast down onto
the MuJoCo boxes meet the surfaces of dgraph.entities.walking.terrain; scenes compose (one floor);
TALOS loads and stands in each, before the first edge."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.walking.terrain import TERRAINS, Surface, Terrain
from dgraph_sim.device import MujocoDevice
from dgraph_sim.scenes import Scene, SceneError, add_scene, scene_names

ROOT = Path(__file__).resolve().parents[2]
WALKING_SCENES = ("stairs10", "platforms", "obstacles")
RAY_START = 2.0
"""Height (m) the rays are cast down from."""


def compiled(name: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name="gripper_left_base_link")  # the push scene's tool hangs on TALOS's gripper
    add_scene(spec, name)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return m, d


def cast_down(m: mujoco.MjModel, d: mujoco.MjData, x: float, y: float) -> tuple[float, np.ndarray, str]:
    """The height, the normal and the geom's name where a ray down through ``(x, y)`` meets the scene."""
    geom, normal = np.zeros(1, dtype=np.int32), np.zeros(3)
    distance = mujoco.mj_ray(m, d, np.array([x, y, RAY_START]), np.array([0.0, 0.0, -1.0]), None, 1, -1, geom, normal)
    assert distance >= 0.0, f"no geom under ({x}, {y})"
    return RAY_START - distance, normal, m.geom(int(geom[0])).name


def samples(surface: Surface, count: int = 5, margin: float = 0.002) -> np.ndarray:
    """A ``count`` x ``count`` grid of horizontal points over ``surface``, ``margin`` inside its edges."""
    a, b = (e - margin for e in surface.half_extents)
    u, v = np.meshgrid(np.linspace(-a, a, count), np.linspace(-b, b, count))
    local = np.column_stack([u.ravel(), v.ravel(), np.zeros(u.size)])
    return (surface.center + local @ surface.placement[:3, :3].T)[:, :2]


def check_rays(m: mujoco.MjModel, d: mujoco.MjData, terrain: Terrain) -> int:
    """Every sample over every surface: the scene's height and normal are the terrain's; returns the count."""
    count = 0
    for surface in terrain.surfaces:
        for x, y in samples(surface):
            height, normal, geom = cast_down(m, d, x, y)
            assert geom == terrain.surface_under(x, y).name == surface.name, (x, y)
            assert height == pytest.approx(terrain.height_at(x, y), abs=1e-6)
            assert normal == pytest.approx(terrain.normal_at(x, y), abs=1e-6)
            count += 1
    return count


@pytest.mark.parametrize("name", WALKING_SCENES)
def test_the_scene_surfaces_are_the_terrains(name):
    terrain = TERRAINS[name]()
    m, d = compiled(name)
    assert check_rays(m, d, terrain) == 25 * len(terrain.surfaces)
    # the robot's start and the floor beside the terrain
    for x, y in [(0.0, 0.0), (0.1, 0.3), (-1.0, 0.0), (1.0, 1.5)]:
        height, normal, geom = cast_down(m, d, x, y)
        assert geom == "floor" and height == pytest.approx(0.0, abs=1e-12) and terrain.height_at(x, y) == 0.0
        assert normal == pytest.approx(terrain.normal_at(x, y)) == [0.0, 0.0, 1.0]
    boxes = [m.geom(s.name) for s in terrain.surfaces]
    assert all(m.geom_contype[g.id] == m.geom_conaffinity[g.id] == 1 for g in boxes)  # they touch the robot


def test_the_obstacles_boards_end_at_their_edges_and_leave_the_floor_between_them():
    """1 mm outside each edge of each board (at the edge's middle) a ray meets the floor, 1 mm
    inside the board; the floor runs between the two lanes and under the 20 cm walk's footsteps 0
    and 4-6 (sole centres at x 0.186, 0.986, 1.186)."""
    terrain = TERRAINS["obstacles"]()
    m, d = compiled("obstacles")
    for board in terrain.surfaces:
        (a, b), (x, y, z) = board.half_extents, board.center
        for dx, dy in [(a, 0.0), (-a, 0.0), (0.0, b), (0.0, -b)]:
            ux, uy = np.sign(dx), np.sign(dy)
            inside = cast_down(m, d, x + dx - 1e-3 * ux, y + dy - 1e-3 * uy)
            outside = cast_down(m, d, x + dx + 1e-3 * ux, y + dy + 1e-3 * uy)
            assert inside[::2] == (pytest.approx(z, abs=1e-9), board.name)
            assert outside[::2] == (pytest.approx(0.0, abs=1e-12), "floor")
    floor_points = [(x, 0.0) for x in np.linspace(0.2, 1.0, 9)] + [(0.586, -0.085), (0.186, 0.085), (0.986, 0.085),
                                                                     (1.186, 0.085), (1.186, -0.085)]
    for x, y in floor_points:
        assert cast_down(m, d, x, y)[::2] == (pytest.approx(0.0, abs=1e-12), "floor")
        assert terrain.surface_under(x, y).name == "floor"


def test_a_box_reaches_the_floor_under_its_surface():
    """Each pad's box has the pad's rotation and reaches the floor: the highest corner of its
    bottom face is at z = 0 (the rest under it), so nothing passes under a pad."""
    terrain = TERRAINS["platforms"]()
    m, d = compiled("platforms")
    for surface in terrain.surfaces:
        geom = m.geom(surface.name)
        half = m.geom_size[geom.id]
        rotation = d.geom_xmat[geom.id].reshape(3, 3)
        bottom = [d.geom_xpos[geom.id] + rotation @ (half * [sx, sy, -1]) for sx in (-1, 1) for sy in (-1, 1)]
        assert max(p[2] for p in bottom) == pytest.approx(0.0, abs=1e-12)
        assert rotation == pytest.approx(surface.placement[:3, :3], abs=1e-9)


def test_scenes_compose_in_order_on_one_floor():
    assert scene_names("obstacles+push") == ["obstacles", "push"]
    m, d = compiled("obstacles+push")
    planes = [g for g in range(m.ngeom) if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE]
    assert [m.geom(g).name for g in planes] == ["floor"]
    assert m.body("block").id > 0 and m.geom("tool").id > 0  # the push scene's block and tool
    assert check_rays(m, d, TERRAINS["obstacles"]()) == 75  # the terrain is untouched: 3 boards x 25 rays
    assert m.nlight == 1 and m.ncam == 1


def test_scenes_that_cannot_be_built_are_named():
    for name, message in [
        ("moon", "unknown scene 'moon'; known: flat, block, stairs10, platforms, obstacles"),
        ("stairs10+moon", "unknown scene 'moon' in 'stairs10\\+moon'"),
        ("flat+obstacles+flat", "'flat\\+obstacles\\+flat' gives the scene 'flat' twice"),
        ("block+push", "scene 'push' cannot be added after 'block': .*repeated name 'block' in body"),
    ]:
        with pytest.raises(SceneError, match=message):
            compiled(name)
    spec = mujoco.MjSpec()
    spec.worldbody.add_geom(name="obstacle_1", size=[0.1, 0, 0])
    with pytest.raises(SceneError, match="scene 'obstacles' cannot be added: .*repeated name 'obstacle_1' in geom"):
        add_scene(spec, "obstacles")
    scene = Scene(mujoco.MjSpec())
    assert scene.floor() is scene.floor(friction=1.0)
    with pytest.raises(SceneError, match="two floors differ: friction 1.0, height 0.0 m, then friction 0.5"):
        scene.floor(friction=0.5)
    with pytest.raises(SceneError, match="surface 'floor' is unbounded"):
        scene.surface(Terrain().surface("floor"))
    sunk = Surface("sunk", np.diag([1.0, 1.0, 1.0, 1.0]), (0.1, 0.1))
    with pytest.raises(SceneError, match="surface 'sunk' is not above the floor"):
        scene.surface(sunk)


def test_the_device_names_a_scene_it_cannot_build():
    with pytest.raises(dg.ParamError, match="sim: parameter 'scene': unknown scene 'moon' in 'stairs10\\+moon'"):
        MujocoDevice("sim", scene="stairs10+moon")


@pytest.mark.parametrize("scene", [*WALKING_SCENES, "obstacles+push"])
def test_talos_stands_before_the_first_edge(scene):
    """``graphs/talos_standing.yaml`` in the scene for 1 s: no fall, the base within 5 mm of its start,
    and only the floor touching the robot (its toes, x <= 0.091 m, are before the first edge at 0.15 m)."""
    graph = dg.load(str(ROOT / "graphs" / "talos_standing.yaml"),
                    {"recorder.rerun": "off", "view.rerun": "off", "device.scene": scene})
    with graph:
        graph.run(ticks=1000, progress=False)
    data = graph["recorder"].data()
    assert not data["device.fallen"].any()
    base = data["device.q"][:, :3]
    assert np.abs(base - base[0]).max() < 5e-3
    device = graph["device"]
    m, d = device.mj_model, device.data
    touching = {m.geom(int(g)).name for c in d.contact[: d.ncon] for g in (c.geom1, c.geom2)
                if m.geom_bodyid[int(g)] == 0}
    assert touching == {"floor"}
    weight = sum(m.body_mass[device.sim.robot_bodies]) * 9.81
    assert data["device.contact_force_total"][-1][2] == pytest.approx(weight, rel=0.02)
