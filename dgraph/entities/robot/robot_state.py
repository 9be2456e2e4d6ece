"""RobotState: one Pinocchio pass at (q, v) that every reader of the robot model shares.

Frame conventions used throughout dgraph's robot entities:

- ``world`` quantities ("local world aligned", Pinocchio's ``LOCAL_WORLD_ALIGNED``) sit at the
  frame origin with world-aligned axes: velocity ``[p_dot, omega]``, Jacobian ``J`` with
  ``[p_dot, omega] = J v``, drift ``[p_ddot, omega_dot]`` at ``a = 0`` (the classical
  acceleration, so ``[p_ddot, omega_dot] = J a + drift``).
- ``local`` quantities (Pinocchio's ``LOCAL``) are the body twist ``V = J_local v`` and its
  time derivative ``V_dot = J_local a + drift_local``, the spatial acceleration at ``a = 0``.
  Contact forces are expressed in the local frame, so contacts use these.
"""

from __future__ import annotations

import functools
import weakref
from typing import Any

import numpy as np
import pinocchio as pin

from dgraph.errors import DGraphError, ParamError

WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
LOCAL = pin.ReferenceFrame.LOCAL


_OWNERS: weakref.WeakValueDictionary[int, RobotState] = weakref.WeakValueDictionary()
"""The state whose pass last filled each Pinocchio data (by ``id``; a live entry keeps its data
alive, so an ``id`` is never reused while it is listed)."""


class RobotState:
    """Kinematics and dynamics of ``model`` at ``(q, v)``, computed once.

    The constructor runs ``computeAllTerms`` (mass matrix, nonlinear effects, joint Jacobians,
    CoM and its Jacobian, centroidal momentum matrix). Its forward pass leaves in ``data.a`` the
    body accelerations at ``a = 0``, so frame accelerations read from it, and the CoM
    acceleration computed from it, are the drifts ``J_dot v`` (checked by finite differences).
    Frame quantities are computed on request from that data (a few µs each).
    """

    def __init__(self, model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray):
        self.model, self._pin_data, self.q, self.v = model, data, q, v
        _OWNERS[id(data)] = self
        pin.computeAllTerms(model, data, q, v)  # also leaves data.a = the accelerations at a = 0
        pin.updateFramePlacements(model, data)
        pin.centerOfMass(model, data, pin.KinematicLevel.ACCELERATION, False)
        self.mass_matrix = data.M.copy()  # Pinocchio 4 fills both triangles (checked by a test)
        self.bias_forces = data.nle.copy()
        self._centroidal_drift: np.ndarray | None = None

    @property
    def data(self) -> pin.Data:
        """The Pinocchio data of this pass. It is shared: a later pass on another ``(q, v)``
        overwrites it, after which reading this state raises instead of answering for the
        other state (values already read are copies and stay valid)."""
        data = self._pin_data
        owner = _OWNERS.get(id(data))
        if owner is not self and owner is not None and not (
                np.array_equal(owner.q, self.q) and np.array_equal(owner.v, self.v)):
            raise DGraphError("a RobotState was read after its Pinocchio data was reused for another (q, v): "
                              "keep copies of the values (e.g. com_position), not the state")
        return data

    # -- whole body -------------------------------------------------------------------------
    @property
    def inverse_mass_matrix(self) -> np.ndarray:
        """``M(q)^-1`` from Pinocchio's sparse Cholesky factorisation of ``M`` (about 30 µs for
        TALOS, a quarter of a dense inverse; it writes only the factorisation fields of the data)."""
        data = self.data
        pin.cholesky.decompose(self.model, data)
        return pin.cholesky.computeMinv(self.model, data).copy()

    @property
    def total_mass(self) -> float:
        """Total mass in kg."""
        return float(self.data.mass[0])

    @property
    def com_position(self) -> np.ndarray:
        """Centre of mass ``c`` in the world frame."""
        return self.data.com[0].copy()

    @property
    def com_velocity(self) -> np.ndarray:
        """``c_dot = J_com v``."""
        return self.data.vcom[0].copy()

    @property
    def com_jacobian(self) -> np.ndarray:
        """``J_com`` (3 x nv)."""
        return self.data.Jcom.copy()

    @property
    def com_drift(self) -> np.ndarray:
        """``J_com_dot v``: the CoM acceleration at ``a = 0``."""
        return self.data.acom[0].copy()

    @property
    def centroidal_momentum_matrix(self) -> np.ndarray:
        """``A_G`` (6 x nv): ``h_G = [l, k] = A_G v`` at the CoM, world axes."""
        return self.data.Ag.copy()

    @property
    def centroidal_momentum(self) -> np.ndarray:
        """``h_G = [l, k]`` (linear, angular) at the CoM."""
        return self.data.Ag @ self.v

    @property
    def centroidal_drift(self) -> np.ndarray:
        """``A_G_dot v``: the momentum rate at ``a = 0`` (computed on first request)."""
        if self._centroidal_drift is None:
            model, data = self.model, self.data
            dhg = pin.computeCentroidalMomentumTimeVariation(model, data, self.q, self.v, np.zeros(model.nv))
            self._centroidal_drift = np.concatenate([dhg.linear, dhg.angular])
        return self._centroidal_drift

    def gravity_torque(self) -> np.ndarray:
        """``g(q)``, the generalized gravity (used by fallbacks; computed on request)."""
        return pin.computeGeneralizedGravity(self.model, self.model.createData(), self.q).copy()

    # -- frames -----------------------------------------------------------------------------
    def frame_id(self, name: str) -> int:
        """The Pinocchio id of frame ``name`` (KeyError if unknown)."""
        if not self.model.existFrame(name):
            raise KeyError(name)
        return self.model.getFrameId(name)

    def frame_placement(self, frame: int) -> pin.SE3:
        """World placement ``oMf`` of a frame (a copy)."""
        return pin.SE3(self.data.oMf[frame])

    def frame_velocity(self, frame: int, ref: pin.ReferenceFrame = WORLD) -> np.ndarray:
        """Frame twist ``[linear, angular]`` (``WORLD``: ``[p_dot, omega]``; ``LOCAL``: body twist)."""
        return pin.getFrameVelocity(self.model, self.data, frame, ref).vector

    def frame_jacobian(self, frame: int, ref: pin.ReferenceFrame = WORLD) -> np.ndarray:
        """Frame Jacobian (6 x nv) in the convention ``ref``."""
        return pin.getFrameJacobian(self.model, self.data, frame, ref)

    def frame_drift(self, frame: int, ref: pin.ReferenceFrame = WORLD) -> np.ndarray:
        """``J_dot v``: classical acceleration (``WORLD``) or spatial acceleration (``LOCAL``) at a = 0."""
        if ref == WORLD:
            return pin.getFrameClassicalAcceleration(self.model, self.data, frame, WORLD).vector
        return pin.getFrameAcceleration(self.model, self.data, frame, ref).vector


