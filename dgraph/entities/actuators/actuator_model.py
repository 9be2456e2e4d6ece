"""The actuator chain between the controller's joint torque and the motor current (thesis Ch. 3).

:class:`ActuatorModel` maps a desired joint torque to the motor current that produces it through
the rigid chain of Eqs. 3.1-3.5 (:mod:`dgraph.entities.actuators.chain`), saturates the current,
and reports what the chain then delivers and what its torque sensor reads.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.actuators.chain import (
    ChainFileError,
    ChainParameters,
    desired_current,
    friction,
    load_chain_file,
)
from dgraph.entities.actuators.thermal_model import _n


@dg.register
class ActuatorModel(dg.Entity):
    """Motor currents for desired joint torques, through TALOS-like rigid actuator chains.

    One chain per joint of ``joints`` (names of the robot's joints), its parameters read from
    ``path`` (:func:`~dgraph.entities.actuators.chain.load_chain_file`, e.g.
    ``graphs/data/talos_actuators.yaml``); every vector is in the order of ``joints``.

    The chain (thesis Eqs. 3.1-3.4): the motor torque ``tau_m = R K_m i_m`` (3.3) drives the
    rotor (``I_m q_ddot``) and the motor-side friction
    ``tau_fm = F_vm q_dot + F_sm sign(q_dot) + off_m`` (3.2), the rest reaches the joint side,
    which Eq. 3.1 writes ``tau_j = I_j q_ddot + g (M_Y sin q + M_X cos q) + tau_fj``: the link's
    inertia, gravity and joint-side friction are the rigid-body model's (the whole-body
    controller's ``tau_j*`` includes them; in MuJoCo the joint-side friction is the joint's, see
    :func:`~dgraph.entities.actuators.chain.mujoco_joint`). Subtracting the two lines of Eq. 3.1:
    ``tau_m - tau_j = I_m q_ddot + tau_fm``, so

    * desired current: ``i_m* = (tau_j* + (I_m - a_c) q_ddot + tau_fm(q_dot)) / (R K_m)``,
    * commanded current: ``i_m = clip(i_m*, -i_max, i_max)``, ``saturated = |i_m*| > i_max``,
    * delivered joint torque: ``tau_j = R K_m i_m - I_m q_ddot - tau_fm(q_dot)`` (equal to
      ``tau_j*`` unless saturated),
    * sensor reading (Eq. 3.4, ``tau_j = K_j tau_js``): ``tau_js = tau_j / K_j``.

    Two corrections for the plant and the controller at hand:

    * ``controller_armature`` (``a_c``, kg m², scalar or one per joint; default 0): the rotor inertia
      the controller's rigid-body model already has at the joint. Pinocchio's rnea includes the
      model's armature (TALOS's URDF: 0.1), so a whole-body controller's ``tau_j*`` already contains
      ``a_c q_ddot``; the chain compensates only ``(I_m - a_c) q_ddot`` then, else it counts
      ``a_c q_ddot`` twice. TALOS driven by Pinocchio's model: 0.1.
    * ``compensate_offsets`` (default true): ``off_m`` is compensated, as the real chain needs. MuJoCo's
      twin of the chain (:func:`~dgraph.entities.actuators.chain.mujoco_joint`) has no offset
      torque, so driving it through this model with the offset compensated adds a constant
      ``off_m`` (0.86 N m on TALOS's elbow): set false there (``tau_fm`` then has no ``off_m``, in
      the current and in the delivered torque alike).

    ``joint_torque`` is what the chain delivers to the link, ``R K_m i_m - I_m q_ddot - tau_fm``:
    ``tau_j* - a_c q_ddot`` unsaturated (the link side of ``tau_j*``).

    Eq. 3.5 (the joint's forward dynamics) is this chain closed by the link's dynamics: MuJoCo
    does that part. ``sign`` is ``numpy.sign`` (0 at rest: no dry friction is compensated at
    ``q_dot = 0``), or ``tanh(smoothing q_dot)`` (Eq. 3.18) with ``smoothing`` given. ``q`` does
    not enter: gravity is in ``tau_j*``.

    Inputs: ``tau_desired`` (tau_j*, N m), ``q_dot`` (rad/s), ``q_ddot`` (rad/s², estimated;
    default zeros). Outputs: ``current_desired`` (i_m*, A), ``current`` (i_m, A),
    ``motor_torque`` (tau_m = R K_m i_m, N m), ``joint_torque`` (tau_j, N m), ``sensor_torque``
    (tau_js, N m), ``saturated`` (bool per joint).
    """

    joints = dg.Param(kind="str_list", doc="names of the robot joints driven, each a joint of the file")
    path = dg.Param(kind="path", doc="actuator parameter file (YAML, load_chain_file; in a graph file, relative to "
                    "its folder)")
    smoothing = dg.Param(None, kind="float", minimum=1e-6, doc="tanh(mu q_dot) for sign(q_dot) (Eq. 3.18; the "
                         "thesis's MPC: 1000); default: sign")
    controller_armature = dg.Param(0.0, kind="vector", minimum=0.0, doc="rotor inertia the controller's model has "
                                   "at each joint, kg m² (Pinocchio's armature: in tau_j* already); I_m minus it is "
                                   "compensated. Scalar or one per joint")
    compensate_offsets = dg.Param(True, kind="bool", doc="compensate off_m (a real chain); false for MuJoCo's twin, "
                                  "which has no offset torque")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, joints: Sequence[str], path: str, smoothing: float | None = None,
            controller_armature: ArrayLike = 0.0, compensate_offsets: bool = True,
        ) -> None: ...

    tau_desired = dg.Input(shape=_n, doc="desired joint torque tau_j*, N m")
    q_dot = dg.Input(shape=_n, doc="joint velocity, rad/s")
    # declared per instance (its zero default is sized by joints): q_ddot (n), the estimated
    # joint acceleration, rad/s²

    def configure(self) -> None:
        """Read the file; gather each joint's parameters into vectors."""
        if not self.joints:
            raise dg.ParamError(f"{self.name}: parameter 'joints': at least one joint", entity=self.name)
        if len(set(self.joints)) != len(self.joints):
            raise dg.ParamError(f"{self.name}: parameter 'joints': a joint is named twice", entity=self.name)
        try:
            chains = load_chain_file(self.path)
        except ChainFileError as exc:
            raise dg.ParamError(f"{self.name}: parameter 'path': {exc}", entity=self.name) from None
        missing = [j for j in self.joints if j not in chains]
        if missing:
            raise dg.ParamError(f"{self.name}: parameter 'joints': {missing} not in {self.path} (it has "
                                f"{sorted(chains)})", entity=self.name)
        self.chains: list[ChainParameters] = [chains[j] for j in self.joints]
        self.size = len(self.joints)
        for name in ChainParameters.names():
            setattr(self, f"_{name}", np.array([getattr(c, name) for c in self.chains]))
        armature = np.asarray(self.controller_armature, dtype=float)
        if armature.shape not in ((), (1,), (self.size,)):
            raise dg.ParamError(f"{self.name}: parameter 'controller_armature' must be a scalar or {self.size} "
                                f"values, got shape {armature.shape}", entity=self.name)
        self._armature = np.broadcast_to(armature.reshape(-1) if armature.ndim else armature, (self.size,)).copy()
        self._offset = self._off_m if self.compensate_offsets else np.zeros(self.size)
        self.declare("q_ddot", dg.Input(shape=(self.size,), default=np.zeros(self.size),
                                        doc="joint acceleration (estimated), rad/s²; default zeros"))

    def motor_friction(self, q_dot: np.ndarray) -> np.ndarray:
        """``tau_fm = F_vm q_dot + F_sm sign(q_dot) + off_m`` (Eq. 3.2,
        :func:`~dgraph.entities.actuators.chain.friction`), ``sign`` as configured; without ``off_m`` if
        ``compensate_offsets`` is false."""
        return friction(self._F_vm, self._F_sm, self._offset, q_dot, self.smoothing)

    def _losses(self, t: int) -> np.ndarray:
        """``I_m q_ddot + tau_fm(q_dot)``: what the rotor side takes of the motor torque."""
        return self._I_m * self.q_ddot(t) + self.motor_friction(self.q_dot(t))

    @dg.output(shape=_n, depends=("tau_desired", "q_dot", "q_ddot"))
    def current_desired(self, t: int) -> np.ndarray:
        """``i_m* = (tau_j* + (I_m - a_c) q_ddot + tau_fm) / (R K_m)``, A (before saturation; ``a_c`` the
        ``controller_armature``, already in ``tau_j*``; :func:`~dgraph.entities.actuators.chain.desired_current`)."""
        return desired_current(self.chains, self.tau_desired(t), self.q_dot(t), self.q_ddot(t), self.smoothing,
                               self.compensate_offsets, self._armature)

    @dg.output(shape=_n, depends=("current_desired",))
    def current(self, t: int) -> np.ndarray:
        """``i_m = clip(i_m*, -i_max, i_max)``, A."""
        return np.clip(self.current_desired(t), -self._i_max, self._i_max)

    @dg.output(shape=_n, dtype="bool", depends=("current_desired",))
    def saturated(self, t: int) -> np.ndarray:
        """``|i_m*| > i_max`` per joint."""
        return np.abs(self.current_desired(t)) > self._i_max

    @dg.output(shape=_n, depends=("current",))
    def motor_torque(self, t: int) -> np.ndarray:
        """``tau_m = R K_m i_m`` (Eq. 3.3), N m."""
        return self._R_Km * self.current(t)

    @dg.output(shape=_n, depends=("motor_torque", "q_dot", "q_ddot"))
    def joint_torque(self, t: int) -> np.ndarray:
        """``tau_j = R K_m i_m - I_m q_ddot - tau_fm``: the torque the chain delivers to the joint, N m
        (``tau_j* - a_c q_ddot`` unsaturated)."""
        return self.motor_torque(t) - self._losses(t)

    @dg.output(shape=_n, depends=("joint_torque",))
    def sensor_torque(self, t: int) -> np.ndarray:
        """``tau_js = tau_j / K_j`` (Eq. 3.4): the joint torque sensor's reading, N m."""
        return self.joint_torque(t) / self._K_j
