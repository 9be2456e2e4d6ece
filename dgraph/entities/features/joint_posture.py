"""JointPosture: actuated joint positions against a reference posture."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.control.feature import FeatureValue
from dgraph.entities.features.feature import Feature
from dgraph.entities.robot.loading import load_model
from dgraph.entities.robot.robot_state import RobotState, plugged_model
from dgraph.entities.selection import contiguous


@dg.register
class JointPosture(Feature):
    """Joint positions ``q_j`` against ``q_j*`` (the thesis's posture regularisation).

    ``error = q_j - q_j*``, ``error_velocity = v_j - v_j*``, ``jacobian = S_j`` (the rows of
    the identity selecting the joints' velocities), ``drift = 0``,
    ``reference_acceleration = a_j*``. One-degree-of-freedom joints only.

    Parameters: ``model`` (to size the ports and find the reference posture; default
    ``talos``), ``joints`` (names; default every joint with one degree of freedom),
    ``reference_configuration`` (a named configuration of the model, default
    ``half_sitting``, the default of the ``reference`` input; empty: no default).
    Inputs: ``robot``, ``reference`` (n joints), ``reference_velocity``,
    ``reference_acceleration`` (n, default 0).
    """

    model = dg.Param("talos", kind="name_or_path", doc="robot name, URDF path or pinocchio.Model (sizes the ports)")
    joints = dg.Param((), kind="str_list", doc="joint names (default: every 1-dof joint)")
    reference_configuration = dg.Param("half_sitting", kind="str", doc="named configuration used as default")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", joints: Sequence[str] = (),
            reference_configuration: str = "half_sitting",
        ) -> None: ...

    def configure(self) -> None:
        """Resolve the joints and declare the inputs sized by them."""
        model = load_model(self.model, self.name)
        self.nv = model.nv
        names = list(self.joints) or [model.names[j] for j in range(1, model.njoints) if model.joints[j].nv == 1]
        self.q_index, self.v_index = [], []
        for name in names:
            if not model.existJointName(name) or model.joints[model.getJointId(name)].nv != 1:
                raise dg.ParamError(f"{self.name}: {name!r} is not a one-dof joint of the model", entity=self.name)
            joint = model.joints[model.getJointId(name)]
            self.q_index.append(joint.idx_q)
            self.v_index.append(joint.idx_v)
        self.rows, self.size = None, len(names)
        self.joint_names = names
        self._selection = np.zeros((self.size, model.nv))
        self._selection[np.arange(self.size), self.v_index] = 1.0
        self._zeros = np.zeros(self.size)
        for constant in (self._selection, self._zeros):  # shared by every tick's value: read-only
            constant.flags.writeable = False
        self.q_index, self.v_index = contiguous(np.array(self.q_index)), contiguous(np.array(self.v_index))
        default = self._named_configuration(model)
        self.declare("reference", dg.Input(shape=(self.size,), doc="q_j*", labels=names,
                                           **({} if default is None else {"default": default})))
        self.declare("reference_velocity", dg.Input(shape=(self.size,), default=np.zeros(self.size), doc="v_j*"))
        self.declare("reference_acceleration", dg.Input(shape=(self.size,), default=np.zeros(self.size),
                                                        doc="a_j*"))

    def check(self) -> list[str]:
        """The plugged robot model must be the size of ``model``."""
        model = plugged_model(self.robot)
        if model is not None and model.nv != self.nv:
            return [f"its model has nv = {self.nv} but the plugged robot has nv = {model.nv}"]
        return []

    def _named_configuration(self, model: object) -> np.ndarray | None:
        if not self.reference_configuration:
            return None
        try:
            q = model.referenceConfigurations[self.reference_configuration]
        except Exception:
            raise dg.ParamError(f"{self.name}: the model has no configuration {self.reference_configuration!r}",
                                entity=self.name) from None
        return np.asarray(q)[self.q_index].copy()

    def evaluate(self, state: RobotState, t: int) -> FeatureValue:
        """Posture error; the Jacobian (a selection) and the drift (0) are constants."""
        return FeatureValue(state.q[self.q_index] - self.reference(t),
                            state.v[self.v_index] - self.reference_velocity(t),
                            self._selection, self._zeros, self.reference_acceleration(t))
