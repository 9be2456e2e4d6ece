"""Scenes: the world around the robot, added to an ``mujoco.MjSpec``.

A :class:`Scene` wraps a spec and adds a floor, blocks, stairs and tilted platforms, the surfaces
of a walking terrain, a light and a camera tracking the robot. Scene geoms collide with the robot
(``contype = conaffinity = 1``; robot geoms have ``contype = 1, conaffinity = 0``, so they touch
the scene but not each other). Named scenes (:data:`SCENES`) are what the ``scene`` parameter of
the MuJoCo device selects, one name or several joined by ``+`` (``obstacles+push``: the boards,
then the push scene's tool and block; :func:`add_scene`)::

    scene = Scene(spec)
    scene.floor(friction=1.0)
    scene.box("block", size=(0.2, 0.2, 0.2), pos=(0.6, 0.0, 0.1), free=True, mass=5.0)
    scene.stairs(steps=3, rise=0.1, run=0.3, start=(1.0, 0.0))
    scene.platform("ramp", size=(0.5, 0.5, 0.02), pos=(2.0, 0.0, 0.1), roll=0.0, pitch=0.1)
    scene.terrain(tilted_platforms())  # a box under each surface of the planners' terrain

The walking scenes ``stairs10``, ``platforms`` and ``obstacles`` are built from the terrains of
the same names (:data:`dgraph.entities.walking.terrain.TERRAINS`), so a planner reading the
terrain and the simulator share one geometry.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Sequence

import mujoco
import numpy as np

from dgraph.entities.walking.terrain import TERRAINS, Surface, Terrain

SCENE_GROUP = 0
"""Geom group of scene geoms (visible by default)."""
SCENE_SEPARATOR = "+"
"""Joins the names of scenes applied one after the other (``obstacles+push``)."""
TERRAIN_RGBA = ((0.62, 0.5, 0.38, 1.0), (0.5, 0.4, 0.3, 1.0))
"""The colours of a terrain's boxes, alternating so that neighbouring surfaces show their edges."""


class SceneError(ValueError):
    """A scene that cannot be built: an unknown name, two scenes adding elements of the same name,
    two floors that differ, a robot body that a scene needs missing."""


