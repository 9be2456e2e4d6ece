"""Recorder: log chosen signals every tick to numpy columns (.npz) and to Rerun."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

import dgraph as dg
from dgraph.entities.recording.columns import Table
from dgraph.entities.recording.layout import (
    LAYOUTS,
    blueprint,
    default_panels,
    parse_layout,
    signal_path,
    walking_top_views,
)
from dgraph.entities.recording.rerun_stream import SINKS, RerunStream, default_flush_every, open_stream_for, sink_mode
from dgraph.entities.recording.stream_view import StreamSink
from dgraph.signals.signal import Signal


def component_names(sig: Signal, shape: tuple[int, ...]) -> list[str]:
    """Readable names of a signal's components: its labels, else ``name[i]`` / ``name[i,j]``."""
    if shape == ():
        return [sig.name]
    if sig.spec.labels is not None and len(sig.spec.labels) == int(np.prod(shape)):
        return [f"{sig.name}.{label}" for label in sig.spec.labels]
    return [f"{sig.name}[{','.join(map(str, idx))}]" for idx in np.ndindex(*shape)]


@dg.register
class Recorder(StreamSink, dg.Entity):
    """Records signals every tick, without changing what is computed.

    At each tick, after the control is computed and before the states are committed, the
    recorder reads each signal at ``t`` (a cached read, since the device has just pulled the
    graph; a signal nobody else needs is computed as it would be on demand); the row is kept
    only if the tick commits. Values go to in-memory numpy columns (about 8 bytes per number
    per tick), saved as ``.npz`` on :meth:`close` (keys ``tick``, ``time`` and
    ``entity.signal``), and to Rerun as time series on the ``tick`` and ``time`` timelines,
    one series per component, entity path ``signals/<entity>/<signal>``.

    The faults of the recorded ticks (:mod:`dgraph.faults`: what bad data a tick survived and
    what replaced it) are recorded too: in the ``.npz``, ``degraded`` (per recorded tick) and
    one entry per fault (those the graph's fault log keeps) in ``fault_tick``, ``fault_signal``,
    ``fault_cause``, ``fault_action`` and ``fault_detail``; in Rerun, a warning on the ``faults``
    text log at the fault's tick, sent with the series (one batch per flush). All are read from
    the graph's log, which keeps a tick's faults once the tick commits.

    Parameters: ``signals`` (``entity.signal`` names), ``rerun`` (``save``: an .rrd file,
    ``rrd_path`` or ``out/<graph name>.rrd``; ``spawn``: a viewer; ``serve``: a web viewer on
    loopback; ``off``; not given: ``save`` if ``rrd_path`` is given, else nothing, unless the
    session says otherwise, as ``dgraph run`` does: see
    :func:`~dgraph.entities.recording.rerun_stream.sink_mode`), ``npz_path``, ``decimation``
    (log one tick in N to Rerun), ``flush_every`` (ticks buffered before sending to Rerun;
    default 1000 to a file, 200 to a viewer: Rerun's cost is per send and per series, not per
    row), ``layout`` (the blueprint sent with the recording: ``default``, ``none``, or a list of
    panels ``{title, signals}``; see :mod:`~dgraph.entities.recording.layout`). The Rerun sink is
    shared with the other entities of the graph that open the same one (a ``RobotView``): one
    recording, one blueprint (the first recorder's), with a 3D view of every robot view drawing
    into it.
    """

    observes = True
    signals = dg.Param(kind="str_list", doc="names 'entity.signal' of the recorded signals")
    rerun = dg.Param(None, kind="str", choices=SINKS,
                     doc="Rerun sink (default: save if rrd_path is given, else off unless dgraph run saves)")
    rrd_path = dg.Param(None, kind="str", doc=".rrd file for rerun=save (default out/<graph name>.rrd)")
    npz_path = dg.Param(None, kind="str", doc=".npz file written on close (default: none)")
    decimation = dg.Param(1, kind="int", doc="send one tick in N to Rerun")
    flush_every = dg.Param(None, kind="int",
                           doc="ticks buffered before a Rerun send (default: 1000 to a file, 200 to a viewer)")
    layout = dg.Param("default", kind="object",
                      doc=f"Rerun blueprint: {' or '.join(LAYOUTS)}, or a list of panels {{title, signals}}")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, signals: Sequence[str], rerun: Literal["off", "save", "spawn", "serve"] | None = None,
            rrd_path: str | None = None, npz_path: str | None = None, decimation: int = 1,
            flush_every: int | None = None, layout: Any = "default",
        ) -> None: ...

    def configure(self) -> None:
        """Check the parameters."""
        repeated = sorted({name for name in self.signals if self.signals.count(name) > 1})
        if repeated:
            raise dg.ParamError(f"{self.name}: signals recorded twice: {', '.join(repeated)}", entity=self.name)
        self.rerun = sink_mode(self.rerun, self.rrd_path)
        self._layout = parse_layout(self.layout, self.signals, self.name)
        if self.flush_every is None:
            self.flush_every = default_flush_every(self.rerun)
        if self.decimation < 1 or self.flush_every < 1:
            raise dg.ParamError(f"{self.name}: decimation and flush_every must be >= 1", entity=self.name)
        self._sources: list[Signal] | None = None
        self._rows = Table()  # the tick, then one column per signal
        self._row_written = False  # at this tick's observe, kept if the tick commits
        self._faults_sent = 0  # how many of the graph's kept faults went to Rerun
        self._stream: RerunStream | None = None
        self._plotted: list[tuple[int, str, list[str]]] | None = None
        self._pending = 0
        self.closed = False
        if self.npz_path and not self.npz_path.endswith(".npz"):
            self.npz_path += ".npz"  # what numpy would write anyway; reported as written

    def check(self) -> list[str]:
        """Every recorded name must be a signal of the graph."""
        if self.graph is None:
            return []
        problems = []
        for name in self.signals:
            try:
                self.graph.signal(name)
            except dg.DGraphError as exc:
                problems.append(f"recorded signal {name!r}: {exc}")
        return problems

    def _open(self) -> list[Signal]:
        if self.graph is None:
            raise dg.GraphError(f"{self.name}: a recorder must be in a graph", entity=self.name)
        problems = self.check()
        if problems:
            raise dg.GraphError("; ".join(problems), entity=self.name)
        self._sources = [self.graph.signal(name) for name in self.signals]
        if self.rerun != "off":
            self._stream = open_stream_for(self)
        return self._sources

    def observe(self, t: int) -> None:
        """Read every recorded signal at ``t`` and write the row (a value that does not fit its
        column fails the tick here, before anything commits); it is kept when the tick commits."""
        sources = self._sources if self._sources is not None else self._open()
        row = (t, *[sig(t) for sig in sources])
        try:
            self._rows.write(row)
        except (ValueError, TypeError) as exc:
            raise self._misfit(row, t, exc) from exc
        self._row_written = True

    def _misfit(self, row: tuple[Any, ...], t: int, cause: Exception) -> dg.DGraphError:
        """The error naming the recorded signal whose value at ``t`` does not fit its column."""
        for i, (name, value) in enumerate(zip(self.signals, row[1:], strict=True), start=1):
            shape, expected = np.shape(value), self._rows.field_shape(i)
            if shape not in ((), expected):
                return dg.SpecError(f"{self.name}: {name} at tick {t} has shape {shape}, its first recorded "
                                    f"value had {expected}", entity=self.name, signal=name)
        return dg.GraphError(f"{self.name}: the row of tick {t} cannot be recorded: {cause}", entity=self.name)

    def commit_state(self, t_next: int) -> None:
        """The tick committed: keep its row (a failed tick leaves no row)."""
        if self._row_written:
            self._row_written = False
            self._rows.keep()
        if self._stream is not None:
            self._pending += 1
            if self._pending >= self.flush_every:
                self._send()

    def _send(self) -> None:
        faults = self.graph.fault_log.faults
        if len(faults) > self._faults_sent:  # one batch for all the faults kept since the last send
            self._stream.send_faults(faults[self._faults_sent:])
            self._faults_sent = len(faults)
        n = self._pending
        self._pending = 0
        if n == 0 or self._stream is None:
            return
        start = self._rows.n - n
        ticks = self._rows.column(0, start)
        keep = ticks % self.decimation == 0 if self.decimation > 1 else slice(None)  # a slice: no copy
        if not ticks[keep].size:
            return
        if self._plotted is None:
            self._plotted = self._plotted_series()
            self._send_blueprint()
        series = []
        for i, path, names in self._plotted:
            values = np.ascontiguousarray(self._rows.column(i, start)[keep], dtype=float)  # one copy at most
            series.append((path, names, values.reshape(len(values), -1)))
        if series:
            self._stream.send_series(ticks[keep], series)

    def _send_blueprint(self) -> None:
        """Send the layout's blueprint (once per sink): the panels (by default, those of the
        plotted signals and the graph's walking views), a 3D view of each robot view and a top
        view of each walking view drawing into the same recording."""
        if self._layout == "none" or self._stream is None or self._stream.blueprint_sent:
            return
        if self._layout == "default":
            panels = default_panels([self.signals[i - 1] for i, _, _ in self._plotted or []], self.graph or [])
        else:
            panels = self._layout
        origins: list[str] = []
        for entity in self.graph or []:
            if entity.type_name == "RobotView" and getattr(entity, "_stream", None) is self._stream:
                origin = "/" + entity.path.split("/")[0]
                if origin not in origins:
                    origins.append(origin)
        self._stream.send_blueprint(blueprint(panels, origins, top_views=walking_top_views(self.graph or [],
                                                                                         self._stream)))

    def _plotted_series(self) -> list[tuple[int, str, list[str]]]:
        """The columns sent to Rerun (numbers; other values are kept in the .npz, not plotted):
        column index, entity path, component names."""
        plotted = []
        for i, (name, sig) in enumerate(zip(self.signals, self._sources or [], strict=True), start=1):
            column = self._rows.column(i)
            if column.dtype.kind in "fiub":
                plotted.append((i, signal_path(name), component_names(sig, column.shape[1:])))
        return plotted

    @property
    def ticks(self) -> np.ndarray:
        """The recorded ticks."""
        return self._rows.column(0).astype(np.int64)

    def data(self) -> dict[str, np.ndarray]:
        """The recording so far: ``tick``, ``time`` (s), one array per signal (ticks first),
        ``degraded`` and the ``fault_*`` arrays (see the class docstring)."""
        out = {"tick": self.ticks}
        out["time"] = out["tick"] * (self.graph.dt if self.graph is not None else 1.0)
        for i, name in enumerate(self.signals, start=1):
            out[name] = self._rows.column(i).copy()
        log = self.graph.fault_log if self.graph is not None else None
        recorded = set(out["tick"].tolist())
        faults = [f for f in log.faults if f.tick in recorded] if log is not None else []
        out["degraded"] = np.isin(out["tick"], log.degraded if log is not None else [])
        out["fault_tick"] = np.array([f.tick for f in faults], dtype=np.int64)
        for field in ("signal", "cause", "action", "detail"):
            out[f"fault_{field}"] = np.array([getattr(f, field) for f in faults], dtype=str)
        return out

    def close(self) -> None:
        """Flush to Rerun, close the stream, write the .npz (idempotent)."""
        if self.closed:
            return
        super().close()
        if self.npz_path:
            try:
                Path(self.npz_path).parent.mkdir(parents=True, exist_ok=True)
                np.savez(self.npz_path, **self.data())
            except OSError as exc:
                raise dg.GraphError(f"{self.name}: cannot write {self.npz_path}: {exc.strerror or exc}",
                                    entity=self.name) from None
