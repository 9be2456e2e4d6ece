"""ForceTask: the force part of a Cartesian force-contact task, a PI with feed-forward (thesis Eq. 4.12)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.entities.constants import per_row_problem
from dgraph.entities.tasks.gains import Gains


@dg.register
class ForceTask(dg.Entity):
    """PI+ force law with anti-windup (thesis Eq. 4.12, after Shahriari et al.):

    ``e_f = F* - F_ext``,  ``F_F = F* + P_F e_f + I_F integral(e_f)``,

    with the integral clamped so that ``|I_F integral(e_f)| <= integral_limit`` on every axis
    (the thesis names an anti-windup but no law). ``F_F`` is the force the solver should make
    the contact carry: plug ``force`` into a :class:`~dgraph.entities.contacts.PointContact`'s
    ``force_reference``; the contact's motion rows do the position part (parallel
    force/position control, thesis §4.3.4). While ``active`` is false the integral is reset
    and ``force = F*``. Forces are those of the environment on the robot, world axes.

    Parameters: ``size`` (3 for a force, 6 for a wrench), ``integral_limit`` (N).
    Inputs: ``reference`` (``F*``), ``measured`` (``F_ext``), ``p_gain`` (``P_F``), ``i_gain``
    (``I_F``, 1/s; scalars or per axis, >= 0), ``active``.
    State: ``integral`` (of ``e_f``, N s). Outputs: ``force`` (``F_F``), ``error`` (``e_f``).
    """

    has_state = True
    size = dg.Param(3, kind="int", minimum=1, maximum=6, doc="3 (force) or 6 (wrench)")
    integral_limit = dg.Param(20.0, kind="float", minimum=0.0, doc="largest |I_F integral| per axis (N)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, size: int = 3, integral_limit: float = 20.0, dt: float | None = None,
        ) -> None: ...

    reference = dg.Input(shape=("size",), doc="F*: desired force on the robot")
    measured = dg.Input(shape=("size",), doc="F_ext: measured force on the robot")
    p_gain = dg.Input(default=0.0, minimum=0.0, doc="P_F (scalar or per axis)")
    i_gain = dg.Input(default=0.0, minimum=0.0, doc="I_F in 1/s (scalar or per axis)")
    active = dg.Input(shape=(), dtype="bool", default=True, doc="false: reset the integral, force = F*")
    integral = dg.State(shape=("size",), doc="integral of e_f (N s)")

    def configure(self) -> None:
        """Gain conversion."""
        self._gains = Gains(self)

    def constant_problem(self, name: str, value: object) -> str | None:
        """The gains are a scalar or one per axis of the force (or wrench)."""
        return per_row_problem(value, self.size, "axis of the force") if name in ("p_gain", "i_gain") else None
    def reset(self) -> None:
        """Zero integral."""
        self.integral.set(np.zeros(self.size), 0)

    @dg.output(shape=("size",), depends=("reference", "measured"))
    def error(self, t: int) -> np.ndarray:
        """``e_f = F* - F_ext``."""
        return self.reference(t) - self.measured(t)

    @dg.output(shape=("size",), depends=("reference", "error", "p_gain", "i_gain", "active", "integral"),
               on_demand=("error",))  # read only while active
    def force(self, t: int) -> np.ndarray:
        """``F* + P_F e_f + I_F integral(e_f)`` (``F*`` while inactive)."""
        if not self.active(t):
            return self.reference(t)
        p, i = self._gains.vector("p_gain", self.size, t), self._gains.vector("i_gain", self.size, t)
        return self.reference(t) + p * self.error(t) + i * self.integral(t)

    def prepare_state(self, t: int) -> None:
        """Integrate ``e_f`` while active (clamped: anti-windup); reset it while inactive."""
        if not self.active(t):
            self.integral.stage(np.zeros(self.size))
            return
        i = self._gains.vector("i_gain", self.size, t)
        integral = self.integral(t) + self.dt * self.error(t)
        limit = np.divide(self.integral_limit, i, out=np.full(self.size, np.inf), where=i > 0)
        self.integral.stage(np.clip(integral, -limit, limit))

    def commit_state(self, t_next: int) -> None:
        """Publish the integral."""
        self.integral.commit(t_next)
