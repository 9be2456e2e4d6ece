"""SensorFault: a fault injected into a signal, as a broken sensor, cable or driver would produce it.

Plugged between a device's reading and its reader (``device.encoder_position -> fault.reading``,
``fault.output -> estimator.encoder_position``), it passes the reading through, except during
its window ``[start, start + ticks)`` (``start`` in seconds), where the chosen elements
(``indices``; all if empty) are:

- ``nan`` / ``inf``: NaN, or ``+inf`` (``-inf`` with a negative ``magnitude``);
- ``frozen``: the value they had at the first tick of the window;
- ``jump``: the reading plus ``magnitude``.

Its output may hold NaN and infinities by design (``finite=None``: value checks let them
through, as a real sensor would), so what it tests is how the readers cope.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

import dgraph as dg

KINDS = ("nan", "inf", "frozen", "jump")


@dg.register
class SensorFault(dg.Entity):
    """A fault on a float signal during a window of ticks (see the module docstring).

    Parameters: ``kind`` (``nan``, ``inf``, ``frozen``, ``jump``), ``start`` (s), ``ticks``
    (length of the window), ``indices`` (elements of the flattened reading; empty: all),
    ``magnitude`` (the jump, or the sign of the infinity).
    Inputs: ``reading``. Outputs: ``output`` (the reading, faulty during the window).
    States: ``frozen_value`` (the reading at the first tick of the window, for ``frozen``).
    """

    has_state = True

    kind = dg.Param(kind="str", choices=KINDS, doc="what the fault does to the reading")
    start = dg.Param(0.0, kind="float", minimum=0.0, doc="first tick of the window, in seconds")
    ticks = dg.Param(1, kind="int", minimum=1, doc="length of the window in ticks")
    indices = dg.Param([], kind="int_list", doc="elements at fault (flattened; empty: all)")
    magnitude = dg.Param(1.0, kind="float", doc="jump added to the reading, or the sign of inf")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, kind: Literal["nan", "inf", "frozen", "jump"], start: float = 0.0, ticks: int = 1,
            indices: Sequence[int] = (), magnitude: float = 1.0,
        ) -> None: ...

    reading = dg.Input(shape=None, doc="the sensor reading")
    frozen_value = dg.State(shape=None, finite=False, doc="the reading at the window's first tick")

    def setup(self) -> None:
        """No window tick known until the graph's dt is."""
        self._first: int | None = None
        self._staged = False

    def reset(self) -> None:
        """Nothing frozen yet."""
        self.frozen_value.set(np.zeros(0), 0)

    def window(self) -> range:
        """The ticks at fault."""
        if self._first is None:
            self._first = round(self.start / self.dt)
        return range(self._first, self._first + self.ticks)

    @dg.output(shape=None, depends=("reading", "frozen_value", "t"), finite=None)
    def output(self, t: int) -> Any:
        """The reading, faulty inside the window."""
        value = self.reading(t)
        window = self.window()
        if t not in window:
            return value
        value = np.array(value, dtype=float)
        flat = value.reshape(-1)
        at = slice(None) if not self.indices else list(self.indices)
        if self.kind == "nan":
            flat[at] = np.nan
        elif self.kind == "inf":
            flat[at] = np.inf if self.magnitude >= 0 else -np.inf
        elif self.kind == "jump":
            flat[at] += self.magnitude
        elif t > window.start:
            flat[at] = self.frozen_value(t).reshape(-1)[at]
        return value

    def prepare_state(self, t: int) -> None:
        """At the window's first tick, keep the reading (what ``frozen`` holds)."""
        self._staged = t == self.window().start
        if self._staged:
            self.frozen_value.stage(np.array(self.reading(t), dtype=float))

    def commit_state(self, t_next: int) -> None:
        """Publish the frozen reading."""
        if self._staged:
            self.frozen_value.commit(t_next)
            self._staged = False


__all__ = ["KINDS", "SensorFault"]
