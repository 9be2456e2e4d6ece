"""KinematicDevice: a perfect robot that integrates a velocity or acceleration command."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.entities.discrete.configuration_integrator import integration_step
from dgraph.params import MAX_SIZE


@dg.register
class KinematicDevice(dg.Device):
    """A kinematic simulator: no dynamics, the command is applied exactly.

    Velocity control: ``v(t+1) = u(t)``, ``q(t+1) = q(t) (+) dt v(t+1)``.
    Acceleration control (semi-implicit Euler): ``v(t+1) = v(t) + dt u(t)``,
    ``q(t+1) = q(t) (+) dt v(t+1)``.
    ``(+)`` is vector addition, or ``pinocchio.integrate`` when a model is given (a free-flyer
    base then integrates on SE(3); ``q`` has ``nq`` entries and ``v``, ``u`` have ``nv``).

    Parameters: ``control`` (``velocity`` | ``acceleration``), ``size`` (without a model),
    ``model`` (example-robot-data name such as ``talos``, or a ``pinocchio.Model``),
    ``q0``, ``v0`` (default: neutral configuration, zero velocity), ``dt`` (default: graph's).
    Inputs: ``control`` (nv). States: ``q`` (nq), ``v`` (nv).
    """

    control_mode = dg.Param("velocity", kind="str", choices=("velocity", "acceleration"),
                         doc="what the control input commands")
    size = dg.Param(None, kind="int", minimum=1, maximum=MAX_SIZE, doc="state size for a vector state (no model)")
    model = dg.Param(None, kind="name_or_path", doc="example-robot-data robot name, URDF path or pinocchio.Model")
    q0 = dg.Param(None, kind="vector", doc="initial configuration (default: neutral / zeros)")
    v0 = dg.Param(None, kind="vector", doc="initial velocity (default: zeros)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, control_mode: Literal["velocity", "acceleration"] = "velocity", size: int | None = None,
            model: str | Any | None = None, q0: ArrayLike | None = None, v0: ArrayLike | None = None,
            dt: float | None = None,
        ) -> None: ...

    control = dg.Input(shape=("nv",), doc="commanded velocity or acceleration")
    q = dg.State(shape=("nq",), doc="configuration")
    v = dg.State(shape=("nv",), doc="velocity")

    def configure(self) -> None:
        """Size the state from the model or from ``size``."""
        if self.model is not None:
            from dgraph.entities.robot.loading import load_model  # Pinocchio only when given a model

            self.pin_model = load_model(self.model, self.name)
            self.nq, self.nv = self.pin_model.nq, self.pin_model.nv
        elif self.size is not None and self.size > 0:
            self.pin_model = None
            self.nq = self.nv = self.size
        else:
            raise dg.ParamError(f"{self.name}: give either a positive size or a model", entity=self.name)

    def reset(self) -> None:
        """Initial configuration and velocity."""
        if self.q0 is not None:
            q0 = self.q0
        elif self.pin_model is not None:
            import pinocchio as pin
            q0 = pin.neutral(self.pin_model)
        else:
            q0 = np.zeros(self.nq)
        self.q.set(q0, 0)
        self.v.set(np.zeros(self.nv) if self.v0 is None else self.v0, 0)

    def _integrate(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        if self.pin_model is None:
            return q + dq
        import pinocchio as pin
        return pin.integrate(self.pin_model, q, dq)

    def prepare_state(self, t: int) -> None:
        """Pull ``control(t)`` and integrate one tick."""
        q_next, v_next = integration_step(self._integrate, self.q(t), self.v(t), self.control(t), self.dt,
                                          self.control_mode)
        self.q.stage(q_next)
        self.v.stage(v_next)

    def commit_state(self, t_next: int) -> None:
        """Stamp ``q`` and ``v`` at ``t + 1``."""
        self.q.commit(t_next)
        self.v.commit(t_next)
