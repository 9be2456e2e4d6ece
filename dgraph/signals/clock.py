"""The clock shared by the signals of one graph: current tick and time-driven invalidation.

Reading any signal at a tick different from :attr:`Clock.t` advances the clock first, which
invalidates the time-varying outputs (those declaring ``"t"`` in their dependencies) and
releases periodic outputs whose hold has expired. Everything else becomes stale only when a
source it depends on changes (a constant is set, a device commits its state).

The clock also keeps the latest tick it reached (:attr:`Clock.latest`): a read at an earlier
tick (by hand; the loop only moves forward) is a *past read*, which
:meth:`Output._evaluate_past <dgraph.signals.signal.Output._evaluate_past>` checks so that no
stamp moves backwards.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from dgraph.signals.signal import Output

BEFORE_TIME = -(2**63)
"""The :attr:`Clock.latest` of a clock nothing was read on yet (an int below any tick)."""


class Clock:
    """Current tick and switches shared by every signal of a graph.

    Attributes:
        t: the last tick at which a signal was read (``None`` before the first read).
        latest: the latest tick at which a signal was read (:data:`BEFORE_TIME` before the first
            read); every stamp computed on this clock is at most this.
        cache_enabled: when False every read recomputes (for validating the cache).
        check_values: check each computed value against its spec (shape, NaN, inf); a debugging aid, off by
            default (shapes are checked at plug time; devices and solvers check what they consume).
        profiling: time each computation (``Output.total_duration``, exclusive of upstream).
        inner: profiling accumulator of the time spent in nested computations.
    """

    __slots__ = ("cache_enabled", "check_values", "held", "inner", "latest", "periodic", "profiling", "t",
                 "time_varying")

    def __init__(self) -> None:
        self.t: int | None = None
        self.latest = BEFORE_TIME
        self.time_varying: list[Output] = []
        self.periodic: list[Output] = []
        self.held: list[Output] = []
        self.cache_enabled = True
        self.check_values = False
        self.profiling = False
        self.inner = 0.0

    def advance(self, t: int) -> None:
        """Move to tick ``t``: invalidate time-varying outputs, release the holds of periodic
        outputs whose window has ended, then stamp ``t`` on periodic outputs still valid at the
        start of a window (that is the window's sample). Moving back leaves :attr:`latest`."""
        self.t = t
        if t > self.latest:
            self.latest = t
        for output in self.time_varying:
            output.invalidate()
        if self.held:
            still_held = []
            for output in self.held:
                if t >= output.next_sample() or t < output.time:
                    output.release_hold()
                else:
                    still_held.append(output)
            self.held = still_held
        for output in self.periodic:  # a value still valid at a window start is that window's sample
            if t % output.period == 0 and not output._stale and output._time is not None and output._time < t:
                output._time = t

    def register(self, output: Output) -> None:
        """Follow ``output`` if it is time-varying, periodic or holding a value."""
        if output.time_varying:
            self.time_varying.append(output)
        if output.period > 1:
            self.periodic.append(output)
        if output._held:
            self.held.append(output)

    def forget(self, outputs: list[Output]) -> None:
        """Stop following ``outputs`` (their entity leaves the graph)."""
        gone = {id(o) for o in outputs}
        self.time_varying = [o for o in self.time_varying if id(o) not in gone]
        self.periodic = [o for o in self.periodic if id(o) not in gone]
        self.held = [o for o in self.held if id(o) not in gone]