def unactuated_dofs(model: pin.Model) -> int:
    """Velocities of the unactuated base: 6 for a free flyer as first joint, else 0."""
    return 6 if model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer" else 0


def plugged_model(robot_input: Any) -> pin.Model | None:
    """The Pinocchio model of the RobotModel whose ``state`` feeds ``robot_input`` (or None)."""
    source = robot_input.source
    return getattr(source.entity, "pin_model", None) if source is not None else None


def frame_problems(robot_input: Any, frames: list[str]) -> list[str]:
    """Problems for a graph's validation: frames missing from the plugged robot's model."""
    model = plugged_model(robot_input)
    if model is None:
        return []
    return [f"the robot model plugged into {robot_input.full_name} has no frame {f!r}" for f in frames
            if not model.existFrame(f)]


class FrameReader:
    """Mixin for entities with a ``frame`` parameter and a ``robot`` input (a RobotModel's state).

    ``frame_index(state)`` is the frame's id in the state's model, looked up once per model
    (a clear ``ParamError`` naming the entity if the model lacks it); ``check`` reports a
    missing frame when the graph is validated, before anything runs.
    """

    def check(self) -> list[str]:
        """The frame must exist in the plugged robot model."""
        return frame_problems(self.robot, [self.frame])

    def frame_index(self, state: RobotState) -> int:
        """The id of ``self.frame`` in ``state.model``."""
        cached = getattr(self, "_frame_cache", None)
        if cached is not None and cached[0] is state.model:
            return cached[1]
        try:
            index = state.frame_id(self.frame)
        except KeyError:
            raise ParamError(f"{self.name}: the robot model has no frame {self.frame!r}", entity=self.name) from None
        self._frame_cache = (state.model, index)
        return index


def homogeneous(placement: pin.SE3) -> np.ndarray:
    """The 4 x 4 homogeneous matrix of a placement."""
    return placement.homogeneous.copy()


def load_model(model: Any, entity: str | None = None) -> pin.Model:
    """A Pinocchio model from an example-robot-data name (e.g. ``talos``) or a ``pin.Model``.

    Models loaded by name are cached per process (loading TALOS takes ~0.8 s) and shared:
    entities must not modify them. A bad value raises :class:`ParamError` naming ``entity``.
    """
    if isinstance(model, pin.Model):
        return model
    prefix = f"{entity}: " if entity else ""
    if not isinstance(model, str):
        raise ParamError(f"{prefix}model must be a robot name or a pinocchio.Model, got {type(model).__name__}",
                         entity=entity)
    try:
        return _load_named(model)
    except Exception as exc:  # example-robot-data raises plain exceptions for unknown names
        raise ParamError(f"{prefix}cannot load robot model {model!r}: {exc}", entity=entity) from None


@functools.lru_cache(maxsize=8)
def _load_named(name: str) -> pin.Model:
    import example_robot_data as erd

    return erd.load(name).model
