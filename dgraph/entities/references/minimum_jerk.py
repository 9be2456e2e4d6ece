"""MinimumJerk: a quintic point-to-point move, ``10 s^3 - 15 s^4 + 6 s^5``."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg


def minimum_jerk(x: float) -> tuple[float, float, float]:
    """The quintic ``s(x) = 10 x^3 - 15 x^4 + 6 x^5`` and its first two derivatives in ``x``:
    ``s(0) = 0``, ``s(1) = 1``, zero first and second derivatives at both ends (every smooth
    move and ramp of the project: this entity, Sinusoid's fade-in, swings, contact ramps)."""
    return (x**3 * (10.0 - 15.0 * x + 6.0 * x * x), 30.0 * x * x * (1.0 - x) ** 2,
            60.0 * x * (1.0 - x) * (1.0 - 2.0 * x))

@dg.register
class MinimumJerk(dg.Entity):
    """A minimum-jerk move from an initial value to ``target`` in ``duration`` seconds.

    With ``tau = t * dt`` the time in seconds, ``s = clip((tau - start) / T, 0, 1)``, ``T`` the
    duration, ``p0`` the initial value and ``d = target - p0``::

        position     = p0 + d (10 s^3 - 15 s^4 + 6 s^5)
        velocity     = d / T   (30 s^2 - 60 s^3 + 30 s^4)
        acceleration = d / T^2 (60 s - 180 s^2 + 120 s^3)

    so position, velocity and acceleration are continuous, with zero velocity and acceleration
    at both ends. Before ``start`` the position is the initial value; after ``start + T`` it
    holds ``target``; velocity and acceleration are zero outside the move.

    The initial value is the input ``current`` sampled at the first tick at or after ``start``
    (plug it, e.g., to the measured position): the entity keeps that sample in its state
    ``origin`` (latched in the tick transition, so the move is the same whoever reads when).
    Before the start, ``position`` follows ``current``. Given the parameter ``initial``,
    ``current`` holds it as a constant (plugging ``current`` replaces it).

    Parameters: ``target`` (scalar or vector), ``duration`` (s, > 0), ``start`` (s, default 0),
    ``initial`` (optional, shape of ``target``), ``dt`` (default: the graph's).
    Inputs: ``current``. States: ``origin``. Outputs: ``position``, ``velocity``,
    ``acceleration`` (shape of ``target``; depend on time).
    """

    has_state = True
    target = dg.Param(kind="vector", doc="final value (scalar or vector)")
    duration = dg.Param(kind="float", maximum=1e9, doc="duration of the move in s (> 0)")
    start = dg.Param(0.0, kind="float", minimum=0.0, maximum=1e9, doc="time at which the move starts, in s")
    initial = dg.Param(None, kind="vector", doc="initial value (default: the input current at start)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, target: ArrayLike, duration: float, start: float = 0.0,
            initial: ArrayLike | None = None, dt: float | None = None,
        ) -> None: ...

    current = dg.Input(shape=lambda self: self.value_shape, doc="value sampled at the start tick")
    origin = dg.State(shape=lambda self: self.value_shape, doc="the initial value of the move, once started")

    def configure(self) -> None:
        """Check the duration and the shape of ``initial``."""
        if not (self.duration > 0 and math.isfinite(self.duration)):
            raise dg.ParamError(f"{self.name}: duration must be > 0, got {self.duration}", entity=self.name)
        self.value_shape = np.shape(self.target)
        if self.initial is not None and np.shape(self.initial) != self.value_shape:
            raise dg.ParamError(f"{self.name}: initial has shape {np.shape(self.initial)}, target "
                                f"{self.value_shape}", entity=self.name)
        self._scalar = self.value_shape == ()
        self._staged = False

    def setup(self) -> None:
        """``initial`` is the constant held by ``current``."""
        if self.initial is not None:
            self.current.set(self.initial)

    def reset(self) -> None:
        """Forget the latched origin: the move starts again from ``current`` at ``start``."""
        self._latched_at: int | None = None

    @property
    def start_tick(self) -> int:
        """The first tick at or after ``start``: where ``current`` is sampled."""
        return math.ceil(self.start / self.dt - 1e-9)

    def prepare_state(self, t: int) -> None:
        """At the start tick (or the first tick after it), sample ``current``."""
        self._staged = self._latched_at is None and t >= self.start_tick
        if self._staged:
            self.origin.stage(self.current(t))

    def commit_state(self, t_next: int) -> None:
        """Keep the sample as ``origin``, stamped with the next tick."""
        if self._staged:
            self.origin.commit(t_next)
            self._latched_at = t_next - 1
            self._staged = False

    def _p0(self, t: int) -> Any:
        if self._latched_at is not None and t > self._latched_at:
            return self.origin(t)
        return self.current(t)  # before the start, or at the sampled tick itself

    def _s(self, t: int) -> float:
        return min(max((t * self.dt - self.start) / self.duration, 0.0), 1.0)

    def _out(self, value: Any) -> Any:
        return float(value) if self._scalar else value

    @dg.output(shape=lambda self: self.value_shape, depends=("t", "current", "origin"), on_demand=("current",))
    def position(self, t: int) -> Any:
        """``p0 + (target - p0)(10 s^3 - 15 s^4 + 6 s^5)``."""
        if t < self.start_tick:
            return self._out(np.array(self.current(t), dtype=float))
        s = self._s(t)
        p0 = np.asarray(self._p0(t), dtype=float)
        return self._out(p0 + (self.target - p0) * minimum_jerk(s)[0])

    @dg.output(shape=lambda self: self.value_shape, depends=("t", "current", "origin"), on_demand=("current",))
    def velocity(self, t: int) -> Any:
        """``(target - p0) / T (30 s^2 - 60 s^3 + 30 s^4)``."""
        if t < self.start_tick:
            return self._out(np.zeros(self.value_shape))
        s = self._s(t)
        p0 = np.asarray(self._p0(t), dtype=float)
        return self._out((self.target - p0) / self.duration * minimum_jerk(s)[1])

    @dg.output(shape=lambda self: self.value_shape, depends=("t", "current", "origin"), on_demand=("current",))
    def acceleration(self, t: int) -> Any:
        """``(target - p0) / T^2 (60 s - 180 s^2 + 120 s^3)``."""
        if t < self.start_tick:
            return self._out(np.zeros(self.value_shape))
        s = self._s(t)
        p0 = np.asarray(self._p0(t), dtype=float)
        return self._out((self.target - p0) / self.duration**2 * minimum_jerk(s)[2])
