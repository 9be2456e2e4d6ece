"""A thin wrapper over a Rerun recording stream: time series sent in columns.

Rerun is imported only when a stream is opened. Sinks: ``save`` (an .rrd file), ``spawn`` (a
local viewer process), ``serve`` (a gRPC server and a web viewer, listening on loopback unless
:func:`serving_on` says otherwise; see :class:`RerunServer`) and ``off``. An entity that does not
choose its sink gets ``save`` if it names an .rrd file, else the session's default
(:func:`sink_mode`): ``off`` for the library, so that loading and running a graph writes
nothing unless asked; ``dgraph run`` makes it ``save`` (:func:`recording_by_default`).
Series are sent in blocks of ticks, every series of a block in one Arrow record batch
(one ``send_record_batch`` call: Rerun's cost is per call and per entity, not per row), so
logging costs a few µs per tick instead of ~37 µs per ``log`` call.

A sink is opened once: :func:`open_stream` returns the stream already open for the same sink
(the same .rrd file, or the same viewer/server for a graph name) and counts its users, so the
entities of a graph that log to Rerun (the :class:`Recorder`, a :class:`RobotView`) write into
one recording; the last user's :meth:`RerunStream.close` flushes and closes the sink.
"""

from __future__ import annotations

import contextlib
import ipaddress
import os
import re
import socket
import subprocess
import sys
import tempfile
import threading
import time
import weakref
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any
from urllib.parse import quote

import numpy as np

from dgraph.errors import GraphError
from dgraph.faults import Fault


@dataclass(frozen=True)
class ServeAddress:
    """Where the ``serve`` sink listens: its gRPC server and its web viewer, both bound to
    ``bind`` (an IP address: loopback by default, ``0.0.0.0`` or ``::`` for every interface)."""

    bind: str = "127.0.0.1"
    grpc_port: int = 9876
    web_port: int = 9090
    keep: bool = False
    """Whether a server outlives its recording, until the :func:`serving_on` block that asked ends."""

    def local_host(self) -> str:
        """The address this machine reaches the servers at (loopback for a wildcard bind)."""
        if ipaddress.ip_address(self.bind).is_unspecified:
            return "::1" if ":" in self.bind else "127.0.0.1"
        return self.bind

    def public_host(self) -> str:
        """The host a browser is pointed at: the bind address, or this machine's name for a wildcard bind."""
        return socket.gethostname() if ipaddress.ip_address(self.bind).is_unspecified else self.bind


SERVE = ServeAddress()
"""What the ``serve`` sink opens (:func:`serving_on`; ``dgraph run --bind --port --web-viewer-port``)."""


_KEPT: list[RerunServer] = []
"""Servers whose recordings are closed, kept serving (``keep``) until their block ends."""


@contextlib.contextmanager
def serving_on(bind: str | None, grpc_port: int | None = None, web_port: int | None = None,
               keep: bool = False) -> Iterator[ServeAddress]:
    """Within the block, ``serve`` sinks listen on ``bind`` (an IP address; ``None``: where they
    would) and on these ports if given; the address is restored after it, so one run's
    ``--bind`` does not widen the next one's. With ``keep``, a server started in the block keeps
    serving its recording after the recording is closed (:func:`kept_servers`), until the block
    ends, which stops it."""
    global SERVE
    before = SERVE
    if bind is not None:
        try:
            ipaddress.ip_address(bind)
        except ValueError:
            raise GraphError(f"Rerun serve address {bind!r}: not an IP address (127.0.0.1, 0.0.0.0, ::...)") from None
    SERVE = ServeAddress(before.bind if bind is None else bind, grpc_port or before.grpc_port,
                         web_port or before.web_port, keep)
    kept = len(_KEPT)
    try:
        yield SERVE
    finally:
        SERVE = before
        while len(_KEPT) > kept:
            _KEPT.pop().stop()


def kept_servers() -> list[RerunServer]:
    """The servers still serving closed recordings (see ``keep`` in :func:`serving_on`)."""
    return [server for server in _KEPT if server.running()]


DEFAULT_SINK = "off"
"""The sink of an entity that neither chooses one nor names an .rrd file (:func:`sink_mode`)."""
SINKS = ("off", "save", "spawn", "serve")


@contextlib.contextmanager
def recording_by_default(mode: str) -> Iterator[str]:
    """Within the block, an entity that does not choose its Rerun sink gets ``mode`` (``dgraph
    run`` saves by default; the library records nothing unless asked)."""
    global DEFAULT_SINK
    if mode not in SINKS:
        raise GraphError(f"Rerun sink {mode!r}: expected one of {', '.join(SINKS)}")
    before, DEFAULT_SINK = DEFAULT_SINK, mode
    try:
        yield mode
    finally:
        DEFAULT_SINK = before


