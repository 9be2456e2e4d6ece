"""The clock shared by the signals of one graph: current tick and time-driven invalidation.

Reading any signal at a tick different from :attr:`Clock.t` advances the clock first, which
invalidates the time-varying outputs (those declaring ``"t"`` in their dependencies) and
releases periodic outputs whose hold has expired. Everything else becomes stale only when a
source it depends on changes (a constant is set, a device commits its state).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from dgraph.signals.signal import Output


class Clock:
    """Current tick and switches shared by every signal of a graph.

    Attributes:
        t: the last tick at which a signal was read (``None`` before the first read).
        cache_enabled: when False every read recomputes (for validating the cache).
        check_values: check each computed value against its spec (shape, NaN).
        profiling: time each computation (``Output.total_duration``, exclusive of upstream).
        inner: profiling accumulator of the time spent in nested computations.
    """

    __slots__ = ("cache_enabled", "check_values", "held", "inner", "profiling", "t", "time_varying")

    def __init__(self) -> None:
        self.t: int | None = None
        self.time_varying: list[Output] = []
        self.held: list[Output] = []
        self.cache_enabled = True
        self.check_values = True
        self.profiling = False
        self.inner = 0.0

    def advance(self, t: int) -> None:
        """Move to tick ``t``: invalidate time-varying outputs and release the holds of periodic
        outputs whose period window has ended."""
        self.t = t
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