def _quat_from_rpy(roll: float, pitch: float, yaw: float = 0.0) -> list[float]:
    """MuJoCo quaternion ``(w, x, y, z)`` of ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    quat = np.zeros(4)
    mujoco.mju_euler2Quat(quat, np.array([roll, pitch, yaw]), "XYZ")  # uppercase: extrinsic, i.e. Rz Ry Rx
    return quat.tolist()


class Scene:
    """Builder adding scene elements to an ``MjSpec`` (each method returns the created element)."""

    def __init__(self, spec: mujoco.MjSpec):
        self.spec = spec
        self._material_added = False
        self._floor: tuple[mujoco.MjsGeom, float, float] | None = None

    def _grid_material(self) -> str:
        if not self._material_added:
            self.spec.add_texture(name="grid", type=mujoco.mjtTexture.mjTEXTURE_2D,
                                  builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, width=256, height=256,
                                  rgb1=[0.25, 0.3, 0.35], rgb2=[0.45, 0.5, 0.55])
            material = self.spec.add_material(name="grid", texrepeat=[4.0, 4.0], reflectance=0.1)
            material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "grid"
            self._material_added = True
        return "grid"

    def floor(self, friction: float = 1.0, height: float = 0.0) -> mujoco.MjsGeom:
        """An infinite plane at ``z = height`` with sliding friction ``friction``, added once: a
        second call (a scene composed of several) returns the first floor, or raises
        :class:`SceneError` if it asks for another friction or height."""
        if self._floor is not None:
            geom, first_friction, first_height = self._floor
            if (friction, height) != (first_friction, first_height):
                raise SceneError(f"two floors differ: friction {first_friction}, height {first_height} m, then "
                                 f"friction {friction}, height {height} m")
            return geom
        geom = self.spec.worldbody.add_geom(
            name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 0.05], pos=[0.0, 0.0, height],
            friction=[friction, 0.005, 0.0001], material=self._grid_material(), contype=1, conaffinity=1,
            group=SCENE_GROUP)
        self._floor = (geom, friction, height)
        return geom

    def box(self, name: str, size: Sequence[float], pos: Sequence[float], *, free: bool = False,
            mocap: bool = False, mass: float = 1.0, friction: float = 1.0, roll: float = 0.0, pitch: float = 0.0,
            yaw: float = 0.0, rgba: Sequence[float] = (0.6, 0.45, 0.3, 1.0)) -> mujoco.MjsGeom:
        """A box of full ``size`` (x, y, z) centred at ``pos``; ``free=True`` makes it a movable block,
        ``mocap=True`` a static block that a simulation can move or remove (body ``name``,
        :mod:`dgraph_sim.disturbances`)."""
        half = [s / 2.0 for s in size]
        quat = _quat_from_rpy(roll, pitch, yaw)
        if mocap:
            body = self.spec.worldbody.add_body(name=name, pos=list(pos), quat=quat, mocap=True)
            return body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=half,
                                 friction=[friction, 0.005, 0.0001], rgba=list(rgba), contype=1, conaffinity=1,
                                 group=SCENE_GROUP)
        if free:
            body = self.spec.worldbody.add_body(name=name, pos=list(pos), quat=quat)
            body.add_freejoint(name=f"{name}_free")
            return body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=half, mass=mass,
                                 friction=[friction, 0.005, 0.0001], rgba=list(rgba), contype=1, conaffinity=1,
                                 group=SCENE_GROUP)
        return self.spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=list(pos),
                                            quat=quat, friction=[friction, 0.005, 0.0001], rgba=list(rgba),
                                            contype=1, conaffinity=1, group=SCENE_GROUP)

    def stairs(self, steps: int, rise: float, run: float, start: Sequence[float] = (1.0, 0.0), width: float = 1.0,
               name: str = "step") -> list[mujoco.MjsGeom]:
        """``steps`` static steps going up along +x: step ``k`` (from 1) is a box of height ``k * rise``
        whose front edge is at ``x = start[0] + (k - 1) * run``, centred on ``y = start[1]``."""
        geoms = []
        for k in range(1, steps + 1):
            height = k * rise
            x = start[0] + (k - 0.5) * run
            geoms.append(self.box(f"{name}_{k}", size=(run, width, height), pos=(x, start[1], height / 2.0)))
        return geoms

    def platform(self, name: str, size: Sequence[float], pos: Sequence[float], roll: float = 0.0,
                 pitch: float = 0.0) -> mujoco.MjsGeom:
        """A static tilted box (full ``size``) centred at ``pos``, rotated by ``roll`` then ``pitch`` (rad)."""
        return self.box(name, size, pos, roll=roll, pitch=pitch)

    def surface(self, surface: Surface, friction: float = 1.0,
                rgba: Sequence[float] = TERRAIN_RGBA[0]) -> mujoco.MjsGeom:
        """A static box named as ``surface`` whose top face is the surface's rectangle and which
        reaches the floor (z = 0) under all of it (:meth:`Surface.box`, depth ``d``). A tilted
        box's sides lean with it: beyond the surface's high edge its side comes down to the floor
        ``d sin(tilt)`` away (4.9 cm for the platforms' 0.181 m edges), below the edge's height; a
        terrain puts the floor there. SceneError for an unbounded surface or one not above the
        floor."""
        if not surface.bounded:
            raise SceneError(f"surface {surface.name!r} is unbounded: no box has it as a face")
        highest = float(surface.corners()[:, 2].max())
        if highest <= 0.0:
            raise SceneError(f"surface {surface.name!r} is not above the floor (its highest corner at {highest} m)")
        centre, half_sizes, rotation = surface.box()
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation).reshape(-1))
        return self.spec.worldbody.add_geom(
            name=surface.name, type=mujoco.mjtGeom.mjGEOM_BOX, size=half_sizes.tolist(),
            pos=centre.tolist(), quat=quat.tolist(),
            friction=[friction, 0.005, 0.0001], rgba=list(rgba), contype=1, conaffinity=1, group=SCENE_GROUP)

    def terrain(self, terrain: Terrain, friction: float = 1.0) -> list[mujoco.MjsGeom]:
        """The floor if ``terrain`` has one (:meth:`floor`), then a box under each of its
        surfaces (:meth:`surface`), in colours alternating along them; returns the boxes."""
        if terrain.floor:
            self.floor(friction=friction)
        return [self.surface(surface, friction, TERRAIN_RGBA[index % 2])
                for index, surface in enumerate(terrain.surfaces)]

    def tool(self, body: str, start: Sequence[float], end: Sequence[float], radius: float,
             name: str = "tool") -> mujoco.MjsGeom:
        """A massless cylinder held by a robot ``body`` from ``start`` to ``end`` (body frame), touching
        the scene but not the robot, with a site ``<name>_tip`` at ``end``. Massless, so the robot's
        Pinocchio model stays exact."""
        robot_body = self.spec.body(body)
        if robot_body is None:
            raise SceneError(f"the tool {name!r} needs the robot body {body!r}, which the model does not have")
        robot_body.add_site(name=f"{name}_tip", pos=list(end), size=[0.005, 0.005, 0.005], group=4)
        return robot_body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CYLINDER, fromto=[*start, *end],
                                   size=[radius, 0.0, 0.0], mass=0.0, density=0.0, rgba=[0.2, 0.2, 0.25, 1.0],
                                   friction=[0.5, 0.005, 0.0001], contype=1, conaffinity=0, group=SCENE_GROUP)

    def wall(self, name: str, front_x: float, center: Sequence[float], size: Sequence[float],
             thickness: float = 0.02, window: Sequence[float] | None = None, friction: float = 0.5,
             ) -> list[mujoco.MjsGeom]:
        """A static vertical wall facing the robot: its front face is the plane ``x = front_x``
        (normal -x), centred at ``(y, z) = center``, ``size = (width, height)``, ``thickness`` deep.

        ``window = (y, z, side)``: a square opening of that side (m) centred at ``(y, z)`` on the
        front face, filled by a plate of the same thickness, a mocap body ``<name>_plate`` that
        :mod:`dgraph_sim.disturbances` can remove (a hole breaking through): the wall is then four
        static boxes around the window. Returns the geoms (the plate's last)."""
        cy, cz = center
        width, height = size
        x = front_x + thickness / 2.0
        rgba = (0.7, 0.72, 0.75, 1.0)
        if window is None:
            return [self.box(name, (thickness, width, height), (x, cy, cz), friction=friction, rgba=rgba)]
        wy, wz, side = window
        y0, y1, z0, z1 = cy - width / 2.0, cy + width / 2.0, cz - height / 2.0, cz + height / 2.0
        a, b, c, d = wy - side / 2.0, wy + side / 2.0, wz - side / 2.0, wz + side / 2.0
        if not (y0 < a and b < y1 and z0 < c and d < z1):
            raise ValueError(f"the window of {name!r} is not inside the wall")
        parts = [(f"{name}_left", y0, a, z0, z1), (f"{name}_right", b, y1, z0, z1),
                 (f"{name}_bottom", a, b, z0, c), (f"{name}_top", a, b, d, z1)]
        geoms = [self.box(n, (thickness, hi_y - lo_y, hi_z - lo_z), (x, (lo_y + hi_y) / 2.0, (lo_z + hi_z) / 2.0),
                          friction=friction, rgba=rgba) for n, lo_y, hi_y, lo_z, hi_z in parts]
        geoms.append(self.box(f"{name}_plate", (thickness, side, side), (x, wy, wz), mocap=True, friction=friction,
                              rgba=(0.75, 0.6, 0.35, 1.0)))
        return geoms

    def light(self, pos: Sequence[float] = (0.0, -1.0, 4.0), direction: Sequence[float] = (0.0, 0.3, -1.0),
              ) -> mujoco.MjsLight:
        """A directional light casting shadows."""
        light = self.spec.worldbody.add_light(name="sun", pos=list(pos), dir=list(direction), castshadow=True)
        light.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        light.diffuse = [0.8, 0.8, 0.8]
        return light

    def sky(self) -> mujoco.MjsTexture:
        """A gradient skybox (rendering only)."""
        return self.spec.add_texture(name="sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                                     builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, width=256, height=256,
                                     rgb1=[0.55, 0.7, 0.85], rgb2=[0.1, 0.15, 0.2])

    def tracking_camera(self, body: str, distance: float = 3.5, height: float = 0.0, tilt: float = 0.12,
                        name: str = "track") -> mujoco.MjsCamera:
        """A camera beside ``body`` (at -y, ``height`` above it, looking ``tilt`` rad down), following the
        centre of mass of the body's subtree (the whole robot for its base)."""
        return self.spec.body(body).add_camera(
            name=name, pos=[0.0, -distance, height], quat=_quat_from_rpy(np.pi / 2.0 - tilt, 0.0, 0.0),
            mode=mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM)

    def front_camera(self, distance: float = 3.5, height: float = 1.0, tilt: float = 0.12,
                     name: str = "front") -> mujoco.MjsCamera:
        """A camera fixed in the world at ``(distance, 0, height)``, looking back along -x and
        ``tilt`` rad down: lateral motion of a robot standing at the origin shows (a tracking
        camera would follow it)."""
        return self.spec.worldbody.add_camera(name=name, pos=[distance, 0.0, height],
                                              quat=_quat_from_rpy(np.pi / 2.0 - tilt, 0.0, np.pi / 2.0))


def flat(scene: Scene) -> None:
    """A flat floor (friction 1)."""
    scene.floor(friction=1.0)


def block(scene: Scene) -> None:
    """Flat floor and a 10 kg free block 0.6 m in front of the robot."""
    scene.floor(friction=1.0)
    scene.box("block", size=(0.3, 0.4, 0.5), pos=(0.6, 0.0, 0.25), free=True, mass=10.0)


def stairs10(scene: Scene) -> None:
    """The terrain ``stairs10`` (:func:`dgraph.entities.walking.terrain.stairs`): six 10 cm rises
    over 0.30 m treads, 1.0 m wide, the first riser 0.15 m ahead of the robot, the 1.0 x 2.0 m
    landing at 0.60 m (thesis L4839, the walking notes §1.5)."""
    scene.terrain(TERRAINS["stairs10"]())


def platforms(scene: Scene) -> None:
    """The terrain ``platforms`` (:func:`dgraph.entities.walking.terrain.tilted_platforms`): the
    two flat pads at 0.16 m and the four pads tilted by 15 degrees of mlp's tilted platforms, the
    first pad's edge 0.15 m ahead of the robot (the walking notes §1.5). The mesh's pads are 3 cm
    slabs in the air; here each is a solid box down to the floor."""
    scene.terrain(TERRAINS["platforms"]())


def obstacles(scene: Scene) -> None:
    """The terrain ``obstacles`` (:func:`dgraph.entities.walking.terrain.obstacles`): boards of 1,
    2 and 1 cm in the feet's lanes, under the second to fourth footsteps of the 20 cm walk (the
    MPTC report's uneven terrain, obstacles up to 2 cm)."""
    scene.terrain(TERRAINS["obstacles"]())


def slope(scene: Scene) -> None:
    """Flat floor and a platform pitched 0.1 rad, 1 m in front of the robot."""
    scene.floor(friction=1.0)
    scene.platform("slope", size=(1.0, 1.0, 0.05), pos=(1.5, 0.0, 0.05), pitch=-0.1)


PUSH_BLOCK_TOP = 0.58
"""Height (m) of the top of the ``push`` scene's block."""
LEFT_TOOL_TIP = (0.0, 0.0, -0.2)
"""The ``push`` tool's tip in TALOS's ``gripper_left_base_link`` frame (along the fingers, 8 cm
beyond their tips), where ``graphs/talos_push_tank.yaml`` puts the Pinocchio frame
``left_tool_tip``. The tool is on the gripper, beyond the wrist force/torque sensor, which
therefore measures the push."""


def push(scene: Scene) -> None:
    """TALOS's left hand holds a 0.14 m tool (a cylinder along the fingers) above a table-height block
    (0.2 x 0.2 x 0.58 m, a mocap body named ``block`` that :mod:`dgraph_sim.disturbances` can remove); the
    block's top is 2.2 cm under the tool tip at half-sitting (thesis §5.4.1)."""
    scene.floor(friction=1.0)
    scene.tool("gripper_left_base_link", start=(0.0, 0.0, -0.06), end=LEFT_TOOL_TIP, radius=0.015)
    scene.box("block", size=(0.2, 0.2, PUSH_BLOCK_TOP), pos=(0.18, 0.49, PUSH_BLOCK_TOP / 2.0), mocap=True,
              friction=0.5, rgba=(0.55, 0.6, 0.7, 1.0))


DRILL_TOOL_TIP = (0.15, 0.0, 0.06)
"""The ``drill`` tool's tip in the Panda's ``panda_hand`` frame: an angle head, 15 cm along the
hand's x axis, 6 cm down its z axis (horizontal when the hand points down), where
``graphs/panda_drill.yaml`` puts the Pinocchio frame ``tool_tip``."""
DRILL_WALL_X = 0.65
"""Front face of the ``drill`` scene's wall: the plane ``x = 0.65`` m (normal -x)."""
DRILL_HOLES = tuple((DRILL_WALL_X, -0.18 + 0.04 * k, 0.45) for k in range(10))
"""Table 6.2's ten holes between the reference holes R1 (y = -0.22) and R2 (y = +0.22) at
z = 0.45 m, 4 cm apart on the wall (scaled to the Panda's workspace; the thesis gives no spacing)."""
DRILL_BREAKTHROUGH = 5
"""The hole (index into :data:`DRILL_HOLES`) whose patch of wall is the removable plate ``wall_plate``."""


def drill(scene: Scene) -> None:
    """A Panda holding a 15 cm angle tool (a cylinder along the hand's x axis, radius 6 mm) in front of
    a vertical wall (front face ``x = 0.65`` m, 0.8 x 0.5 m, 2 cm thick, centred at ``y = 0``, ``z = 0.45`` m); the
    wall around hole :data:`DRILL_BREAKTHROUGH` is a 3 cm square plate, the mocap body ``wall_plate``,
    that a simulation removes to break the hole through (thesis Ch. 6 drilling, Table 6.2). No sensor:
    the device measures the contact force itself (``contact_force_total``)."""
    scene.floor(friction=1.0)
    scene.tool("panda_hand", start=(0.0, 0.0, 0.06), end=DRILL_TOOL_TIP, radius=0.006)
    _, y, z = DRILL_HOLES[DRILL_BREAKTHROUGH]
    scene.wall("wall", DRILL_WALL_X, center=(0.0, 0.45), size=(0.8, 0.5), window=(y, z, 0.03))


TALOS_WALL_X = 0.455
"""Front face of the ``talos_wall`` scene's wall: the plane ``x = 0.455`` m (normal -x), 5 mm in
front of the ``push`` tool's tip in ``graphs/talos_wall_push.yaml``'s initial configuration (the
tool horizontal along +x at ``(0.45, 0.35, 1.10)``)."""


def talos_wall(scene: Scene) -> None:
    """TALOS's left hand holds the ``push`` scene's tool (:data:`LEFT_TOOL_TIP`) in front of a static
    vertical wall (front face ``x = 0.455`` m, 0.3 x 0.3 m, 2 cm thick, centred at ``y = 0.35``,
    ``z = 1.10`` m) that the tool pushes along its axis (Scenario 2 of thesis Ch. 6: the standing
    robot's largest normal force)."""
    scene.floor(friction=1.0)
    scene.tool("gripper_left_base_link", start=(0.0, 0.0, -0.06), end=LEFT_TOOL_TIP, radius=0.015)
    scene.wall("wall", TALOS_WALL_X, center=(0.35, 1.10), size=(0.3, 0.3))


SCENES: dict[str, Callable[[Scene], None]] = {"flat": flat, "block": block, "stairs10": stairs10,
                                              "platforms": platforms, "obstacles": obstacles, "slope": slope,
                                              "push": push, "drill": drill, "talos_wall": talos_wall}
"""Scenes by name (the robot's light and tracking camera are added by :func:`add_scene`)."""


def scene_names(name: str) -> list[str]:
    """The scenes that ``name`` says: a name of :data:`SCENES`, or several joined by ``+``
    (:data:`SCENE_SEPARATOR`). SceneError for an unknown name or one given twice."""
    names = name.split(SCENE_SEPARATOR)
    for part in names:
        if part not in SCENES:
            raise SceneError(f"unknown scene {part!r}" + (f" in {name!r}" if len(names) > 1 else "")
                             + f"; known: {', '.join(SCENES)}")
    repeated = next((part for part, count in Counter(names).items() if count > 1), None)
    if repeated is not None:
        raise SceneError(f"{name!r} gives the scene {repeated!r} twice")
    return names


def add_scene(spec: mujoco.MjSpec, name: str, tracked_body: str | None = None) -> Scene:
    """Add the scene ``name`` to ``spec`` (several joined by ``+``: each in order, one floor;
    :func:`scene_names`), plus a light, a ``front`` camera fixed in the world and (if given) a
    ``track`` camera following ``tracked_body`` from the side. SceneError for a scene that cannot
    be built (:class:`SceneError`)."""
    names = scene_names(name)
    scene = Scene(spec)
    for index, part in enumerate(names):
        try:
            SCENES[part](scene)
        except SceneError:
            raise
        except ValueError as exc:  # MuJoCo refuses a name that the model or an earlier scene has
            after = f" after {', '.join(map(repr, names[:index]))}" if index else ""
            raise SceneError(f"scene {part!r} cannot be added{after}: {exc}") from None
    scene.light()
    scene.sky()
    scene.front_camera()
    if tracked_body is not None:
        scene.tracking_camera(tracked_body)
    return scene
