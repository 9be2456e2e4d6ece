"""The device loop: one tick of a graph, and runs of many ticks with progress.

One tick at ``t``:

1. ``before`` hooks of every device, at ``t``;
2. periodic outputs (``period=N``) whose window starts at ``t`` (``t % N == 0``) are sampled,
   so that what they hold never depends on who reads them when;
3. every stateful entity prepares (stages) its next state from the values at ``t`` (devices
   pull their control here, so this is where the graph is evaluated);
4. observers (recorders) read what they record, at ``t``;
5. every stateful entity commits its staged state, stamped ``t + 1`` (this cannot fail), and
   observers keep the row they read; the faults reported during the tick (:mod:`dgraph.faults`)
   are kept in the graph's fault log;
6. ``after`` hooks of every device, at ``t + 1``.

Nothing is committed if steps 1-4 fail, so a failing hook or computation leaves every state
at ``t``, consistent, and the loop can be resumed. Bad data is not a failure: an entity that
meets it substitutes a safe value and reports a fault, and the tick completes, degraded.
"""

from __future__ import annotations

import math
import signal
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from dgraph.errors import GraphError

if TYPE_CHECKING:
    from dgraph.device import Device
    from dgraph.entity import Entity
    from dgraph.graph import Graph

Roles = dict[str, Any]
"""``devices``, ``stateful``, ``observers`` and ``commit`` (stateful, then observers) entities,
``periodic`` outputs of a graph, and its ``faults`` (a :class:`~dgraph.faults.FaultLog`)."""

PROGRESS_MIN_TICKS = 5000
"""Runs at least this long show a progress bar by default."""


def call_phase(entity: Entity, phase: str, t: int) -> None:
    """Run one phase (``prepare_state``, ``observe`` or ``commit_state``) of ``entity``."""
    getattr(entity, phase)(t)


def transition(roles: Roles, t: int, call: Callable[[Entity, str, int], None] = call_phase) -> None:
    """Steps 1-5 of a tick from ``t``: after it, every state is stamped ``t + 1``.

    ``call`` runs each entity phase (the profiler passes a timed version).
    """
    devices, stateful, observers, faults = roles["devices"], roles["stateful"], roles["observers"], roles["faults"]
    faults.begin(t)
    for device in devices:
        device.before.run(t)
    for output in roles["periodic"]:
        if t % output.period == 0:
            output.sample(t)
    for entity in stateful:
        call(entity, "prepare_state", t)
    for entity in observers:
        call(entity, "observe", t)
    for entity in roles["commit"]:
        call(entity, "commit_state", t + 1)
    faults.commit(t)


def run_after_hooks(devices: Sequence[Device], t_next: int) -> None:
    """Step 6 of a tick: the ``after`` hooks, at the new tick."""
    for device in devices:
        device.after.run(t_next)


def step(graph: Graph, call: Callable[[Entity, str, int], None] = call_phase) -> None:
    """Advance ``graph`` by one tick."""
    roles = graph.roles()
    transition(roles, graph.t, call)
    graph.t += 1
    run_after_hooks(roles["devices"], graph.t)


def run(graph: Graph, ticks: int | None = None, duration: float | None = None,
        progress: bool | None = None) -> None:
    """Run ``ticks`` ticks, or ``duration`` seconds of control time (``round(duration / dt)``).

    ``progress=None`` shows a progress bar (tqdm, on stderr) for runs of at least
    :data:`PROGRESS_MIN_TICKS` ticks.
    """
    if (ticks is None) == (duration is None):
        raise GraphError("run needs exactly one of ticks= or duration=")
    if duration is not None:
        if not (duration >= 0 and math.isfinite(duration / graph.dt)):
            raise GraphError(f"duration must be a finite number of seconds >= 0, got {duration!r}")
        ticks = round(duration / graph.dt)
    if not isinstance(ticks, int) or ticks < 0:
        raise GraphError(f"ticks must be an int >= 0, got {ticks!r}")
    if not graph.roles()["stateful"]:
        raise GraphError(f"graph {graph.name!r} has no device or stateful entity to step")
    show = ticks >= PROGRESS_MIN_TICKS if progress is None else progress
    with interrupts_between_ticks() as interrupted:
        if not show:
            for _ in range(ticks):
                step(graph)
                if interrupted():
                    raise KeyboardInterrupt(f"interrupted at tick {graph.t}")
            return
        from tqdm import tqdm
        with tqdm(total=ticks, unit="tick", desc=graph.name, mininterval=0.5, leave=False) as bar:
            for done in range(1, ticks + 1):
                step(graph)
                if interrupted():
                    raise KeyboardInterrupt(f"interrupted at tick {graph.t}")
                if done % 100 == 0 or done == ticks:
                    bar.update(done - bar.n)


@contextmanager
def interrupts_between_ticks() -> Iterator[Callable[[], bool]]:
    """Let Ctrl-C stop a run between two ticks, never in the middle of a commit.

    The first SIGINT is noted and the run stops after the current tick; a second one
    interrupts at once (for a tick that hangs). Only in the main thread; elsewhere a no-op.
    """
    if threading.current_thread() is not threading.main_thread():
        yield lambda: False
        return
    hits: list[int] = []

    def note(signum: int, frame: Any) -> None:
        if hits:
            raise KeyboardInterrupt
        hits.append(signum)

    previous = signal.signal(signal.SIGINT, note)
    try:
        yield lambda: bool(hits)
    finally:
        signal.signal(signal.SIGINT, previous)
