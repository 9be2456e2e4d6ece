"""StreamSink and StreamView: what the entities sending to the graph's Rerun recording share (how
they close: Recorder, RobotView, WalkingView), and what the views drawing into it share (their sink
parameters, the check of their entity path: RobotView, WalkingView)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import dgraph as dg
from dgraph.entities.recording.rerun_stream import SINKS, RerunStream, default_flush_every, sink_mode


class StreamSink:
    """Mixin for an entity that sends what it buffers to a Rerun stream (``_stream``, None until
    opened) with ``_send``, and closes once (``closed``)."""

    name: str
    closed: bool
    _stream: RerunStream | None
    _send: Callable[[], None]  # the subclass's: send what it buffered

    def close(self) -> None:
        """Send the buffered ticks and release the shared stream (idempotent)."""
        if self.closed:
            return
        self.closed = True
        if self._stream is not None:
            self._send()
            self._stream.close()


class StreamView(StreamSink):
    """Mixin for an observer that draws one tick in ``decimation`` under the entity path ``path``
    (a parameter of the class: its default differs), buffering ``flush_every`` ticks per send.

    Parameters: ``decimation``, ``rerun`` (the sink; default: save if ``rrd_path`` is given, else
    off unless ``dgraph run`` saves: nothing is written for a library user who did not ask),
    ``rrd_path``, ``flush_every`` (default 1000 ticks to a file, 200 to a viewer).
    A subclass calls :meth:`configure_stream` in its ``configure`` and defines ``_send`` (send
    the buffered ticks).
    """

    decimation = dg.Param(20, kind="int", minimum=1, doc="draw one tick in N (20: 50 Hz at 1 kHz)")
    rerun = dg.Param(None, kind="str", choices=SINKS,
                     doc="Rerun sink (default: save if rrd_path is given, else off unless dgraph run saves)")
    rrd_path = dg.Param(None, kind="str", doc=".rrd file for rerun=save (default out/<graph name>.rrd)")
    flush_every = dg.Param(None, kind="int", minimum=1,
                           doc="ticks buffered before a Rerun send (default: 1000 to a file, 200 to a viewer)")

    path: str
    params: dict[str, Any]

    def configure_stream(self, example: str) -> None:
        """Resolve the sink and the flush period, normalise ``path`` (a ParamError quoting
        ``example`` when it is not an entity path); nothing is opened before the first tick."""
        self.rerun = sink_mode(self.rerun, self.rrd_path)
        if self.flush_every is None:
            self.flush_every = default_flush_every(self.rerun)
        self.path = self.path.strip("/")
        if not self.path or any(not part for part in self.path.split("/")):
            raise dg.ParamError(f"{self.name}: path must be an entity path such as {example!r}, got "
                                f"{self.params['path']!r}", entity=self.name)
        self._stream: RerunStream | None = None
        self._ticks: list[int] = []
        self._last_send: int | None = None
        self.closed = False

