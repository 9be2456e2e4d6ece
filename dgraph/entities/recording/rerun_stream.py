"""A thin wrapper over a Rerun recording stream: time series sent in columns.

Rerun is imported only when a stream is opened. Sinks: ``save`` (an .rrd file, the default
when headless), ``spawn`` (a local viewer process) and ``serve`` (gRPC plus a web viewer on
loopback). Series are sent in blocks of ticks, every series of a block in one Arrow record batch
(one ``send_record_batch`` call: Rerun's cost is per call and per entity, not per row), so
logging costs a few µs per tick instead of ~37 µs per ``log`` call.

A sink is opened once: :func:`open_stream` returns the stream already open for the same sink
(the same .rrd file, or the same viewer/server for a graph name) and counts its users, so the
entities of a graph that log to Rerun (the :class:`Recorder`, a :class:`RobotView`) write into
one recording; the last user's :meth:`RerunStream.close` flushes and closes the sink.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from dgraph.errors import GraphError


class RerunStream:
    """One Rerun recording with a ``tick`` sequence timeline and a ``time`` duration timeline."""

    def __init__(self, application_id: str, mode: str, rrd_path: str | None, dt: float):
        import rerun as rr

        self._rr = rr
        self.dt = dt
        self.url: str | None = None
        self.rec = rr.RecordingStream(application_id)
        if mode == "save":
            try:
                Path(str(rrd_path)).parent.mkdir(parents=True, exist_ok=True)
                self.rec.save(str(rrd_path))
            except (OSError, RuntimeError) as exc:
                raise GraphError(f"cannot write the Rerun recording {rrd_path}: {exc}") from None
        elif mode == "spawn":
            self.rec.spawn()
        elif mode == "serve":
            self.url = self.rec.serve_grpc()
            rr.serve_web_viewer(open_browser=False, connect_to=self.url)
        self._series_fields: dict[str, Any] = {}  # the Arrow field of each series sent, by entity path
        self.users = 1
        self.application_id = application_id
        self.owner: object = None
        self._key: tuple[str, str] | None = None

    def indexes(self, ticks: np.ndarray) -> list[Any]:
        """The ``tick`` and ``time`` time columns of ``ticks``."""
        rr = self._rr
        return [rr.TimeColumn("tick", sequence=ticks), rr.TimeColumn("time", duration=ticks * self.dt)]

    def send_batch(self, ticks: np.ndarray, fields: list[Any], columns: list[Any]) -> None:
        """Send one Arrow record batch: the ``tick`` and ``time`` columns of ``ticks``, then the
        component ``columns`` described by ``fields`` (see :func:`component_field`)."""
        import pyarrow as pa

        indexes = [index.as_arrow_array() for index in self.indexes(ticks)]
        schema = pa.schema(index_fields() + fields)
        self.rec.send_record_batch(pa.RecordBatch.from_arrays(indexes + columns, schema=schema))

    def send_series(self, ticks: np.ndarray, series: list[tuple[str, list[str], np.ndarray]]) -> None:
        """Send time series at ``ticks``, all in one batch: for each ``(path, names, values)``,
        ``values`` (rows = ticks, columns = components, float) as series named ``names``."""
        import pyarrow as pa

        fields, columns = [], []
        for path, names, values in series:
            if path not in self._series_fields:  # a new series: its names, once, as static data
                self.rec.log(path, self._rr.SeriesLines(names=names), static=True)
                self._series_fields[path] = component_field(path, self._rr.Scalars.descriptor_scalars(),
                                                            pa.list_(pa.float64()))
            fields.append(self._series_fields[path])
            offsets = pa.array(np.arange(len(values) + 1, dtype=np.int32) * values.shape[1])
            columns.append(pa.ListArray.from_arrays(offsets, pa.array(values.ravel())))
        self.send_batch(ticks, fields, columns)

    def close(self) -> None:
        """Release this user's share; the last user flushes and closes the sink."""
        self.users -= 1
        if self.users > 0:
            return
        if self._key is not None and _OPEN.get(self._key) is self:
            del _OPEN[self._key]
        self.rec.flush()
        self.rec.disconnect()


def index_fields() -> list[Any]:
    """Arrow fields of the ``tick`` (sequence) and ``time`` (duration) columns, tagged as Rerun indexes."""
    import pyarrow as pa

    return [pa.field(name, kind, metadata={"rerun:kind": "index", "rerun:index_name": name})
            for name, kind in (("tick", pa.int64()), ("time", pa.duration("ns")))]


