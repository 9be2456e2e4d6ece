"""ConfigurationIntegrator: a QP's velocity or acceleration turned into joint position commands."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import numpy as np

import dgraph as dg
from dgraph.signals.value_types import value_type

Integrate = Callable[[np.ndarray, np.ndarray], np.ndarray]


@value_type
class NextState(NamedTuple):
    """The configuration and velocity one tick later."""

    q: np.ndarray
    v: np.ndarray


def integration_step(integrate: Integrate, q: np.ndarray, v: np.ndarray, u: np.ndarray, dt: float,
                     mode: str) -> NextState:
    """One tick: ``(q ⊕ dt v_next, v_next)`` with ``v_next = u`` (``mode`` ``velocity``) or
    ``v + dt u`` (``acceleration``, semi-implicit Euler); ``⊕`` is ``integrate(q, dq)``."""
    v_next = u if mode == "velocity" else v + dt * u
    return NextState(integrate(q, dt * v_next), v_next)


@dg.register
class ConfigurationIntegrator(dg.Entity):
    """The position-scheme integrator (thesis Ch. 4.4.1.c, Fig. 4.2): one integration of the IK
    velocity, two of the inverse-dynamics acceleration, on the configuration manifold.

    ``control_mode`` ``velocity`` (IK): ``v⁺ = u``; ``acceleration`` (TSID position):
    ``v⁺ = v + dt u``; both then ``q⁺ = pinocchio.integrate(q, dt v⁺)``, the free-flyer base
    included (it moves on SE(3) with the body twist ``v[:6]``). The integrated ``(q, v)`` are
    outputs so that the graph feeds them back to the QP's robot model instead of the measured
    state, "to avoid instabilities" (Ch. 4.4.1.c); the measured state only starts the
    integration (tick 0) and re-synchronises it every ``sync_period`` ticks or whenever
    ``sync`` is true. The device receives ``joint_position`` = the actuated part of ``q⁺``, the
    position to reach at the end of the tick, and ``joint_velocity`` = that of ``v⁺``
    (``MujocoDevice`` in position mode: ``control`` and ``velocity_reference``).

    Parameters: ``model`` (robot name or ``pinocchio.Model``), ``control_mode`` (``velocity`` |
    ``acceleration``), ``sync_period`` (ticks between re-synchronisations, 0 = only at tick 0),
    ``dt`` (default: the graph's).
    Inputs: ``command`` (nv: velocity or acceleration), ``measured_q`` (nq), ``measured_v`` (nv),
    ``sync`` (bool, default false).
    States: ``integrated_q``, ``integrated_v`` (the integration, one tick behind ``q⁺``, ``v⁺``).
    Outputs: ``q``, ``v`` (the state the QP sees at ``t``: integrated, or measured when
    synchronising), ``next_q``, ``next_v`` (``q⁺``, ``v⁺``), ``joint_position`` (nq without the free flyer),
    ``joint_velocity`` (nv without the free flyer).
    """

    has_state = True

    model = dg.Param("talos", kind="name_or_path", doc="robot name, URDF path or pinocchio.Model")
    control_mode = dg.Param("velocity", kind="str", choices=("velocity", "acceleration"),
                            doc="velocity: integrate once (IK); acceleration: twice (TSID position)")
    sync_period = dg.Param(0, kind="int", minimum=0, doc="re-synchronise every N ticks (0: only at tick 0)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, model: str | Any = "talos",
            control_mode: Literal["velocity", "acceleration"] = "velocity", sync_period: int = 0,
            dt: float | None = None,
        ) -> None: ...

    command = dg.Input(shape=("nv",), doc="the QP's velocity or acceleration")
    measured_q = dg.Input(shape=("nq",), doc="measured (estimated) configuration")
    measured_v = dg.Input(shape=("nv",), doc="measured (estimated) velocity")
    sync = dg.Input(shape=(), dtype="bool", default=False, doc="re-synchronise to the measured state at t")

    integrated_q = dg.State(shape=("nq",), doc="integrated configuration")
    integrated_v = dg.State(shape=("nv",), doc="integrated velocity")

    def configure(self) -> None:
        """Load the model (Pinocchio only here: the discrete family imports the core only)."""
        import pinocchio as pin

        from dgraph.entities.robot.loading import has_free_flyer, load_model

        self.pin_model = load_model(self.model, self.name)
        self.nq, self.nv = self.pin_model.nq, self.pin_model.nv
        self._base_q, self._base_v = (7, 6) if has_free_flyer(self.pin_model) else (0, 0)
        self.nqa, self.na = self.nq - self._base_q, self.nv - self._base_v
        self._neutral = pin.neutral(self.pin_model)
        self._integrate = lambda q, dq: pin.integrate(self.pin_model, q, dq)

    def reset(self) -> None:
        """Placeholders: tick 0 always takes the measured state."""
        self.integrated_q.set(self._neutral, 0)
        self.integrated_v.set(np.zeros(self.nv), 0)

    def _synchronising(self, t: int) -> bool:
        return t == 0 or (self.sync_period > 0 and t % self.sync_period == 0) or bool(self.sync(t))

    @dg.output(shape=("nq",), depends=("integrated_q", "measured_q", "sync", "t"), on_demand=("measured_q",))
    def q(self, t: int) -> np.ndarray:
        """The configuration the QP uses at ``t``."""
        return self.measured_q(t) if self._synchronising(t) else self.integrated_q(t)

    @dg.output(shape=("nv",), depends=("integrated_v", "measured_v", "sync", "t"), on_demand=("measured_v",))
    def v(self, t: int) -> np.ndarray:
        """The velocity the QP uses at ``t``."""
        return self.measured_v(t) if self._synchronising(t) else self.integrated_v(t)

    @dg.output(dtype=NextState, depends=("q", "v", "command"))
    def next_state(self, t: int) -> NextState:
        """``(q⁺, v⁺)``: one tick of integration of ``command(t)``."""
        return integration_step(self._integrate, self.q(t), self.v(t), self.command(t), self.dt,
                                self.control_mode)

    @dg.output(shape=("nq",), depends=("next_state",))
    def next_q(self, t: int) -> np.ndarray:
        """``q⁺``."""
        return self.next_state(t).q

    @dg.output(shape=("nv",), depends=("next_state",))
    def next_v(self, t: int) -> np.ndarray:
        """``v⁺``."""
        return self.next_state(t).v

    @dg.output(shape=("nqa",), depends=("next_state",))
    def joint_position(self, t: int) -> np.ndarray:
        """Actuated part of ``q⁺``: the joint position command."""
        return self.next_state(t).q[self._base_q:]

    @dg.output(shape=("na",), depends=("next_state",))
    def joint_velocity(self, t: int) -> np.ndarray:
        """Actuated part of ``v⁺``: the joint velocity reference."""
        return self.next_state(t).v[self._base_v:]

    def prepare_state(self, t: int) -> None:
        """Stage ``q⁺``, ``v⁺``."""
        q_next, v_next = self.next_state(t)
        self.integrated_q.stage(q_next)
        self.integrated_v.stage(v_next)

    def commit_state(self, t_next: int) -> None:
        """Publish them at ``t + 1``."""
        self.integrated_q.commit(t_next)
        self.integrated_v.commit(t_next)
