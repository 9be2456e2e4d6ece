"""RobotModel: the Pinocchio model of a robot, evaluated once per tick for every reader."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.entities.robot.loading import load_model
from dgraph.entities.robot.robot_state import DataFields, RobotState


def _frame_outputs(frame: str, frame_id: int) -> dict[str, dg.Output]:
    """The four per-frame outputs of :class:`RobotModel`, read from the shared ``state``."""

    def placement(self: RobotModel, t: int) -> np.ndarray:
        return self.state(t).frame(frame_id).placement

    def velocity(self: RobotModel, t: int) -> np.ndarray:
        return self.state(t).frame(frame_id).velocity

    def jacobian(self: RobotModel, t: int) -> np.ndarray:
        return self.state(t).frame(frame_id).jacobian

    def drift(self: RobotModel, t: int) -> np.ndarray:
        return self.state(t).frame(frame_id).drift

    nv = ("nv",)
    return {
        f"{frame}_placement": dg.Output(placement, shape=(4, 4), depends=("state",),
                                        doc=f"world placement of {frame} (4 x 4 homogeneous)"),
        f"{frame}_velocity": dg.Output(velocity, shape=(6,), depends=("state",),
                                       doc=f"[p_dot, omega] of {frame}, world axes"),
        f"{frame}_jacobian": dg.Output(jacobian, shape=(6, *nv), depends=("state",),
                                       doc=f"Jacobian of {frame}, world axes at the frame origin"),
        f"{frame}_drift": dg.Output(drift, shape=(6,), depends=("state",),
                                    doc=f"J_dot v of {frame}: classical acceleration at a = 0, world axes"),
    }


def with_tool_frames(model: pin.Model, tool_frames: Any, entity: str) -> pin.Model:
    """A copy of ``model`` with operational frames ``{name: {parent: frame, translation: [x, y, z]}}``
    (fixed offsets from an existing frame, same axes), e.g. the tip of a tool held in a hand."""
    if not isinstance(tool_frames, dict):
        raise dg.ParamError(f"{entity}: tool_frames must map names to {{parent, translation}}", entity=entity)
    model = pin.Model(model)
    for name, spec in tool_frames.items():
        if not (isinstance(name, str) and name.isidentifier()) or model.existFrame(name):
            raise dg.ParamError(f"{entity}: tool frame {name!r} must be a new identifier", entity=entity)
        if not isinstance(spec, dict) or set(spec) != {"parent", "translation"}:
            raise dg.ParamError(f"{entity}: tool frame {name!r} needs exactly 'parent' and 'translation'",
                                entity=entity)
        translation = np.asarray(spec["translation"], dtype=float)
        if not model.existFrame(str(spec["parent"])) or translation.shape != (3,) or not np.isfinite(translation).all():
            raise dg.ParamError(f"{entity}: tool frame {name!r}: parent {spec['parent']!r} must be a frame of the "
                                "model and translation 3 finite numbers", entity=entity)
        parent = model.frames[model.getFrameId(str(spec["parent"]))]
        placement = parent.placement * pin.SE3(np.eye(3), translation)
        model.addFrame(pin.Frame(name, parent.parentJoint, model.getFrameId(str(spec["parent"])), placement,
                                 pin.FrameType.OP_FRAME))
    return model


@dg.register
class RobotModel(dg.Entity):
    """Rigid-body model of a robot (Pinocchio): one shared computation per tick.

    Inputs: ``q`` (nq, Pinocchio convention: free-flyer ``[xyz, quaternion xyzw]`` then
    joints; a fixed base: the joints), ``v`` (nv: base linear and angular velocity in the base
    frame, then joints).

    ``state`` runs the Pinocchio pass once per tick (:class:`RobotState`: ``computeAllTerms``,
    which also gives the drifts at ``a = 0``); every other output, and every feature, task
    and contact plugged to ``state``, reads from it. Outputs (thesis Eq. 2.1–2.4, 2.32):

    - ``mass_matrix`` ``M(q)`` (nv x nv), ``bias_forces`` ``h = C(q, v) v + g(q)`` (nv), so
      ``M a + h = S^T tau + J_c^T f``;
    - ``com_position`` ``c``, ``com_velocity`` ``c_dot = J_com v``, ``com_jacobian``
      ``J_com`` (3 x nv), ``com_drift`` ``J_com_dot v``;
    - ``centroidal_momentum_matrix`` ``A_G`` (6 x nv, ``h_G = [l, k] = A_G v``),
      ``centroidal_momentum`` ``h_G``, ``centroidal_drift`` ``A_G_dot v``;
    - for each frame named in ``frames``: ``<frame>_placement`` (4 x 4), ``<frame>_velocity``
      ``[p_dot, omega]``, ``<frame>_jacobian`` and ``<frame>_drift`` ``J_dot v``, all with
      world axes at the frame origin (see :mod:`dgraph.entities.robot.robot_state`).

    Parameters: ``model`` (an example-robot-data name, default ``talos``, e.g. ``panda``,
    ``ur5``; the path of a URDF file, a fixed-base model; or a ``pin.Model``; see
    :mod:`dgraph.entities.robot.loading`),
    ``frames`` (frame names whose kinematics are published), ``tool_frames`` (extra frames at
    fixed offsets, ``{name: {parent: frame, translation: [x, y, z]}}``, e.g. a tool tip; the
    model is then this entity's own copy).
    """

    model = dg.Param("talos", kind="name_or_path", doc="example-robot-data robot name, URDF path or pinocchio.Model")
    frames = dg.Param((), kind="str_list", doc="frames whose placement, velocity, Jacobian and drift are outputs")
    tool_frames = dg.Param(None, kind="object", doc="extra frames: {name: {parent: frame, translation: [x, y, z]}}")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos", frames: Sequence[str] = (), tool_frames: Any = None,
        ) -> None: ...

    q = dg.Input(shape=("nq",), doc="configuration (Pinocchio convention)")
    v = dg.Input(shape=("nv",), doc="generalized velocity (Pinocchio convention)")

    def configure(self) -> None:
        """Load the model and declare the per-frame outputs."""
        self.pin_model = load_model(self.model, self.name)
        if self.tool_frames:
            self.pin_model = with_tool_frames(self.pin_model, self.tool_frames, self.name)
        self.nq, self.nv = self.pin_model.nq, self.pin_model.nv
        self._fields = DataFields(self.pin_model.createData())  # the data of every pass, and its views
        for frame in self.frames:
            if not self.pin_model.existFrame(frame):
                raise dg.ParamError(f"{self.name}: the model has no frame {frame!r}", entity=self.name)
            if not frame.isidentifier():
                raise dg.ParamError(f"{self.name}: frame name {frame!r} cannot name a signal", entity=self.name)
            for name, out in _frame_outputs(frame, self.pin_model.getFrameId(frame)).items():
                self.declare(name, out)

    @dg.output(dtype=RobotState, depends=("q", "v"))
    def state(self, t: int) -> RobotState:
        """The shared Pinocchio pass at ``(q(t), v(t))``."""
        return RobotState(self.pin_model, self._fields, self.q(t), self.v(t))

    @dg.output(shape=("nv", "nv"), depends=("state",))
    def mass_matrix(self, t: int) -> np.ndarray:
        """``M(q)``, symmetric (a copy: the state's is a view of the data that the next pass refills)."""
        return self.state(t).mass_matrix.copy()

    @dg.output(shape=("nv",), depends=("state",))
    def bias_forces(self, t: int) -> np.ndarray:
        """``h = C(q, v) v + g(q)`` (a copy, like ``mass_matrix``)."""
        return self.state(t).bias_forces.copy()

    @dg.output(shape=(3,), depends=("state",), labels=("x", "y", "z"))
    def com_position(self, t: int) -> np.ndarray:
        """CoM position in the world frame."""
        return self.state(t).com.position

    @dg.output(shape=(3,), depends=("state",), labels=("x", "y", "z"))
    def com_velocity(self, t: int) -> np.ndarray:
        """CoM velocity ``J_com v``."""
        return self.state(t).com.velocity

    @dg.output(shape=(3, "nv"), depends=("state",))
    def com_jacobian(self, t: int) -> np.ndarray:
        """``J_com``."""
        return self.state(t).com.jacobian

    @dg.output(shape=(3,), depends=("state",))
    def com_drift(self, t: int) -> np.ndarray:
        """``J_com_dot v``."""
        return self.state(t).com.drift

    @dg.output(shape=(6, "nv"), depends=("state",))
    def centroidal_momentum_matrix(self, t: int) -> np.ndarray:
        """``A_G``."""
        return self.state(t).centroidal_momentum_matrix

    @dg.output(shape=(6,), depends=("state",), labels=("lx", "ly", "lz", "kx", "ky", "kz"))
    def centroidal_momentum(self, t: int) -> np.ndarray:
        """``h_G = A_G v``."""
        return self.state(t).centroidal_momentum

    @dg.output(shape=(6,), depends=("state",))
    def centroidal_drift(self, t: int) -> np.ndarray:
        """``A_G_dot v``."""
        return self.state(t).centroidal_drift