def sink_mode(rerun: str | None, rrd_path: str | None) -> str:
    """The sink of a recording entity: its own ``rerun`` if given, else ``save`` if it names an
    .rrd file (``rrd_path``), else :data:`DEFAULT_SINK` (``off`` unless :func:`recording_by_default`)."""
    if rerun is not None:
        return rerun
    return "save" if rrd_path else DEFAULT_SINK


class RerunServer:
    """A ``rerun --serve-web`` process: Rerun's gRPC server and web viewer on ``address``.

    The SDK's own ``serve_grpc`` and ``serve_web_viewer`` listen on every interface (0.0.0.0) and
    take no address, so ``serve`` runs the Rerun command line, which binds where it is told, and
    the recording connects to it. It is started here, waited for until both ports accept
    connections, and stopped by :meth:`stop` (at the latest when this object is collected or the
    interpreter exits). On Linux it also dies with this process when that ends otherwise
    (SIGKILL, a crash: see :func:`dying_with_parent`), so that it never keeps the ports.
    """

    def __init__(self, address: ServeAddress, timeout: float = 10.0):
        self.address = address
        for port in (address.grpc_port, address.web_port):
            _check_free(address.bind, port)
        self._log: IO[bytes] = tempfile.TemporaryFile()
        command = [rerun_binary(), "--serve-web", "--bind", address.bind, "--port", str(address.grpc_port),
                   "--web-viewer-port", str(address.web_port)]
        self._process = subprocess.Popen(dying_with_parent(command), stdin=subprocess.DEVNULL, stdout=self._log,
                                         stderr=self._log)
        self._stop = weakref.finalize(self, _stop_process, self._process)
        self._wait_listening(timeout)
        self.grpc_url = f"rerun+http://{_url_host(address.local_host())}:{address.grpc_port}/proxy"
        public = _url_host(address.public_host())
        self.viewer_url = (f"http://{public}:{address.web_port}/?url="
                           + quote(f"rerun+http://{public}:{address.grpc_port}/proxy", safe=""))

    def _wait_listening(self, timeout: float) -> None:
        """Return when both ports accept connections; raise if the process exits or is too slow."""
        deadline = time.monotonic() + timeout
        pending = [self.address.grpc_port, self.address.web_port]
        while pending:
            if self._process.poll() is not None:
                raise self._failure(f"exited with status {self._process.returncode}")
            if time.monotonic() > deadline:
                self.stop()
                raise self._failure(f"is not listening after {timeout:g} s")
            pending = [port for port in pending if not _accepts(self.address.local_host(), port)]
            if pending:
                time.sleep(0.02)

    def _failure(self, what: str) -> GraphError:
        self._log.seek(0)
        lines = self._log.read().decode(errors="replace").strip().splitlines()
        said = re.sub(r"\x1b\[[0-9;]*m", "", lines[-1]) if lines else "(it printed nothing)"
        a = self.address
        return GraphError(f"the Rerun server (rerun --serve-web on {a.bind}, ports {a.grpc_port} and "
                          f"{a.web_port}) {what}: {said}")

    def stop(self) -> None:
        """Stop the server (once; later calls do nothing)."""
        self._stop()

    def running(self) -> bool:
        """Whether the server process is still running."""
        return self._process.poll() is None


def rerun_binary() -> str:
    """The ``rerun`` executable of the installed rerun-sdk (``RERUN_CLI_PATH`` overrides it), not
    the Python wrapper script, which would survive being stopped."""
    if "RERUN_CLI_PATH" in os.environ:
        return os.environ["RERUN_CLI_PATH"]
    import rerun_cli

    path = Path(rerun_cli.__file__).parent / ("rerun.exe" if sys.platform.startswith("win") else "rerun")
    if not path.is_file():
        raise GraphError(f"the Rerun command line is missing from the rerun-sdk install ({path})")
    return str(path)


_PARENT_DEATH_SIGNAL = """\
import ctypes, os, signal, sys
parent, command = int(sys.argv[1]), sys.argv[2:]
ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG; best effort (0 or -1)
if os.getppid() != parent:  # the parent ended before the line above: it would never be signalled
    sys.exit(1)
os.execv(command[0], command)
"""
"""A child that asks the kernel for SIGTERM when its parent ends, then becomes ``command`` (the
setting survives ``execv``); run by :func:`dying_with_parent`."""


