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

import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from dgraph.entities.robot.loading import has_free_flyer
from dgraph.errors import DGraphError, ParamError
from dgraph.signals.value_types import value_type

WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
LOCAL = pin.ReferenceFrame.LOCAL


_OWNERS: dict[int, weakref.ref[RobotState]] = {}
"""For each Pinocchio data (by ``id``), a weak reference to the state whose pass last filled it (a
Python dict: an attribute set on the Pinocchio object costs four times more to write and read).
A data lives at least as long as its states, so an ``id`` is reused only once they are gone."""


class computed_once:
    """A read-only attribute computed by ``method`` at the first read and then stored on the
    instance (``functools.cached_property`` without its per-instance lock, which Python 3.11
    takes at every first read: ~0.7 µs, and a state is new every tick)."""

    def __init__(self, method: Callable[[Any], Any]):
        self.method, self.name, self.__doc__ = method, method.__name__, method.__doc__

    def __get__(self, instance: Any, owner: type | None = None) -> Any:
        if instance is None:
            return self
        value = instance.__dict__[self.name] = self.method(instance)
        return value


@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class FrameKinematics:
    """One frame of one :class:`RobotState` in one convention (``WORLD`` or ``LOCAL``).

    ``placement`` is the world placement ``oMf`` (4 x 4 homogeneous), ``rotation`` ``R`` and
    ``translation`` ``p`` views of it; ``velocity`` the twist ``J v``, ``jacobian`` ``J`` (6 x nv)
    and ``drift`` ``J_dot v`` in that convention (see the module docstring). Every array is this
    tick's own: readers may keep them, and must not write into them.
    """

    placement: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    velocity: np.ndarray
    jacobian: np.ndarray
    drift: np.ndarray


@dataclass(slots=True)  # not frozen: a frozen dataclass costs 15x more to build; treat it as immutable
class CenterOfMassKinematics:
    """The centre of mass of one :class:`RobotState`: ``position`` ``c`` (world), ``velocity``
    ``c_dot = J_com v``, ``jacobian`` ``J_com`` (3 x nv) and ``drift`` ``J_com_dot v`` (the CoM
    acceleration at ``a = 0``). Arrays of this tick, like :class:`FrameKinematics`'s."""

    position: np.ndarray
    velocity: np.ndarray
    jacobian: np.ndarray
    drift: np.ndarray


class DataFields:
    """Read-only numpy views of the fields of one Pinocchio data that :class:`RobotState` reads:
    ``mass_matrix`` (``M`` as its transpose, C-ordered: ``M`` is symmetric to the bit),
    ``bias_forces`` (``nle``), ``com_velocity`` and ``com_acceleration`` (``vcom[0]``,
    ``acom[0]``), ``com_jacobian`` (``Jcom``), ``momentum_matrix`` (``Ag``) and
    ``momentum_matrix_rate`` (``dAg``).

    Every pass on the data refills the same memory, so the views are made once per data (each
    eigenpy access costs about a microsecond) and the states of its successive passes share
    them; each view keeps the data alive.
    """

    __slots__ = ("bias_forces", "com_acceleration", "com_jacobian", "com_velocity", "data", "mass_matrix",
                 "momentum_matrix", "momentum_matrix_rate")

    def __init__(self, data: pin.Data):
        self.data = data
        self.mass_matrix = _read_only(data.M.T)
        self.bias_forces = _read_only(data.nle)
        self.com_velocity, self.com_acceleration = _read_only(data.vcom[0]), _read_only(data.acom[0])
        self.com_jacobian = _read_only(data.Jcom)
        self.momentum_matrix, self.momentum_matrix_rate = _read_only(data.Ag), _read_only(data.dAg)


