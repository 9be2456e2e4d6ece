"""PointContact: a frame's point pressing on a surface (a tool tip on a block), with a force reference."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.control.contact import ContactConstraint
from dgraph.entities.constants import per_row_problem
from dgraph.entities.contacts.anchoring import AnchoredContact
from dgraph.entities.robot.robot_state import WORLD, FrameReader, RobotState
from dgraph.entities.tasks.gains import Gains


def tangent_basis(normal: np.ndarray) -> np.ndarray:
    """Rows ``t1, t2, n``: an orthonormal basis whose last row is the unit ``normal``."""
    n = normal / np.linalg.norm(normal)
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1)
    return np.vstack([t1, np.cross(n, t1), n])


def point_friction(normal: np.ndarray, mu: float) -> np.ndarray:
    """Rows ``C`` (5 x 3): four faces ``+-t_i . f - mu' n . f <= 0`` of the pyramid inscribed in
    Coulomb's cone (``mu' = mu / sqrt 2``, thesis Eq. 2.11), then the normal force ``n . f``."""
    t1, t2, n = tangent_basis(normal)
    inner = mu / np.sqrt(2.0)
    return np.vstack([t1 - inner * n, -t1 - inner * n, t2 - inner * n, -t2 - inner * n, n])


@dg.register
class PointContact(AnchoredContact, FrameReader, dg.Entity):
    """A unilateral point contact of a robot frame on a surface of world ``normal`` (TSID's
    ContactPoint), the contact of a Cartesian force-contact task (thesis Eq. 4.12-4.13).

    Motion (hard rows of the QP): the point does not accelerate, with a PD correction towards the
    anchor ``p_a`` (where the point was when the contact became active):
    ``J a + J_dot v = -Kp (p - p_a) - Kd p_dot``, with ``J`` the 3 x nv linear Jacobian of the
    frame origin (world axes) and ``J_dot v`` its classical acceleration at ``a = 0``.

    Force: ``f`` (3 variables, world axes) is the force the surface exerts on the robot at the
    point; ``n . f`` within ``[min_normal_force, max_normal_force]`` and the inscribed friction
    pyramid (:func:`point_friction`). Cost ``force_weight ||f - f*||^2`` with ``f*`` the input
    ``force_reference`` (plug a :class:`~dgraph.entities.tasks.ForceTask`'s ``force``); left
    unplugged and unset, the contact has no force reference: ``||f||^2`` regularises it.

    Parameters: ``frame`` (the point: a frame of the plugged model, e.g. a tool tip added with
    RobotModel's ``tool_frames``), ``normal`` (3, world, pointing from the surface into the
    robot's side: the direction of the force on the robot), ``mu``, ``min_normal_force``,
    ``max_normal_force`` (N), ``force_weight``.
    Inputs: ``robot``, ``kp``, ``kd`` (scalar or 3), ``active`` (commands ``activate`` /
    ``deactivate``), ``force_reference`` (3, N, world), ``normal_force_scale`` and
    ``force_weight_scale`` (ramps of the normal-force bound and of the force weight, as Contact6d).
    State: ``anchor`` (3, the anchored point; None while inactive).
    Outputs: ``contact`` (:class:`ContactConstraint`), ``error`` (``p - p_a``), ``position`` (``p``).
    """

    frame = dg.Param(kind="str", doc="the contact point (a frame of the model)")
    normal = dg.Param([0.0, 0.0, 1.0], kind="vector", doc="surface normal, world (direction of the force on the robot)")
    mu = dg.Param(0.5, kind="float", minimum=1e-3, doc="friction coefficient")
    min_normal_force = dg.Param(0.0, kind="float", minimum=0.0, doc="minimum normal force (N)")
    max_normal_force = dg.Param(200.0, kind="float", minimum=0.0, doc="maximum normal force (N)")
    force_weight = dg.Param(1e-5, kind="float", minimum=0.0, doc="weight of ||f - f*||^2 in the cost")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, frame: str, normal: ArrayLike = (0.0, 0.0, 1.0), mu: float = 0.5,
            min_normal_force: float = 0.0, max_normal_force: float = 200.0, force_weight: float = 1e-05,
        ) -> None: ...

    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")
    kp = dg.Input(default=0.0, minimum=0.0, doc="anchor stiffness (scalar or 3)")
    kd = dg.Input(default=0.0, minimum=0.0, doc="anchor damping (scalar or 3)")
    force_reference = dg.Input(shape=(3,), default=np.zeros(3), doc="f*: desired force on the robot (N, world)")

    def configure(self) -> None:
        """Friction rows and bounds."""
        normal = np.asarray(self.normal, dtype=float)
        if normal.shape != (3,) or not np.linalg.norm(normal) > 1e-9:
            raise dg.ParamError(f"{self.name}: normal must be a non-zero 3-vector", entity=self.name)
        self._friction = point_friction(normal, self.mu)
        self._lower, self._upper = self.friction_bounds(len(self._friction) - 1)
        self._generator = np.eye(3)
        self._rotation = np.eye(3)  # forces are in world axes; shared by every tick's constraint: read-only
        self._rotation.flags.writeable = False
        self._gains = Gains(self)

    def constant_problem(self, name: str, value: object) -> str | None:
        """``kp`` and ``kd`` are a scalar or one gain per axis."""
        return per_row_problem(value, 3, "axis (x y z, world)") if name in ("kp", "kd") else None
    def here(self, t: int) -> np.ndarray:
        """The point at ``t`` (a copy)."""
        state = self.robot(t)
        return state.frame(self.frame_index(state), WORLD).translation.copy()

    @dg.output(shape=(3,), depends=("robot",))
    def position(self, t: int) -> np.ndarray:
        """The point ``p`` (world)."""
        state = self.robot(t)
        return state.frame(self.frame_index(state), WORLD).translation

    @dg.output(dtype=ContactConstraint, depends=("robot", "kp", "kd", "active", "force_reference", "anchor",
                                                 "normal_force_scale", "force_weight_scale"))
    def contact(self, t: int) -> ContactConstraint:
        """Motion rows, friction rows and the force reference at ``t``."""
        state = self.robot(t)
        frame = state.frame(self.frame_index(state), WORLD)
        error = frame.translation - self.anchor_or_here(t)
        kp, kd = self._gains.vector("kp", 3, t), self._gains.vector("kd", 3, t)
        rhs = -kp * error - kd * frame.velocity[:3] - frame.drift[:3]
        lower, upper, force_weight = self.force_terms(t)
        return ContactConstraint(self.name, bool(self.active(t)), frame.jacobian[:3], rhs, self._generator,
                                 self._friction, lower, upper, force_weight, self._rotation,
                                 error, self._force_reference(t))

    def _force_reference(self, t: int) -> np.ndarray | None:
        """``f*``, or None when nothing sets it (a plain contact: its force is regularised to 0
        and, for an energy tank, is an environment force, not a force task)."""
        inp = self.force_reference
        return inp(t) if inp.source is not None or inp.is_set else None

    @dg.output(shape=(3,), depends=("contact",))
    def error(self, t: int) -> np.ndarray:
        """``p - p_a`` (world)."""
        return self.contact(t).error
