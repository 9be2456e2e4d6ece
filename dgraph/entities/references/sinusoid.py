"""Sinusoid: ``offset + amplitude * sin(2 pi f s + phase)`` and its derivatives."""

from __future__ import annotations

from typing import Any

import numpy as np

import dgraph as dg


@dg.register
class Sinusoid(dg.Entity):
    """A sinusoidal reference, with ``s = t * dt`` the time in seconds:

    ``output = offset + amplitude * sin(2 pi frequency s + phase)``,
    ``velocity`` and ``acceleration`` its first and second time derivatives.

    Parameters: ``amplitude`` (scalar or vector), ``frequency`` (Hz), ``phase`` (rad),
    ``offset`` (same shape as amplitude, default 0), ``dt`` (default: the graph's).
    Outputs depend on time only.
    """

    amplitude = dg.Param(kind="vector", doc="amplitude (scalar or vector)")
    frequency = dg.Param(kind="vector", doc="frequency in Hz (scalar or per component)")
    phase = dg.Param(0.0, kind="vector", doc="phase in rad (scalar or per component)")
    offset = dg.Param(0.0, kind="vector", doc="offset (scalar or per component)")
    dt = dg.Param(None, kind="float", doc="tick period in s (default: the graph's dt)")

    def configure(self) -> None:
        """Broadcast the parameters to a common shape."""
        self.value_shape = np.shape(self.amplitude)
        self._omega = 2.0 * np.pi * np.broadcast_to(self.frequency, self.value_shape)
        self._phase = np.broadcast_to(self.phase, self.value_shape)
        self._offset = np.broadcast_to(self.offset, self.value_shape)
        self._scalar = self.value_shape == ()

    def _wave(self, t: int, derivative: int) -> Any:
        s = t * self.dt
        arg = self._omega * s + self._phase
        if derivative == 0:
            value = self._offset + self.amplitude * np.sin(arg)
        elif derivative == 1:
            value = self.amplitude * self._omega * np.cos(arg)
        else:
            value = -self.amplitude * self._omega**2 * np.sin(arg)
        return float(value) if self._scalar else value

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def output(self, t: int) -> Any:
        """Position: ``offset + A sin(w s + phi)``."""
        return self._wave(t, 0)

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def velocity(self, t: int) -> Any:
        """Velocity: ``A w cos(w s + phi)``."""
        return self._wave(t, 1)

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def acceleration(self, t: int) -> Any:
        """Acceleration: ``-A w^2 sin(w s + phi)``."""
        return self._wave(t, 2)
