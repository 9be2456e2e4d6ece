"""The actuator chain between the controller's joint torque and the motor current (thesis Ch. 3).

:class:`ActuatorModel` maps a desired joint torque to the motor current that produces it through
the rigid chain of Eqs. 3.1-3.5 (:mod:`dgraph.entities.actuators.chain`), saturates the current,
and reports what the chain then delivers and what its torque sensor reads.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.entities.actuators.chain import ChainFileError, ChainParameters, load_chain_file


def _n(entity: ActuatorModel) -> tuple[int]:
    return (entity.size,)


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

    * desired current: ``i_m* = (tau_j* + I_m q_ddot + tau_fm(q_dot)) / (R K_m)``,
    * commanded current: ``i_m = clip(i_m*, -i_max, i_max)``, ``saturated = |i_m*| > i_max``,
    * delivered joint torque: ``tau_j = R K_m i_m - I_m q_ddot - tau_fm(q_dot)`` (equal to
      ``tau_j*`` unless saturated),
    * sensor reading (Eq. 3.4, ``tau_j = K_j tau_js``): ``tau_js = tau_j / K_j``.

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
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(self, name: str, *, joints: Sequence[str], path: str, smoothing: float | None = None) -> None: ...

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
        self.declare("q_ddot", dg.Input(shape=(self.size,), default=np.zeros(self.size),
                                        doc="joint acceleration (estimated), rad/s²; default zeros"))

    def motor_friction(self, q_dot: np.ndarray) -> np.ndarray:
        """``tau_fm = F_vm q_dot + F_sm sign(q_dot) + off_m`` (Eq. 3.2), ``sign`` as configured."""
        sign = np.sign(q_dot) if self.smoothing is None else np.tanh(self.smoothing * q_dot)
        return self._F_vm * q_dot + self._F_sm * sign + self._off_m

    def _losses(self, t: int) -> np.ndarray:
        """``I_m q_ddot + tau_fm(q_dot)``: what the rotor side takes of the motor torque."""
        return self._I_m * self.q_ddot(t) + self.motor_friction(self.q_dot(t))

    @dg.output(shape=_n, depends=("tau_desired", "q_dot", "q_ddot"))
    def current_desired(self, t: int) -> np.ndarray:
        """``i_m* = (tau_j* + I_m q_ddot + tau_fm) / (R K_m)``, A (before saturation)."""
        return (self.tau_desired(t) + self._losses(t)) / self._R_Km

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
        """``tau_j = R K_m i_m - I_m q_ddot - tau_fm``: the torque the chain delivers to the joint, N m."""
        return self.motor_torque(t) - self._losses(t)

    @dg.output(shape=_n, depends=("joint_torque",))
    def sensor_torque(self, t: int) -> np.ndarray:
        """``tau_js = tau_j / K_j`` (Eq. 3.4): the joint torque sensor's reading, N m."""
        return self.joint_torque(t) / self._K_j
