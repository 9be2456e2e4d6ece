"""VelocityTask: a velocity-level task ``J v = -lambda e + x_dot*`` on a feature, for a priority stack."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.control.feature import FeatureValue
from dgraph.control.rows import RowBlock
from dgraph.entities.activation import Activatable
from dgraph.entities.constants import constant_problems
from dgraph.entities.features.feature import per_row_of_feature_problem
from dgraph.entities.hierarchy.adaptive_gain import adaptive_gain
from dgraph.entities.robot.robot_state import RobotState
from dgraph.entities.tasks.gains import Gains


@dg.register
class VelocityTask(Activatable, dg.Entity):
    """A task of the inverse-kinematics stack (thesis Eq. 4.1–4.2, 2.45; SoT's Task).

    With the feature's ``e = x (-) x*``, ``J`` and ``e_dot = J v - x_dot*`` (so the reference
    velocity is ``x_dot* = J v - e_dot``, read at the state the feature was evaluated at), the
    task imposes the first-order error dynamics ``e_dot = -lambda e``, i.e. the rows

    ``J v = x_dot* - lambda e``        (equalities over the velocity ``v``)

    ⚠ The thesis prints Eq. 4.2 with ``+K_P``; with ``e = x (-) x*`` the stable law is
    ``-lambda e`` (Eq. 2.42/2.45, notes §1). The gain is the input ``gain`` (scalar or per row,
    >= 0, 1/s), or, with ``adaptive``, SoT's adaptive gain
    ``lambda(e) = (l0 - linf) exp(-l0' / (l0 - linf) ||e||) + linf`` from the inputs
    ``gain_at_zero`` (l0), ``gain_at_infinity`` (linf), ``gain_slope`` (l0').

    Parameters: ``adaptive`` (bool).
    Inputs: ``feature`` (a feature's ``feature`` output), ``robot`` (the state that feature
    read, for ``J v``), ``gain`` or the three adaptive-gain
    inputs, ``active`` (bool; commands ``activate`` / ``deactivate``; an inactive task adds
    no row to its level).
    Outputs: ``rows`` (:class:`~dgraph.control.rows.RowBlock`, plugged into a hierarchical solver),
    ``desired_velocity`` (``x_dot* - lambda e``), ``gain_value`` (``lambda``, per row).
    """

    adaptive = dg.Param(False, kind="bool", doc="use SoT's adaptive gain instead of a constant gain")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, adaptive: bool = False) -> None: ...

    feature = dg.Input(dtype=FeatureValue, doc="the feature's value (error, rate, Jacobian)")
    robot = dg.Input(dtype=RobotState, doc="the RobotModel's state the feature was evaluated at (for J v)")

    def configure(self) -> None:
        """Declare the gain inputs."""
        if self.adaptive:
            for name, default, doc in (("gain_at_zero", 1.0, "l0: the gain at e = 0 (1/s)"),
                                       ("gain_at_infinity", 1.0, "linf: the gain far away (1/s)"),
                                       ("gain_slope", 0.0, "l0': minus the slope at e = 0")):
                self.declare(name, dg.Input(shape=(), default=default, minimum=0.0, doc=doc))
        else:
            self.declare("gain", dg.Input(default=1.0, minimum=0.0, doc="lambda (scalar or per row, 1/s)"))
        self._gains = Gains(self)

    def constant_problem(self, name: str, value: object) -> str | None:
        """A constant ``gain`` is a scalar or one per row of the plugged feature."""
        return per_row_of_feature_problem(self.feature, value) if name == "gain" else None

    def check(self) -> list[str]:
        """The constant gain fits the plugged feature; constant adaptive gains have l0 >= linf."""
        found = constant_problems(self)
        if self.adaptive and self.gain_at_zero.source is None and self.gain_at_infinity.source is None \
                and self.gain_at_zero.value < self.gain_at_infinity.value:
            found.append(f"the adaptive gain needs gain_at_zero >= gain_at_infinity, got {self.gain_at_zero.value} "
                         f"< {self.gain_at_infinity.value}")
        return found

    def _feature(self, t: int) -> FeatureValue:
        return self.feature(t)

    @dg.output(shape=None)
    def gain_value(self, t: int) -> np.ndarray:
        """``lambda`` per row (constant, or adaptive in ``||e||``)."""
        error = self._feature(t).error
        if not self.adaptive:
            return self._gains.vector("gain", len(error), t)
        at_zero, at_infinity, slope = (float(self.gain_at_zero(t)), float(self.gain_at_infinity(t)),
                                       float(self.gain_slope(t)))
        if not at_zero >= at_infinity >= 0.0 or not slope >= 0.0:
            raise dg.SpecError(f"{self.name} at tick {t}: the adaptive gain needs l0 >= linf >= 0 and l0' >= 0, "
                               f"got {at_zero}, {at_infinity}, {slope}", entity=self.name, signal="gain_at_zero")
        return np.full(len(error), adaptive_gain(float(np.linalg.norm(error)), at_zero, at_infinity, slope))

    @dg.output(shape=None, depends=("feature", "robot", "gain_value"))
    def desired_velocity(self, t: int) -> np.ndarray:
        """``x_dot* - lambda e`` with ``x_dot* = J v - e_dot``."""
        f = self._feature(t)
        reference_velocity = f.jacobian @ self.robot(t).v - f.error_velocity
        return reference_velocity - self.gain_value(t) * f.error

    @dg.output(dtype=RowBlock, depends=("feature", "desired_velocity", "active"))
    def rows(self, t: int) -> RowBlock:
        """``J v = x_dot* - lambda e`` (no row while inactive)."""
        return RowBlock.equalities(self._feature(t).jacobian, self.desired_velocity(t), bool(self.active(t)))
