"""RobotView: the robot's links in Rerun's 3D view, moving with the configuration ``q``."""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

import dgraph as dg
from dgraph.entities.recording.rerun_stream import (
    RerunStream,
    component_field,
    open_stream_for,
)
from dgraph.entities.recording.stream_view import StreamView
from dgraph.entities.robot.loading import load_model, load_robot

FLOOR_HALF_SIZE = 2.0
"""Half side of the floor square, in metres."""

MESH_TYPES = {".stl": "model/stl", ".obj": "model/obj", ".glb": "model/gltf-binary", ".gltf": "model/gltf+json"}
"""Mesh files Rerun's ``Asset3D`` reads, by (case-insensitive) extension."""


def quaternions_xyzw(rotations: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(x, y, z, w)`` of rotation matrices ``(..., 3, 3)``, vectorised.

    Each quaternion is computed from the largest of ``4 w^2, 4 x^2, 4 y^2, 4 z^2`` (the
    numerically safe branch), chosen per matrix.
    """
    r = np.asarray(rotations, dtype=float)
    m00, m01, m02 = r[..., 0, 0], r[..., 0, 1], r[..., 0, 2]
    m10, m11, m12 = r[..., 1, 0], r[..., 1, 1], r[..., 1, 2]
    m20, m21, m22 = r[..., 2, 0], r[..., 2, 1], r[..., 2, 2]
    x2, y2, z2 = 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22
    w2 = 1 + m00 + m11 + m22
    candidates = np.stack([  # (..., branch, xyzw), branch k is 4 q_k^2 times the quaternion / (2 sqrt(4 q_k^2))
        np.stack([x2, m01 + m10, m02 + m20, m21 - m12], -1),
        np.stack([m01 + m10, y2, m12 + m21, m02 - m20], -1),
        np.stack([m02 + m20, m12 + m21, z2, m10 - m01], -1),
        np.stack([m21 - m12, m02 - m20, m10 - m01, w2], -1),
    ], -2)
    branch = np.argmax(np.stack([x2, y2, z2, w2], -1), -1)[..., None, None]
    q = np.take_along_axis(candidates, branch, -2)[..., 0, :]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _entity_name(name: str) -> str:
    """A frame or geometry name usable as one Rerun entity-path part."""
    return re.sub(r"[^A-Za-z0-9_\-]", "_", name) or "_"


class _Link:
    """A frame carrying visual geometries: its joint and its placement in the joint frame."""

    __slots__ = ("frame", "geometries", "joint", "name", "placement")

    def __init__(self, name: str, frame: int, joint: int, placement: Any):
        self.name = name
        self.frame = frame
        self.joint = joint
        self.placement = placement  # jMf, pinocchio.SE3
        self.geometries: list[Any] = []


@dg.register
class RobotView(StreamView, dg.Entity):
    """Shows the robot in Rerun's 3D view (meshes once, then link poses over time).

    At the first committed tick the visual geometries of the example-robot-data ``model`` are
    logged once, as static data: an entity ``<path>/<link>/<geometry>`` per geometry, holding
    the mesh (``Asset3D`` from its STL file, or a box / cylinder primitive) and, as a static
    ``Transform3D``, its placement in the link frame and its ``meshScale``. A floor square
    and world axes are logged beside ``<path>`` (``floor=True``).

    Then, every ``decimation`` ticks, the link poses in the world are computed from ``q(t)``
    (``pinocchio.forwardKinematics``, ``oMf = oMi[joint] * jMf`` for every link that carries a
    geometry) and logged as ``Transform3D`` of ``<path>/<link>`` on the ``tick`` and ``time``
    timelines (translation and quaternion). Like the :class:`Recorder`, it reads ``q`` in
    :meth:`observe` and keeps it only when the tick commits; the configurations are buffered and,
    every ``flush_every`` ticks (default 1000 to a file, 200 to a viewer), their poses are
    computed in one go (one warm loop instead of one cold call every ``decimation`` ticks) and
    sent as one Arrow record batch holding a column per link and component (one
    ``send_record_batch`` call: Rerun's cost is per call and per entity, not per row), so TALOS
    (52 links) costs about 10 µs per tick on average at ``decimation=20`` to a file.

    It writes into the same Rerun recording as the graph's recorder: both open their sink
    with :func:`~dgraph.entities.recording.rerun_stream.open_stream`, which shares one stream
    per .rrd file (``save``; same default file ``out/<graph name>.rrd``) or per graph name
    (``spawn``, ``serve``).

    Parameters: ``model`` (example-robot-data name), ``decimation``, ``path`` (entity path
    prefix), ``floor``, ``rerun`` (``save`` | ``spawn`` | ``serve`` | ``off``; not given: as the
    :class:`Recorder`'s, ``save`` if ``rrd_path`` is given, else the session's default, nothing
    for the library), ``rrd_path``, ``flush_every``. Inputs: ``q`` (``nq``, Pinocchio convention: a free-flyer base is
    ``x y z qx qy qz qw``).
    """

    observes = True
    model = dg.Param("talos", kind="name_or_path", doc="example-robot-data robot name or URDF path")
    path = dg.Param("world/robot", kind="str", doc="Rerun entity path of the robot")
    floor = dg.Param(True, kind="bool", doc="also log a floor square and world axes")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, decimation: int = 20, rerun: Literal["off", "save", "spawn", "serve"] | None = None,
            rrd_path: str | None = None, flush_every: int | None = None, model: str | Any = "talos",
            path: str = "world/robot", floor: bool = True,
        ) -> None: ...

    q = dg.Input(shape=("nq",), doc="configuration (Pinocchio convention)")

    def configure(self) -> None:
        """Load the kinematics (the meshes are read when the view first draws: one that records
        nothing reads none)."""
        self.configure_stream("world/robot")
        self.pin_model = load_model(self.model, self.name)
        self.nq = self.pin_model.nq
        self._links: list[_Link] | None = None
        self._fields: list[Any] | None = None
        self._data: Any = None
        self._statics_sent = False
        self._staged: tuple[int, np.ndarray] | None = None
        self._qs: list[np.ndarray] = []  # the configurations of the buffered ticks
        self.skipped: list[str] = []  # geometries that could not be drawn

    @property
    def links(self) -> list[_Link]:
        """The links that carry visual geometries (their meshes read at the first use)."""
        return self._load_links()

    def _link_frames(self) -> tuple[np.ndarray, np.ndarray]:
        """The joint each link moves with, and the link's placement in that joint's frame."""
        self._load_links()
        return self._joints, self._jMf

    def _load_links(self) -> list[_Link]:
        """Read the robot's meshes (once per process: :func:`load_robot`) and list its links."""
        if self._links is None:
            try:
                visual_model = load_robot(self.model).visual_model
            except Exception as exc:  # Pinocchio raises plain exceptions for a mesh it cannot read
                raise dg.ParamError(f"{self.name}: cannot load the meshes of the robot {self.model!r}: {exc}",
                                    entity=self.name) from None
            self._links = self._collect_links(visual_model)
            self._joints = np.array([link.joint for link in self._links])
            self._jMf = np.array([link.placement.homogeneous for link in self._links])
        return self._links

    def _collect_links(self, visual_model: Any) -> list[_Link]:
        model = self.pin_model
        links: dict[int, _Link] = {}
        for geom in visual_model.geometryObjects:
            frame = geom.parentFrame
            if frame >= model.nframes or model.frames[frame].parentJoint != geom.parentJoint:
                frame = -1 - geom.parentJoint  # no usable frame: the joint itself
            link = links.get(frame)
            if link is None:
                if frame >= 0:
                    f = model.frames[frame]
                    link = _Link(_entity_name(f.name), frame, f.parentJoint, f.placement)
                else:
                    import pinocchio as pin
                    link = _Link(_entity_name(model.names[geom.parentJoint]), frame, geom.parentJoint,
                                 pin.SE3.Identity())
                links[frame] = link
            link.geometries.append(geom)
        names = [link.name for link in links.values()]
        for link in links.values():
            if names.count(link.name) > 1:
                link.name = f"{link.name}_{link.frame}"
        return list(links.values())

    # -- poses ----------------------------------------------------------------------------
    def poses(self, qs: np.ndarray) -> np.ndarray:
        """World poses of the links at each configuration (row) of ``qs``: homogeneous matrices,
        shape ``(len(qs), links, 4, 4)``."""
        import pinocchio as pin

        if self._data is None:
            self._data = self.pin_model.createData()
        model, data = self.pin_model, self._data
        link_joints, jMf = self._link_frames()
        joints = []
        for q in qs:
            pin.forwardKinematics(model, data, q)
            joints += [oMi.homogeneous for oMi in data.oMi.tolist()]  # tolist: one binding call
        return np.array(joints).reshape(len(qs), model.njoints, 4, 4)[:, link_joints] @ jMf

    # -- tick -----------------------------------------------------------------------------
    def _open(self) -> RerunStream:
        if self.graph is None:
            raise dg.GraphError(f"{self.name}: a robot view must be in a graph", entity=self.name)
        self._stream = open_stream_for(self)
        return self._stream

    def observe(self, t: int) -> None:
        """Every ``decimation`` ticks, read ``q(t)`` (copied; its poses are computed at the send);
        kept if the tick commits. A ``q`` of the wrong size fails the tick here."""
        if self.closed or self.rerun == "off":
            return
        if self._stream is None:
            self._open()
        if t % self.decimation and (self._statics_sent or self._ticks):
            self._staged = None
            return
        q = np.array(self.q(t), dtype=float)
        if q.shape != (self.nq,):
            raise dg.SpecError(f"{self.name}.q: expected shape ({self.nq},), got {q.shape} at tick {t}",
                               entity=self.name, signal="q")
        self._staged = (t, q)

    def commit_state(self, t_next: int) -> None:
        """The tick committed: log the statics once, buffer ``q``, send every ``flush_every``."""
        staged, self._staged = self._staged, None
        if staged is None or self._stream is None:
            return
        if not self._statics_sent:
            self._log_statics()
        t, q = staged
        self._ticks.append(t)
        self._qs.append(q)
        if self._last_send is None:
            self._last_send = t
        if t - self._last_send >= self.flush_every:
            self._send()

    def _pose_fields(self, rr: Any) -> list[Any]:
        """Arrow fields of a batch of poses: per link its translation and quaternion columns
        (lists of float32 triples / quadruples), tagged with Rerun's column metadata."""
        import pyarrow as pa

        fields = []
        for path in (f"/{self.path}/{link.name}" for link in self.links):
            for descriptor, size in ((rr.Transform3D.descriptor_translation(), 3),
                                     (rr.Transform3D.descriptor_quaternion(), 4)):
                item = pa.list_(pa.field("item", pa.float32(), nullable=False), size)
                fields.append(component_field(path, descriptor, pa.list_(item)))
        return fields

    def _send(self) -> None:
        if not self._ticks or self._stream is None:
            return
        import pyarrow as pa

        if self._fields is None:
            self._fields = self._pose_fields(self._stream._rr)
        ticks = np.array(self._ticks, dtype=np.int64)
        poses = self.poses(np.array(self._qs)).transpose(1, 0, 2, 3)  # (links, ticks, 4, 4)
        self._ticks, self._qs = [], []
        self._last_send = int(ticks[-1])
        n, links = len(ticks), len(self.links)
        # one Arrow array per component holding every link's rows, then a zero-copy slice per link
        offsets = pa.array(np.arange(n * links + 1, dtype=np.int32))
        blocks = []
        for values, field in ((poses[:, :, :3, 3], self._fields[0]),
                              (quaternions_xyzw(poses[:, :, :3, :3]), self._fields[1])):
            rows = pa.FixedSizeListArray.from_arrays(values.astype(np.float32).ravel(), type=field.type.value_type)
            blocks.append(pa.ListArray.from_arrays(offsets, rows, type=field.type))
        columns = [block.slice(k * n, n) for k in range(links) for block in blocks]
        self._stream.send_batch(ticks, self._fields, columns)

    def _log_statics(self) -> None:
        stream = self._stream
        assert stream is not None
        rr, rec = stream._rr, stream.rec
        self._statics_sent = True
        root = self.path.split("/")[0]
        rec.log(root, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        if self.floor:
            parent = self.path.rsplit("/", 1)[0] if "/" in self.path else ""
            prefix = f"{parent}/" if parent else ""
            rec.log(f"{prefix}floor", rr.Boxes3D(half_sizes=[[FLOOR_HALF_SIZE, FLOOR_HALF_SIZE, 0.0005]],
                                                 centers=[[0.0, 0.0, -0.0005]], colors=[[150, 150, 150, 255]],
                                                 fill_mode="solid"), static=True)
            rec.log(f"{prefix}axes", rr.Arrows3D(origins=np.zeros((3, 3)), vectors=0.3 * np.eye(3),
                                                 colors=[[255, 0, 0], [0, 200, 0], [0, 0, 255]]), static=True)
        for link in self.links:
            fMj = link.placement.inverse()
            for geom in link.geometries:
                fMg = fMj * geom.placement
                shape = self._shape(rr, geom)
                if shape is None:
                    self.skipped.append(geom.name)  # neither a mesh file Rerun reads nor a primitive
                    continue
                rec.log(f"{self.path}/{link.name}/{_entity_name(geom.name)}",
                        rr.Transform3D(translation=fMg.translation, mat3x3=fMg.rotation,
                                       scale=np.asarray(geom.meshScale, dtype=float)),
                        shape, static=True)

    @staticmethod
    def _shape(rr: Any, geom: Any) -> Any:
        """The Rerun archetype drawing ``geom`` in its own frame, or ``None``."""
        color = np.clip(np.asarray(geom.meshColor, dtype=float), 0.0, 1.0)
        rgba = (255 * color).round().astype(np.uint8)
        kind = type(geom.geometry).__name__
        mesh = Path(geom.meshPath)
        media_type = MESH_TYPES.get(mesh.suffix.lower())
        if media_type is not None and mesh.is_file():
            return rr.Asset3D(contents=mesh.read_bytes(), media_type=media_type, albedo_factor=rgba)
        if kind == "Box":
            return rr.Boxes3D(half_sizes=[np.asarray(geom.geometry.halfSide)], colors=[rgba], fill_mode="solid")
        if kind == "Cylinder":
            return rr.Cylinders3D(lengths=[2 * geom.geometry.halfLength], radii=[geom.geometry.radius],
                                  colors=[rgba], fill_mode="solid")
        if kind == "Sphere":
            return rr.Ellipsoids3D(half_sizes=[[geom.geometry.radius] * 3], colors=[rgba], fill_mode="solid")
        return None

