"""JointLimits: joint position and velocity limits as velocity inequalities for a priority stack."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.control.rows import RowBlock, selection
from dgraph.entities.activation import Activatable
from dgraph.entities.robot.loading import load_model
from dgraph.entities.robot.robot_state import RobotState, plugged_model


@dg.register
class JointLimits(Activatable, dg.Entity):
    """The model's joint limits as bounds on the next velocity (SoT's joint-limit task).

    For each one-degree-of-freedom joint ``j`` (position ``q_j``, velocity ``v_j``) of the
    model, with the model's limits ``q_min``, ``q_max``, ``v_max``:

    ``q_min <= q_j + dt v_j <= q_max`` and ``|v_j| <= v_max``,

    i.e. ``l_j <= v_j <= u_j`` with ``l_j = clip((q_min - q_j) / dt, -v_max, v_max)`` and
    ``u_j = clip((q_max - q_j) / dt, -v_max, v_max)`` (the thesis gives no limit values and no
    mapping, notes §14; these are the integration of the IK scheme, ``q+ = q (+) dt v``). A
    joint outside its range is brought back at most at ``v_max`` (the bounds stay ordered).
    Infinite limits bound nothing.

    Parameters: ``model`` (sizes the rows; the same robot as the RobotModel), ``dt`` (default:
    the graph's), ``velocity_scale`` (fraction of ``v_max`` allowed).
    Inputs: ``robot`` (RobotModel state, for ``q``), ``active`` (bool; commands ``activate`` /
    ``deactivate``).
    Outputs: ``rows`` (:class:`~dgraph.control.rows.RowBlock`, inequalities over ``v``).
    """

    model = dg.Param("talos", kind="name_or_path", doc="robot name, URDF path or pinocchio.Model (sizes the rows)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="integration period in s (default: the graph's dt)")
    velocity_scale = dg.Param(1.0, kind="float", minimum=0.0, doc="fraction of the velocity limits allowed")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", dt: float | None = None, velocity_scale: float = 1.0,
        ) -> None: ...

    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")

    def configure(self) -> None:
        """The one-dof joints and their limits."""
        model = load_model(self.model, self.name)
        self.nv = model.nv
        joints = [model.joints[j] for j in range(1, model.njoints) if model.joints[j].nv == 1]
        self._q_index = np.array([j.idx_q for j in joints], dtype=int)
        v_index = np.array([j.idx_v for j in joints], dtype=int)
        self._q_min = model.lowerPositionLimit[self._q_index].copy()
        self._q_max = model.upperPositionLimit[self._q_index].copy()
        self._v_max = self.velocity_scale * model.velocityLimit[v_index]
        self._selection = selection(v_index, model.nv)

    def check(self) -> list[str]:
        """The plugged robot model must be the size of ``model``."""
        model = plugged_model(self.robot)
        if model is not None and model.nv != self.nv:
            return [f"its model has nv = {self.nv} but the plugged robot has nv = {model.nv}"]
        return []

    @dg.output(dtype=RowBlock, depends=("robot", "active"))
    def rows(self, t: int) -> RowBlock:
        """``l <= S v <= u`` (see the class docstring)."""
        q = self.robot(t).q[self._q_index]
        with np.errstate(invalid="ignore"):  # inf - inf cannot happen: limits are finite or one-sided
            lower = np.clip((self._q_min - q) / self.dt, -self._v_max, self._v_max)
            upper = np.clip((self._q_max - q) / self.dt, -self._v_max, self._v_max)
        return RowBlock.inequalities(self._selection, lower, upper, bool(self.active(t)))
