"""WalkingView: a walk in Rerun's 3D view (the terrain, the planned footprints, the current support
polygon, the planned and measured ZMP, the CoM and the DCM on the ground)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

import dgraph as dg
from dgraph.entities.recording.rerun_stream import (
    RerunStream,
    open_stream_for,
)
from dgraph.entities.recording.robot_view import quaternions_xyzw
from dgraph.entities.recording.stream_view import StreamView
from dgraph.entities.walking.footsteps import SIDES, FootstepPlan, convex_hull
from dgraph.entities.walking.terrain import Terrain, flat

FOOT_COLORS = {"left": (40, 110, 230), "right": (230, 90, 40)}
"""The colour of each foot's footprints (RGB)."""
SUPPORT_POLYGON_COLOR = (40, 170, 60)
POINT_COLORS = {
    "zmp_reference": (250, 190, 0),
    "zmp_measured": (220, 30, 30),
    "com_reference": (150, 150, 150),
    "com_measured": (20, 20, 20),
    "dcm_reference": (170, 60, 200),
}
"""The point inputs, drawn on the ground in these colours (RGB) when plugged or set."""
FOOTPRINT_RADIUS = 0.003
SUPPORT_POLYGON_RADIUS = 0.005
POINT_RADIUS = 0.015
"""Line half-widths and point radii, in metres."""
INITIAL_LABEL = "start"
"""The label of the initial footprints (a footstep's is its index in the plan)."""
TERRAIN_COLORS = ((158, 128, 97), (128, 102, 76))
"""The colours of the terrain's boxes (RGB), alternating along its surfaces as in the MuJoCo scenes."""


def closed_strip(vertices: np.ndarray) -> np.ndarray:
    """``vertices`` (k, 3) followed by the first one again: a closed line strip (k + 1, 3)."""
    return np.vstack([vertices, vertices[:1]])


def footprint_strips(plan: FootstepPlan) -> dict[str, tuple[list[np.ndarray], list[str]]]:
    """Per foot, the closed outlines (5, 3) of its planned soles (``plan.sole.corners`` of each
    placement: the initial one, then its footsteps in order) and their labels (``start``, then
    the footstep's index in ``plan.steps``)."""
    strips: dict[str, tuple[list[np.ndarray], list[str]]] = {}
    for side, placement in zip(SIDES, (plan.initial_left, plan.initial_right), strict=True):
        strips[side] = ([closed_strip(plan.sole.corners(placement))], [INITIAL_LABEL])
    for index, step in enumerate(plan.steps):
        outlines, labels = strips[step.side]
        outlines.append(closed_strip(plan.sole.corners(step.placement)))
        labels.append(str(index))
    return strips


def support_polygon(plan: FootstepPlan, time: float) -> tuple[np.ndarray, float]:
    """The support polygon at plan time ``time`` (s) as a closed strip (k + 1, 3) and the ground
    height: the convex hull (counter-clockwise, no collinear vertex) of the horizontal projections
    of the stance soles' corners (``plan.sole.corners`` of ``plan.stance_placements(time)``),
    each hull vertex at the height of its corner (on a tread or a tilted pad the outline of a
    sole in single support is the sole's own); the ground height ``z_g`` is the mean height of
    the stance sole origins."""
    stance = plan.stance_placements(time).values()
    corners = np.vstack([plan.sole.corners(placement) for placement in stance])
    ground = float(np.mean([placement[2, 3] for placement in stance]))
    hull = convex_hull(corners[:, :2])
    nearest = np.linalg.norm(hull[:, None, :] - corners[None, :, :2], axis=2).argmin(axis=1)
    return closed_strip(np.column_stack([hull, corners[nearest, 2]])), ground


