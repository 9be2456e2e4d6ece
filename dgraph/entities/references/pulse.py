"""Pulse: ``magnitude * direction`` for ``duration`` seconds from ``start``, zero otherwise."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg


@dg.register
class Pulse(dg.Entity):
    """A rectangular pulse: a constant vector during a time window, zero before and after it
    (a push: a wrench ``[fx, fy, fz, tx, ty, tz]`` for a ``MujocoDevice``'s ``wrench_<body>``).

    With ``k0 = round(start / dt)`` and ``n = round(duration / dt)`` the window in ticks::

        value(t) = magnitude * direction   if k0 <= t < k0 + n
                   0                       otherwise

    so the pulse lasts exactly ``n`` ticks and its impulse is ``magnitude * direction * n dt``
    (a device applies ``value(t)`` over the step ``t -> t + 1``). ``direction`` is used as given,
    not normalised: ``[1, 1, 0]`` with magnitude ``F`` pushes ``F`` along each of x and y. The
    magnitude is a separate scalar so that one setting scales the whole pulse (a bisection over
    the largest push a controller survives).

    Parameters: ``direction`` (vector, any length), ``magnitude`` (scalar), ``start`` (s, >= 0),
    ``duration`` (s, >= 0; 0: no pulse), ``dt`` (default: the graph's).
    Outputs: ``value`` (the shape of ``direction``; depends on time only).
    """

    direction = dg.Param(kind="vector", doc="the pulse's vector for magnitude 1 (e.g. a 6D wrench), used as given")
    magnitude = dg.Param(kind="float", doc="scale of direction during the pulse")
    start = dg.Param(kind="float", minimum=0.0, maximum=1e9, doc="time at which the pulse starts, in s")
    duration = dg.Param(kind="float", minimum=0.0, maximum=1e9, doc="length of the pulse in s (0: none)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, direction: ArrayLike, magnitude: float, start: float, duration: float,
            dt: float | None = None,
        ) -> None: ...

    def configure(self) -> None:
        """The two values the output alternates between (read-only)."""
        self.value_shape = np.shape(self.direction)
        if not (math.isfinite(self.magnitude) and np.isfinite(self.direction).all()):
            raise dg.ParamError(f"{self.name}: magnitude and direction must be finite", entity=self.name)
        self._on = self._frozen(self.magnitude * np.asarray(self.direction, dtype=float))
        self._off = self._frozen(np.zeros(self.value_shape))

    def _frozen(self, array: np.ndarray) -> Any:
        """A float for a scalar pulse, else a read-only array."""
        if self.value_shape == ():
            return float(array)
        array.setflags(write=False)
        return array

    @property
    def window(self) -> tuple[int, int]:
        """``(k0, k0 + n)``: the first tick of the pulse and the first tick after it."""
        first = round(self.start / self.dt)
        return first, first + round(self.duration / self.dt)

    @dg.output(shape=lambda self: self.value_shape, depends=("t",))
    def value(self, t: int) -> Any:
        """``magnitude * direction`` during the window ``[k0, k0 + n)``, else zero."""
        first, end = self.window
        return self._on if first <= t < end else self._off
