"""Task: an acceleration-level task ``J a = a* - J_dot v - Kp e - Kd e_dot`` with a weight."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.control.equation import TaskEquation
from dgraph.control.feature import FeatureValue
from dgraph.entities.constants import constant_problems
from dgraph.entities.features.feature import per_row_of_feature_problem
from dgraph.entities.tasks.gains import Gains

GAINS = ("kp", "kd", "weight")
"""The inputs of a Task that take a scalar or one value per row of its feature."""


@dg.register
class Task(dg.Entity):
    """A weighted acceleration task on a feature (thesis Eq. 4.7–4.8, TSID's task form).

    With the feature's ``e = x (-) x*``, ``e_dot``, ``J``, ``J_dot v`` and ``x_ddot*``,
    the desired task acceleration is the PD law

    ``x_ddot_des = x_ddot* - Kp e - Kd e_dot``

    and the task asks the solver for ``J a + J_dot v = x_ddot_des``, i.e. the row block
    ``A = J``, ``b = x_ddot_des - J_dot v`` with cost ``weight * ||A a - b||^2``
    (thesis Eq. 4.14's ``lambda_i ||O_i y - o_i||^2``). Thesis Eq. 4.8 writes the same law with
    ``e = x* (-) x``; see ``docs/control.md``.

    Parameters: ``critical_damping`` (when true, ``Kd = 2 sqrt(Kp)`` and there is no ``kd``
    input).
    Inputs: ``feature`` (a feature's ``feature`` output), ``kp``, ``kd`` (scalar or one gain
    per row, >= 0), ``weight`` (scalar or per row, >= 0; default 1). A constant's sign is checked
    when it is set, its length too once the feature is plugged (else by :meth:`check`); values
    that arrive through a plug are checked at each tick.
    Outputs: ``equation`` (:class:`TaskEquation`, plugged into a solver),
    ``desired_acceleration`` (``x_ddot_des``), ``proportional_gains`` and ``derivative_gains``
    (``Kp``, ``Kd`` as vectors of the feature's size).
    """

    critical_damping = dg.Param(False, kind="bool", doc="use Kd = 2 sqrt(Kp) instead of a kd input")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, critical_damping: bool = False) -> None: ...

    feature = dg.Input(dtype=FeatureValue, doc="the feature's value (error, rate, Jacobian, drift)")
    kp = dg.Input(default=0.0, minimum=0.0, doc="proportional gain (scalar or per row)")
    weight = dg.Input(default=1.0, minimum=0.0, doc="task weight (scalar or per row)")

    def configure(self) -> None:
        """Declare ``kd`` unless the damping is critical."""
        if not self.critical_damping:
            self.declare("kd", dg.Input(default=0.0, minimum=0.0, doc="derivative gain (scalar or per row)"))
        self._gain_vectors = Gains(self)
        self._critical: tuple[np.ndarray, np.ndarray] | None = None

    def constant_problem(self, name: str, value: object) -> str | None:
        """A gain or weight must be a scalar or one value per row of the plugged feature."""
        return per_row_of_feature_problem(self.feature, value) if name in GAINS else None

    def check(self) -> list[str]:
        """The constant gains and weight fit the plugged feature (set before it was plugged)."""
        return constant_problems(self)

    def _critical_kd(self, kp: np.ndarray) -> np.ndarray:
        """``Kd = 2 sqrt(Kp)``, computed again only for a new ``kp`` vector."""
        if self._critical is None or self._critical[0] is not kp:
            kd = 2.0 * np.sqrt(kp)
            kd.flags.writeable = False  # handed out at every tick, like kp
            self._critical = (kp, kd)
        return self._critical[1]

    @dg.output(dtype=TaskEquation)
    def equation(self, t: int) -> TaskEquation:
        """``A = J``, ``b = x_ddot_des - J_dot v``, per-row weights, and the feature and gains
        (the only output a solver reads: the gains and the desired acceleration come with it)."""
        f = self.feature(t)
        size = len(f.error)
        gains = self._gain_vectors
        kp = gains.vector("kp", size, t)
        kd = self._critical_kd(kp) if self.critical_damping else gains.vector("kd", size, t)
        weight = gains.vector("weight", size, t)
        return TaskEquation(f.jacobian, pd_law(f, kp, kd) - f.drift, weight, f, kp, kd)

    @dg.output(shape=None, depends=("equation",))
    def proportional_gains(self, t: int) -> np.ndarray:
        """``Kp``, one gain per row of the feature (for plots; computed only when read)."""
        return self.equation(t).kp

    @dg.output(shape=None, depends=("equation",))
    def derivative_gains(self, t: int) -> np.ndarray:
        """``Kd``, one gain per row (``2 sqrt(Kp)`` with critical damping)."""
        return self.equation(t).kd

    @dg.output(shape=None, depends=("equation",))
    def desired_acceleration(self, t: int) -> np.ndarray:
        """``x_ddot* - Kp e - Kd e_dot`` (for plots; computed only when read)."""
        equation = self.equation(t)
        return pd_law(equation.feature, equation.kp, equation.kd)


def pd_law(feature: FeatureValue, kp: np.ndarray, kd: np.ndarray) -> np.ndarray:
    """The desired task acceleration ``x_ddot_des = x_ddot* - Kp e - Kd e_dot`` (Eq. 4.8, with
    ``e = x (-) x*``)."""
    return feature.reference_acceleration - kp * feature.error - kd * feature.error_velocity