@value_type
class RobotState:
    """Kinematics and dynamics of ``model`` at ``(q, v)``, computed once.

    The constructor runs ``computeAllTerms`` (mass matrix, nonlinear effects, joint Jacobians,
    CoM and its Jacobian, centroidal momentum matrix and its time derivative ``dA_G``). Its
    forward pass leaves in ``data.a`` the body accelerations at ``a = 0``, so frame accelerations
    read from it, and the CoM acceleration computed from it, are the drifts ``J_dot v`` (checked
    by finite differences).
    ``mass_matrix`` and ``bias_forces`` are views of the pass's data, for the readers of the tick
    (the solver copies them into its QP); a read after the data was reused raises, and the
    RobotModel outputs of the same names hand out copies. Every other property is computed from
    that data at its first read and kept (a copy owned by this state, shared by every reader of
    the tick): each is computed at most once per state (the method ``frame_placement`` computes
    at each call). Every array handed out is read-only.

    The pass runs on ``fields.data``: a :class:`DataFields` is made once by the data's owner (a
    :class:`~dgraph.entities.robot.model.RobotModel`) for all its passes.
    """

    def __init__(self, model: pin.Model, fields: DataFields, q: np.ndarray, v: np.ndarray):
        data = fields.data
        self.model, self._pin_data, self._fields, self.q, self.v = model, data, fields, q, v
        self._key = id(data)
        _OWNERS[self._key] = weakref.ref(self)
        pin.computeAllTerms(model, data, q, v)  # also leaves data.a = the accelerations at a = 0
        self._frames: dict[tuple[int, pin.ReferenceFrame], FrameKinematics] = {}

    @property
    def mass_matrix(self) -> np.ndarray:
        """``M(q)`` (nv x nv, symmetric): a view of the pass's data, valid while it is this state's
        (copy it to keep it past the tick; a read after the data was reused raises)."""
        return self.fields.mass_matrix

    @property
    def bias_forces(self) -> np.ndarray:
        """``h = C(q, v) v + g(q)`` (nv): a view of the pass's data, like :attr:`mass_matrix`."""
        return self.fields.bias_forces

    @property
    def data(self) -> pin.Data:
        """The Pinocchio data of this pass. It is shared: a later pass on another ``(q, v)``
        overwrites it, after which computing anything more from this state raises instead of
        answering for the other state (values already computed are this state's and stay valid)."""
        if _OWNERS[self._key]() is not self:
            self._check_not_reused()
        return self._pin_data

    @property
    def fields(self) -> DataFields:
        """The views of the data's fields (valid while the data is this state's, like :attr:`mass_matrix`),
        with the ownership check of :attr:`data`."""
        if _OWNERS[self._key]() is not self:
            self._check_not_reused()
        return self._fields

    def _check_not_reused(self) -> None:
        """For a state whose data a later pass filled: raise unless that pass was at the same ``(q, v)``."""
        owner = _OWNERS[self._key]()
        if owner is None or not (np.array_equal(owner.q, self.q) and np.array_equal(owner.v, self.v)):
            raise DGraphError("a RobotState was read after its Pinocchio data was reused for another (q, v): "
                              "keep the values you need (e.g. com.position), not the state")

    # -- whole body -------------------------------------------------------------------------
    @computed_once
    def inverse_mass_matrix(self) -> np.ndarray:
        """``M(q)^-1`` from Pinocchio's sparse Cholesky factorisation of ``M`` (about 30 µs for
        TALOS, a quarter of a dense inverse; it writes only the factorisation fields of the data)."""
        data = self.data
        pin.cholesky.decompose(self.model, data)
        return _read_only(pin.cholesky.computeMinv(self.model, data).copy())

    @property
    def total_mass(self) -> float:
        """Total mass in kg."""
        return float(self.data.mass[0])

    @computed_once
    def com(self) -> CenterOfMassKinematics:
        """Position, velocity, Jacobian and drift of the centre of mass (the drift from
        ``centerOfMass`` at the acceleration level on the pass's accelerations at ``a = 0``)."""
        fields = self.fields
        position = pin.centerOfMass(self.model, fields.data, pin.KinematicLevel.ACCELERATION, False)  # a copy
        return CenterOfMassKinematics(_read_only(position), _read_only(fields.com_velocity.copy()),
                                      _read_only(fields.com_jacobian.copy()),
                                      _read_only(fields.com_acceleration.copy()))

    @computed_once
    def centroidal_momentum_matrix(self) -> np.ndarray:
        """``A_G`` (6 x nv): ``h_G = [l, k] = A_G v`` at the CoM, world axes."""
        return _read_only(self.fields.momentum_matrix.copy())

    @computed_once
    def centroidal_momentum(self) -> np.ndarray:
        """``h_G = [l, k]`` (linear, angular) at the CoM."""
        return _read_only(self.fields.momentum_matrix @ self.v)

    @computed_once
    def centroidal_drift(self) -> np.ndarray:
        """``A_G_dot v``: the momentum rate at ``a = 0`` (``h_G_dot = A_G a + A_G_dot v``), with
        the pass's ``dA_G``."""
        return _read_only(self.fields.momentum_matrix_rate @ self.v)

    @computed_once
    def coriolis_matrix(self) -> np.ndarray:
        """``C(q, v)`` (nv x nv) with ``C v + g = h`` and ``M_dot = C + C^T`` (Pinocchio's
        ``computeCoriolisMatrix``). That call rewrites the data's ``A_G`` in a convention of its
        own, so the momentum quantities read from it are computed first."""
        _ = self.centroidal_momentum_matrix, self.centroidal_momentum
        return _read_only(pin.computeCoriolisMatrix(self.model, self.data, self.q, self.v).copy())

    # -- frames -----------------------------------------------------------------------------
    def frame_id(self, name: str) -> int:
        """The Pinocchio id of frame ``name`` (KeyError if unknown)."""
        if not self.model.existFrame(name):
            raise KeyError(name)
        return self.model.getFrameId(name)

    def frame(self, frame: int, ref: pin.ReferenceFrame = WORLD) -> FrameKinematics:
        """Placement, velocity, Jacobian and drift of a frame in the convention ``ref``: one
        Pinocchio call each, at the first request for ``(frame, ref)``, then kept. (Frame
        placements are computed one frame at a time, only for the frames asked about; the
        Jacobian, velocity and accelerations come from the joints' quantities.)"""
        kinematics = self._frames.get((frame, ref))
        if kinematics is None:
            model, data = self.model, self.data
            placement = _read_only(pin.updateFramePlacement(model, data, frame).homogeneous)  # a fresh array
            if ref == WORLD:
                drift = pin.getFrameClassicalAcceleration(model, data, frame, WORLD).vector
            else:
                drift = pin.getFrameAcceleration(model, data, frame, ref).vector
            kinematics = self._frames[frame, ref] = FrameKinematics(
                placement, placement[:3, :3], placement[:3, 3],
                _read_only(pin.getFrameVelocity(model, data, frame, ref).vector),
                _read_only(pin.getFrameJacobian(model, data, frame, ref)), _read_only(drift))
        return kinematics

    def frame_placement(self, frame: int) -> pin.SE3:
        """World placement ``oMf`` of a frame (a copy)."""
        return pin.updateFramePlacement(self.model, self.data, frame)

    def frame_velocity(self, frame: int, ref: pin.ReferenceFrame = WORLD) -> np.ndarray:
        """Frame twist ``[linear, angular]`` (``WORLD``: ``[p_dot, omega]``; ``LOCAL``: body twist)."""
        return self.frame(frame, ref).velocity

    def frame_jacobian(self, frame: int, ref: pin.ReferenceFrame = WORLD) -> np.ndarray:
        """Frame Jacobian (6 x nv) in the convention ``ref``."""
        return self.frame(frame, ref).jacobian

    def frame_drift(self, frame: int, ref: pin.ReferenceFrame = WORLD) -> np.ndarray:
        """``J_dot v``: classical acceleration (``WORLD``) or spatial acceleration (``LOCAL``) at a = 0."""
        return self.frame(frame, ref).drift


def _read_only(array: np.ndarray) -> np.ndarray:
    """``array``, made read-only: it is shared by every reader of the tick (or is a view of
    Pinocchio's data), and a reader writing into it would change what the others read."""
    array.setflags(write=False)  # a method call: half the cost of setting flags.writeable
    return array


def unactuated_dofs(model: pin.Model) -> int:
    """Velocities of the unactuated base: 6 for a free flyer as first joint, else 0."""
    return 6 if has_free_flyer(model) else 0


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
