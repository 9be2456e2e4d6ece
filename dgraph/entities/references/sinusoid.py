"""Sinusoid: ``offset + amplitude * sin(2 pi f s + phase)`` and its derivatives."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.references.minimum_jerk import minimum_jerk


@dg.register
class Sinusoid(dg.Entity):
    """A sinusoidal reference, with ``s = t * dt`` the time in seconds:

    ``output = offset + amplitude * sin(2 pi frequency s + phase)``,
    ``velocity`` and ``acceleration`` its first and second time derivatives.

    With ``ramp = T > 0`` the amplitude fades in over the first ``T`` seconds with the
    minimum-jerk envelope ``e(s) = 10 x^3 - 15 x^4 + 6 x^5``, ``x = min(s / T, 1)``:
    ``output = offset + e(s) A sin(w s + phase)`` (and its exact derivatives), so a robot at
    rest can follow from the first tick without a velocity step.

    Parameters: ``amplitude`` (scalar or vector), ``frequency`` (Hz), ``phase`` (rad),
    ``offset`` (same shape as amplitude, default 0), ``ramp`` (s, default 0: no fade-in),
    ``dt`` (default: the graph's).
    Outputs depend on time only.
    """

    amplitude = dg.Param(kind="vector", doc="amplitude (scalar or vector)")
    frequency = dg.Param(kind="vector", doc="frequency in Hz (scalar or per component)")
    phase = dg.Param(0.0, kind="vector", doc="phase in rad (scalar or per component)")
    offset = dg.Param(0.0, kind="vector", doc="offset (scalar or per component)")
    ramp = dg.Param(0.0, kind="float", minimum=0.0, doc="fade-in duration of the amplitude in s (0: none)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, amplitude: ArrayLike, frequency: ArrayLike, phase: ArrayLike = 0.0,
            offset: ArrayLike = 0.0, ramp: float = 0.0, dt: float | None = None,
        ) -> None: ...

    def configure(self) -> None:
        """Broadcast the parameters to a common shape; a frequency and a phase shared by every
        component are kept as floats (one ``math.sin`` and ``math.cos`` per tick)."""
        self.value_shape = np.shape(self.amplitude)
        self._amplitude = np.asarray(self.amplitude, dtype=float)
        omega = 2.0 * np.pi * self._per_component("frequency")
        phase = self._per_component("phase")
        self._offset = self._per_component("offset")
        self._scalar = self.value_shape == ()
        if omega.size and (omega == omega.flat[0]).all() and (phase == phase.flat[0]).all():
            self._omega, self._phase = float(omega.flat[0]), float(phase.flat[0])
            self._sin, self._cos = math.sin, math.cos
        else:
            self._omega, self._phase, self._sin, self._cos = omega, phase, np.sin, np.cos
        self._last_tick: int | None = None  # the tick of _last_waves
        self._last_waves: tuple[Any, Any, Any] = ()

    def _per_component(self, name: str) -> np.ndarray:
        """The parameter ``name`` broadcast to the amplitude's shape (``ParamError`` if it does not fit)."""
        value = getattr(self, name)
        try:
            return np.broadcast_to(value, self.value_shape)
        except ValueError:
            raise dg.ParamError(f"{self.name}: {name} has shape {np.shape(value)} but amplitude {self.value_shape}: "
                                "give a scalar or one value per component", entity=self.name) from None

    def _envelope(self, s: float) -> tuple[float, float, float]:
        """``e, e_dot, e_ddot`` of the fade-in at time ``s``."""
        ramp = self.ramp
        if ramp <= 0.0 or s >= ramp:
            return 1.0, 0.0, 0.0
        e, de, dde = minimum_jerk(max(s, 0.0) / ramp)
        return e, de / ramp, dde / ramp**2

    def _waves(self, t: int) -> tuple[Any, Any, Any]:
        """Position, velocity and acceleration at tick ``t``, computed together once per tick:
        ``offset + k0 A``, ``k1 A``, ``k2 A`` with ``k0 = e sin``, ``k1 = e w cos + e_dot sin``,
        ``k2 = -e w^2 sin + 2 e_dot w cos + e_ddot sin`` (``sin``, ``cos`` of ``w s + phase``)."""
        if t == self._last_tick:
            return self._last_waves
        s = t * self.dt
        omega = self._omega
        arg = omega * s + self._phase
        sin, cos = self._sin(arg), self._cos(arg)
        e, de, dde = self._envelope(s)
        waves = self._scaled(e * sin, e * omega * cos + de * sin,
                             -e * omega * omega * sin + 2 * de * omega * cos + dde * sin)
        self._last_tick, self._last_waves = t, waves
        return waves

    def _scaled(self, k0: Any, k1: Any, k2: Any) -> tuple[Any, Any, Any]:
        """``offset + k0 A``, ``k1 A``, ``k2 A`` (Python floats for a scalar sinusoid)."""
        amplitude = self._amplitude
        waves = (self._offset + k0 * amplitude, k1 * amplitude, k2 * amplitude)
        return tuple(float(w) for w in waves) if self._scalar else waves

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def output(self, t: int) -> Any:
        """Position: ``offset + e(s) A sin(w s + phi)``."""
        return self._waves(t)[0]

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def velocity(self, t: int) -> Any:
        """Velocity: its time derivative."""
        return self._waves(t)[1]

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def acceleration(self, t: int) -> Any:
        """Acceleration: its second time derivative."""
        return self._waves(t)[2]