def component_field(path: str, descriptor: Any, arrow_type: Any) -> Any:
    """Arrow field of a component column of entity ``path`` (a Rerun ``ComponentDescriptor``),
    tagged with Rerun's column metadata."""
    import pyarrow as pa

    return pa.field(f"{path}:{descriptor.component}", arrow_type, metadata={
        "rerun:kind": "data", "rerun:entity_path": path, "rerun:archetype": descriptor.archetype,
        "rerun:component": descriptor.component, "rerun:component_type": descriptor.component_type})


FILE_FLUSH_EVERY = 1000
"""Default ticks buffered before a send to an .rrd file: Rerun's cost (the call, then encoding
on its own threads) is per send and per entity, nearly flat in the rows sent, and no longer
falls much past ~1000 rows a chunk."""
VIEWER_FLUSH_EVERY = 200
"""Default ticks buffered before a send to a viewer (``spawn``, ``serve``): what it shows lags the
run by at most this many ticks."""


def default_flush_every(mode: str) -> int:
    """The default ``flush_every`` of a recording entity for the Rerun sink ``mode``."""
    return FILE_FLUSH_EVERY if mode == "save" else VIEWER_FLUSH_EVERY


_OPEN: dict[tuple[str, str], RerunStream] = {}
"""Open shared streams by sink: ``("save", absolute .rrd path)``, ``(mode, application id)``."""


def open_stream(application_id: str, mode: str, rrd_path: str | None, dt: float, owner: object = None,
                user: str | None = None) -> RerunStream:
    """The stream of this sink, shared within one graph: opened by the first user, counted for
    the others (a Recorder and a RobotView of a graph draw into one recording).

    Sharing is keyed by the file for ``save`` (two writers would corrupt it), and by the
    application (graph) name for ``spawn`` and ``serve``. Only users with the same ``owner``
    (the graph) share: another graph asking for an open file gets a ``GraphError`` naming
    ``user`` (the entity), as does a user with another ``dt``. Every caller must
    :meth:`~RerunStream.close` it once.
    """
    key = (mode, str(Path(str(rrd_path)).resolve())) if mode == "save" else (mode, application_id)
    stream = _OPEN.get(key)
    if stream is None:
        stream = RerunStream(application_id, mode, rrd_path, dt)
        stream._key, stream.owner = key, owner
        _OPEN[key] = stream
        return stream
    prefix = f"{user}: " if user else ""
    if stream.owner is not owner:
        raise GraphError(f"{prefix}the Rerun sink {key[1]} is already in use by another graph "
                         f"({stream.application_id!r}); give each graph its own file", entity=user)
    if stream.dt != dt:
        raise GraphError(f"{prefix}the Rerun sink {key[1]} is already open with dt={stream.dt}, not {dt}",
                         entity=user)
    stream.users += 1
    return stream


def safe_file_stem(name: str) -> str:
    """``name`` reduced to a file name that stays in its directory (no separators, no leading dot)."""
    stem = re.sub(r"[^A-Za-z0-9_.\-]", "_", name).lstrip(".")
    return stem or "graph"


def open_stream_for(entity: Any) -> RerunStream:
    """The graph's shared stream for a recording entity (parameters ``rerun`` and ``rrd_path``;
    ``save`` defaults to ``out/<graph name>.rrd``, so a Recorder and a RobotView share it)."""
    graph = entity.graph
    if entity.rerun == "save" and not entity.rrd_path:
        entity.rrd_path = f"out/{safe_file_stem(graph.name)}.rrd"
    return open_stream(graph.name, entity.rerun, entity.rrd_path, graph.dt, graph, entity.name)


def read_series(rrd_path: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Read the scalar series of an .rrd file: entity path -> (ticks, values[ticks, components])."""
    import rerun.chunk as chunk

    parts: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for ch in chunk.RrdReader(rrd_path).stream():
        batch = ch.to_record_batch()
        if "Scalars:scalars" not in batch.schema.names or "tick" not in batch.schema.names:
            continue
        ticks = np.asarray(batch.column("tick").to_pylist())
        values = np.asarray(batch.column("Scalars:scalars").to_pylist(), dtype=float)
        parts.setdefault(str(ch.entity_path), []).append((ticks, values))
    out = {}
    for path, chunks in parts.items():
        ticks = np.concatenate([c[0] for c in chunks])
        values = np.concatenate([c[1] for c in chunks])
        order = np.argsort(ticks, kind="stable")
        out[path] = (ticks[order], values[order])
    return out