def dying_with_parent(command: list[str]) -> list[str]:
    """``command`` run so that it receives SIGTERM when this process ends, however it ends (also
    SIGKILL, when no ``finally`` or ``weakref.finalize`` runs): on Linux, through a small Python
    child that sets ``prctl(PR_SET_PDEATHSIG)`` on itself and then execs ``command`` (same pid).

    Not ``preexec_fn``, which is unsafe in a process with threads (Rerun's SDK has some), nor a
    shell wrapper (a shell cannot set it). The kernel sends the signal when the *thread* that
    started the child ends, so this is done only from the main thread (whose end is the
    process's); from another thread, on other systems, or without a Python executable, the
    command is returned unchanged (stopped by its owner only). Costs ~50 ms at start."""
    if not sys.platform.startswith("linux") or not sys.executable \
            or threading.current_thread() is not threading.main_thread():
        return command
    return [sys.executable, "-I", "-S", "-c", _PARENT_DEATH_SIGNAL, str(os.getpid()), *command]


def _stop_process(process: subprocess.Popen[bytes]) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def _check_free(bind: str, port: int) -> None:
    """Raise if ``port`` cannot be bound on ``bind`` (something listens there already: the wait
    for the server would otherwise take that listener for it)."""
    family = socket.AF_INET6 if ":" in bind else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((bind, port))
        except OSError as exc:
            raise GraphError(f"Rerun serve: cannot listen on {_url_host(bind)}:{port} ({exc.strerror}; another "
                             "Rerun server or viewer?)") from None


def _accepts(host: str, port: int) -> bool:
    try:
        socket.create_connection((host, port), timeout=0.2).close()
    except OSError:
        return False
    return True


def _url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host


class RerunStream:
    """One Rerun recording with a ``tick`` sequence timeline and a ``time`` duration timeline."""

    def __init__(self, application_id: str, mode: str, rrd_path: str | None, dt: float,
                 serve: ServeAddress | None = None):
        import rerun as rr

        self._rr = rr
        self.dt = dt
        self.url: str | None = None
        self.viewer_url: str | None = None
        self._server: RerunServer | None = None
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
            self._serve(SERVE if serve is None else serve)
        self._series_fields: dict[str, Any] = {}  # the Arrow field of each series sent, by entity path
        self._faults_through = -1  # the last tick whose faults were sent (recorders sharing the sink send each once)
        self.blueprint_sent = False
        self.users = 1
        self.application_id = application_id
        self.owner: object = None
        self._key: tuple[str, str] | None = None

    def _serve(self, address: ServeAddress) -> None:
        """Start the server on ``address``, connect the recording to it, print the viewer's URL."""
        self._server = RerunServer(address)
        self.url, self.viewer_url = self._server.grpc_url, self._server.viewer_url
        self.rec.connect_grpc(self.url)
        print(f"rerun: web viewer at {self.viewer_url} (gRPC {self.url}, listening on {address.bind})",
              file=sys.stderr, flush=True)

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

    def send_blueprint(self, blueprint: Any) -> bool:
        """Send the recording's blueprint (a ``rerun.blueprint.Blueprint``), made active and the
        default; only the first one sent (by the first recorder of a shared sink) is, the others
        are ignored. Returns whether it was sent. An .rrd file holds it as its blueprint store."""
        if self.blueprint_sent:
            return False
        self.blueprint_sent = True
        self.rec.send_blueprint(blueprint, make_active=True, make_default=True)
        return True

    def send_faults(self, faults: list[Fault]) -> None:
        """Log the faults as warnings on the ``faults`` text log, each at its tick, in one batch;
        those of a tick already sent (by another recorder of the same graph) are left out."""
        faults = [fault for fault in faults if fault.tick > self._faults_through]
        if not faults:
            return
        self._faults_through = faults[-1].tick
        ticks = np.array([fault.tick for fault in faults], dtype=np.int64)
        columns = self._rr.TextLog.columns(text=[str(fault) for fault in faults], level=["WARN"] * len(faults))
        self.rec.send_columns("faults", indexes=self.indexes(ticks), columns=columns)

    def close(self) -> None:
        """Release this user's share; the last user flushes and closes the sink."""
        self.users -= 1
        if self.users > 0:
            return
        if self._key is not None and _OPEN.get(self._key) is self:
            del _OPEN[self._key]
        try:
            self.rec.flush()
            self.rec.disconnect()
        finally:
            if self._server is not None:
                if self._server.address.keep and self._server.running():
                    _KEPT.append(self._server)  # serves the closed recording until serving_on's block ends
                else:
                    self._server.stop()


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
    return VIEWER_FLUSH_EVERY if mode in ("spawn", "serve") else FILE_FLUSH_EVERY


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


def join_streams(owner: object) -> list[RerunStream]:
    """The streams open for ``owner`` (a graph), each with one more user: an entity that logs
    to the graph's recording without a sink of its own (a device's video, at close) keeps them
    open until it calls :meth:`~RerunStream.close` on each."""
    streams = [stream for stream in _OPEN.values() if stream.owner is owner]
    for stream in streams:
        stream.users += 1
    return streams


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
