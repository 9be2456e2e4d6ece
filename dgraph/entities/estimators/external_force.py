"""ExternalForce: the force the environment exerts beyond a force/torque sensor, from its reading."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

import dgraph as dg
from dgraph.entities.estimators.sensor_guard import Channel, SensorGuard
from dgraph.entities.robot.robot_state import FrameReader, RobotState


def payload_mass(state: RobotState, frame: int) -> float:
    """Mass carried beyond a sensor frame: the subtree of the frame's parent joint."""
    model = state.model
    joint = model.frames[frame].parentJoint
    return float(sum(model.inertias[j].mass for j in range(joint, model.njoints) if joint in model.supports[j]))


@dg.register
class ExternalForce(FrameReader, dg.Entity):
    """External force on the robot beyond a wrist (or ankle) force/torque sensor, world axes.

    The sensor reads the wrench the child side (hand and what it holds) exerts on the parent side,
    in the sensor frame. Quasi-statically the hand's weight ``m g`` and the external force ``F``
    both go through the sensor, so ``F = R f_s - m g`` (``g`` the gravity vector, ``R`` the
    sensor frame's orientation). The hand's own accelerations are neglected. ``m`` is
    ``payload_mass``, by default the mass of the subtree of the sensor frame's parent joint in
    the plugged model; a reduced model merges the links between that joint and the sensor into
    it (TALOS: 0.31 kg of ``arm_left_7_link``), so give the URDF mass beyond the sensor when it
    matters (TALOS wrist: 1.384 kg). A held tool should be in that mass or massless.

    The reading is checked where it enters (``check_sensors``): a
    :class:`~dgraph.entities.estimators.sensor_guard.SensorGuard` refuses an element that is NaN,
    infinite or outside ``±force_range`` (force) / ``±torque_range`` (torque), replaces it by the
    last trusted value of that element (at the first tick, with none yet: 0 for NaN or an
    infinity, the nearest end of the range for a finite value beyond it), and reports a fault naming
    ``<entity>.wrench[i]``: one bad sample costs one degraded tick, and what reads the force (a
    force task's integral, a contact detector) never sees a non-finite value. An element
    bit-for-bit the same for ``frozen_ticks`` ticks in a row (not 0) is reported frozen and kept
    (there is nothing better), as is a reading whose source state has not been updated for
    ``stale_ticks`` ticks (stale). There is no jump test: a contact that is made or lost is a real
    jump of the reading. The reading is checked at every tick, whether the force is read or not.

    Parameters: ``frame`` (the sensor frame, e.g. ``wrist_left_ft_link``), ``payload_mass`` (kg),
    ``check_sensors``, ``force_range`` (N), ``torque_range`` (N m), ``frozen_ticks``, ``stale_ticks``.
    Inputs: ``robot`` (RobotModel state), ``wrench`` (6, the sensor reading: force then torque,
    raw: it may hold NaN).
    Outputs: ``checked_wrench`` (6, the reading as trusted), ``force`` (3, N, world, from the
    trusted reading), ``payload`` (kg, the compensated mass).
    States: the guard's trusted reading, kept in ``commit_state`` (a failed tick changes nothing).
    """

    has_state = True

    frame = dg.Param(kind="str", doc="the sensor frame")
    payload_mass = dg.Param(None, kind="float", minimum=0.0, optional=True,
                            doc="mass beyond the sensor (kg; default: subtree of the frame's parent joint)")
    check_sensors = dg.Param(True, kind="bool", doc="check the reading and replace a bad element (SensorGuard)")
    force_range = dg.Param(10000.0, kind="float", minimum=0.0, doc="F/T force range (N)")
    torque_range = dg.Param(1000.0, kind="float", minimum=0.0, doc="F/T torque range (N m)")
    frozen_ticks = dg.Param(50, kind="int", minimum=0, doc="identical readings in a row that make the sensor "
                                                             "frozen (0: no test)")
    stale_ticks = dg.Param(20, kind="int", minimum=0, doc="ticks without an update of the sensor's source state "
                                                           "that make it stale (0: no test)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, frame: str, payload_mass: float | None = None, check_sensors: bool = True,
            force_range: float = 10000.0, torque_range: float = 1000.0, frozen_ticks: int = 50, stale_ticks: int = 20,
        ) -> None: ...
    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")
    wrench = dg.Input(shape=(6,), doc="sensor reading [force, torque], sensor frame")

    def setup(self) -> None:
        """No guard until the first reading (made with the graph's dt)."""
        self._guard: SensorGuard | None = None

    def reset(self) -> None:
        """No trusted reading yet."""
        self._guard = None

    def _new_guard(self) -> SensorGuard:
        limit = np.array([self.force_range] * 3 + [self.torque_range] * 3)
        # no rate: dt is never used by the prediction (an entity outside a graph has none)
        dt = self.graph.dt if self.graph is not None else 0.0
        return SensorGuard(self, [Channel("wrench", -limit, limit)], dt, self.frozen_ticks, self.stale_ticks)

    @dg.output(shape=(6,), depends=("wrench",), labels=("fx", "fy", "fz", "tx", "ty", "tz"))
    def checked_wrench(self, t: int) -> Any:
        """The reading as the guard trusts it (the reading itself with ``check_sensors`` off)."""
        if not self.check_sensors:
            return self.wrench(t)
        if self._guard is None:
            self._guard = self._new_guard()
        return self._guard.read(t)[0]

    @dg.output(shape=(), depends=("robot",))
    def payload(self, t: int) -> float:
        """Mass beyond the sensor (kg)."""
        if self.payload_mass is not None:
            return self.payload_mass
        state = self.robot(t)
        return payload_mass(state, self.frame_index(state))

    @dg.output(shape=(3,), depends=("robot", "checked_wrench", "payload"), labels=("x", "y", "z"))
    def force(self, t: int) -> np.ndarray:
        """``R f_s - m g`` (N, world), ``f_s`` the trusted reading."""
        state = self.robot(t)
        rotation = state.frame_placement(self.frame_index(state)).rotation
        return rotation @ self.checked_wrench(t)[:3] - self.payload(t) * state.model.gravity.linear

    def prepare_state(self, t: int) -> None:
        """Check the reading at every tick (the frozen test counts ticks), read or not."""
        if self.check_sensors:
            self.checked_wrench(t)

    def commit_state(self, t_next: int) -> None:
        """The tick's trusted reading becomes the guard's base for the next one."""
        if self._guard is not None:
            self._guard.commit()