@dg.register
class WalkingView(StreamView, dg.Entity):
    """Shows a walk in Rerun's 3D view, under the entity path ``path`` (default ``world/walking``).

    Static, at the first tick (again if the plugged terrain changes): ``<path>/terrain``, the
    terrain's bounded surfaces (not the floor: the :class:`~dgraph.entities.recording.RobotView`
    draws one), each as the solid box that :mod:`dgraph_sim.scenes` puts under it
    (:meth:`~dgraph.entities.walking.terrain.Surface.box`: its top face the surface, tilted with
    it, reaching the floor; labelled with the surface's name, colours alternating). Nothing for
    a terrain without surfaces (the default, the floor alone).

    Static, when a plan is first drawn (again if the plugged plan changes): every planned
    footprint, ``<path>/footprints/left`` and ``<path>/footprints/right`` (one colour per foot),
    a closed line strip through the four sole corners ``p + R c_k`` of
    :meth:`~dgraph.entities.walking.footsteps.SoleShape.corners` (5 vertices, the first one
    repeated), labelled ``start`` for the initial feet and with its index in ``plan.steps`` for a
    footstep, at the soles' real heights and tilts.

    Every ``decimation`` ticks (and at the first tick), on the ``tick`` and ``time`` timelines,
    at plan time ``s = t dt - plan.start`` (the :class:`~dgraph.entities.walking.FootstepPlanner`'s ``start``):

    * ``<path>/support_polygon``: the convex hull of the horizontal projections of the corners
      of the stance soles (``plan.stance_placements(s)``; both feet in double support), each
      vertex at its corner's height, a closed line strip: the polygon the ZMP must stay in
      (walking notes §1.9, item 3), on a tread or a tilted pad the stance sole's outline;
    * ``<path>/<input>``, for each point input plugged or set (an unplugged one is not drawn):
      the point ``(x, y, z_g)`` of the input ``(x, y, z)``, ``z_g`` the mean height of the stance
      sole origins: the ground projection of the planned ZMP, the measured ZMP, the planned CoM,
      the planned DCM (``xi = c + c_dot / omega``, thesis Eqs. 2.27-2.28) and the measured CoM,
      each its own entity so that the viewer shows or hides it alone.

    Like the :class:`~dgraph.entities.recording.RobotView` it reads in :meth:`observe`, keeps
    what it read when the tick commits, buffers and sends every ``flush_every`` ticks (one
    ``send_columns`` per entity), and writes into the graph's shared recording
    (:func:`~dgraph.entities.recording.rerun_stream.open_stream_for`).

    Parameters: ``decimation``, ``path``
    (entity path prefix), ``rerun`` (``save`` | ``spawn`` | ``serve`` | ``off``; not given: as the
    :class:`~dgraph.entities.recording.Recorder`'s, ``save`` if ``rrd_path`` is given, else the
    session's default, nothing for the library), ``rrd_path``, ``flush_every``, ``dt`` (default:
    the graph's). Inputs: ``plan`` (:class:`~dgraph.entities.walking.footsteps.FootstepPlan`),
    ``terrain`` (:class:`~dgraph.entities.walking.terrain.Terrain`, default
    :func:`~dgraph.entities.walking.terrain.flat`), and, each optional, ``zmp_reference``,
    ``zmp_measured``, ``com_reference``, ``dcm_reference``, ``com_measured`` (3, world). No
    outputs: the loop calls it every tick as an observer.
    """

    observes = True
    path = dg.Param("world/walking", kind="str", doc="Rerun entity path prefix of the walk")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, decimation: int = 20, rerun: Literal["off", "save", "spawn", "serve"] | None = None,
            rrd_path: str | None = None, flush_every: int | None = None, path: str = "world/walking",
            dt: float | None = None,
        ) -> None: ...

    plan = dg.Input(dtype=FootstepPlan, doc="the footstep plan")
    terrain = dg.Input(dtype=Terrain, default=flat(), doc="the terrain, drawn once (default: the floor alone)")
    zmp_reference = dg.Input(shape=(3,), default=np.zeros(3), doc="planned ZMP (world; drawn if plugged or set)")
    zmp_measured = dg.Input(shape=(3,), default=np.zeros(3), doc="measured ZMP (world; drawn if plugged or set)")
    com_reference = dg.Input(shape=(3,), default=np.zeros(3), doc="planned CoM (world; drawn if plugged or set)")
    dcm_reference = dg.Input(shape=(3,), default=np.zeros(3), doc="planned DCM (world; drawn if plugged or set)")
    com_measured = dg.Input(shape=(3,), default=np.zeros(3), doc="measured CoM (world; drawn if plugged or set)")

    def configure(self) -> None:
        """Resolve the sink and check the path; nothing is opened before the first tick."""
        self.configure_stream("world/walking")
        self._staged: tuple[int, FootstepPlan, Terrain, np.ndarray, dict[str, np.ndarray]] | None = None
        self._drawn_plan: FootstepPlan | None = None
        self._drawn_terrain: Terrain | None = None
        self._polygons: dict[int, tuple[np.ndarray, float]] = {}  # by phase index, of _polygons_plan
        self._polygons_plan: FootstepPlan | None = None
        self._strips: list[np.ndarray] = []
        self._points: dict[str, tuple[list[int], list[np.ndarray]]] = {name: ([], []) for name in POINT_COLORS}
        self._styled: set[str] = set()  # the point entities whose colour and radius were logged

    @property
    def stream(self) -> RerunStream | None:
        """The Rerun stream it draws into (None before its first tick, or with ``rerun=off``)."""
        return self._stream

    def footprint_bounds(self) -> np.ndarray | None:
        """(2, 3) the lowest and highest corner coordinates of the drawn plan's footprints, or
        None before a plan is drawn."""
        if self._drawn_plan is None:
            return None
        corners = np.vstack([np.vstack(outlines) for outlines, _ in footprint_strips(self._drawn_plan).values()])
        return np.array([corners.min(axis=0), corners.max(axis=0)])

    # -- tick -----------------------------------------------------------------------------
    def observe(self, t: int) -> None:
        """Every ``decimation`` ticks, read the plan, the terrain and the plugged points at ``t``
        and compute what is drawn; kept if the tick commits."""
        if self.closed or self.rerun == "off":
            return
        if self._stream is None:
            if self.graph is None:
                raise dg.GraphError(f"{self.name}: a walking view must be in a graph", entity=self.name)
            self._stream = open_stream_for(self)
        if t % self.decimation and (self._drawn_plan is not None or self._ticks):
            self._staged = None
            return
        plan = self.plan(t)
        strip, ground = self._support_polygon(plan, plan.time(t * self.dt))
        points = {}
        for name in POINT_COLORS:
            inp = self.inputs[name]
            if inp.source is not None or inp.is_set:
                x, y, _ = inp(t)
                points[name] = np.array([x, y, ground])
        self._staged = (t, plan, self.terrain(t), strip, points)

    def _support_polygon(self, plan: FootstepPlan, time: float) -> tuple[np.ndarray, float]:
        """:func:`support_polygon`, computed once per phase of the plan."""
        if plan is not self._polygons_plan:
            self._polygons, self._polygons_plan = {}, plan
        phase = plan.phase_index(time)
        if phase not in self._polygons:
            self._polygons[phase] = support_polygon(plan, time)
        return self._polygons[phase]

    def commit_state(self, t_next: int) -> None:
        """The tick committed: draw a new terrain and a new plan's footprints, buffer the tick,
        send every ``flush_every``."""
        staged, self._staged = self._staged, None
        if staged is None or self._stream is None:
            return
        t, plan, terrain, strip, points = staged
        if terrain is not self._drawn_terrain:
            self._log_terrain(terrain)
        if plan is not self._drawn_plan:
            self._log_footprints(plan)
        self._ticks.append(t)
        self._strips.append(strip)
        for name, point in points.items():
            ticks, values = self._points[name]
            ticks.append(t)
            values.append(point)
        if self._last_send is None:
            self._last_send = t
        if t - self._last_send >= self.flush_every:
            self._send()

    def _log_terrain(self, terrain: Terrain) -> None:
        """Log the boxes of the terrain's bounded surfaces (none drawn before and none now: nothing)."""
        stream = self._stream
        assert stream is not None
        surfaces = [surface for surface in terrain.surfaces if surface.bounded]
        drawn, self._drawn_terrain = self._drawn_terrain, terrain
        if not surfaces and (drawn is None or not drawn.surfaces):
            return
        centers, half_sizes, rotations = np.zeros((len(surfaces), 3)), np.zeros((len(surfaces), 3)), []
        for k, surface in enumerate(surfaces):
            centers[k], half_sizes[k], rotation = surface.box()
            rotations.append(rotation)
        stream.rec.log(f"{self.path}/terrain", stream._rr.Boxes3D(
            centers=centers, half_sizes=half_sizes, quaternions=quaternions_xyzw(np.reshape(rotations, (-1, 3, 3))),
            colors=[TERRAIN_COLORS[k % 2] for k in range(len(surfaces))], labels=[s.name for s in surfaces],
            fill_mode="solid"), static=True)

    def _log_footprints(self, plan: FootstepPlan) -> None:
        stream = self._stream
        assert stream is not None
        rr, rec = stream._rr, stream.rec
        if self._drawn_plan is None:
            rec.log(self.path.split("/")[0], rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self._drawn_plan = plan
        for side, (outlines, labels) in footprint_strips(plan).items():
            rec.log(f"{self.path}/footprints/{side}",
                    rr.LineStrips3D(outlines, labels=labels, colors=FOOT_COLORS[side], radii=FOOTPRINT_RADIUS),
                    static=True)

    def _send(self) -> None:
        stream = self._stream
        if not self._ticks or stream is None:
            return
        rr = stream._rr
        self._send_columns("support_polygon", self._ticks, rr.LineStrips3D.columns(strips=self._strips),
                           rr.LineStrips3D.from_fields(colors=SUPPORT_POLYGON_COLOR, radii=SUPPORT_POLYGON_RADIUS))
        for name, (ticks, values) in self._points.items():
            if ticks:
                self._send_columns(name, ticks, rr.Points3D.columns(positions=np.array(values)),
                                   rr.Points3D.from_fields(colors=POINT_COLORS[name], radii=POINT_RADIUS))
        self._last_send = self._ticks[-1]
        self._ticks, self._strips = [], []
        self._points = {name: ([], []) for name in POINT_COLORS}

    def _send_columns(self, entity: str, ticks: list[int], columns: Any, style: Any) -> None:
        """Send ``columns`` to ``<path>/<entity>`` at ``ticks``; its ``style`` (colour, width) is
        logged once, as static data."""
        stream = self._stream
        assert stream is not None
        if entity not in self._styled:
            self._styled.add(entity)
            stream.rec.log(f"{self.path}/{entity}", style, static=True)
        stream.rec.send_columns(f"{self.path}/{entity}", indexes=stream.indexes(np.array(ticks, dtype=np.int64)),
                                columns=columns)

