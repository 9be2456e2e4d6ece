"""Contact6d: a unilateral rectangular plane contact (a foot sole): four corner forces, or
the 6D wrench in their exact wrench cone."""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.control.contact import ContactConstraint
from dgraph.entities.constants import per_row_problem
from dgraph.entities.contacts.anchoring import AnchoredContact
from dgraph.entities.contacts.wrench_cone import corner_force_metric, wrench_cone
from dgraph.entities.robot.robot_state import LOCAL, FrameReader, RobotState
from dgraph.entities.robot.rotations import MatrixRows, log3_product
from dgraph.entities.tasks.gains import Gains


def corner_positions(front: float, back: float, half_width: float) -> np.ndarray:
    """The four sole corners in the contact frame (rows), sole plane ``z = 0``."""
    return np.array([[front, half_width, 0.0], [front, -half_width, 0.0],
                     [-back, half_width, 0.0], [-back, -half_width, 0.0]])


def force_generator(corners: np.ndarray) -> np.ndarray:
    """``T`` (6 x 3n): stacked corner forces to the wrench ``[sum f_i, sum p_i x f_i]``."""
    n = len(corners)
    generator = np.zeros((6, 3 * n))
    for i, p in enumerate(corners):
        generator[:3, 3 * i:3 * i + 3] = np.eye(3)
        generator[3:, 3 * i:3 * i + 3] = pin.skew(p)
    return generator


def inscribed_coefficient(mu: float) -> float:
    """``mu' = mu / sqrt(2)``: the four-face pyramid ``|f_x|, |f_y| <= mu' f_z`` lies inside
    Coulomb's cone of coefficient ``mu``."""
    return mu / np.sqrt(2.0)


def friction_pyramid(n_corners: int, mu: float) -> np.ndarray:
    """Rows ``C`` with ``C f <= 0`` for a four-face pyramid per corner, inscribed in the cone.

    For each corner force ``(fx, fy, fz)``: ``+-fx <= mu' fz`` and ``+-fy <= mu' fz`` with
    ``mu' = mu / sqrt(2)``, so the pyramid lies inside Coulomb's cone ``||f_t|| <= mu fz``
    (thesis Eq. 2.11) and ``fz >= 0`` follows.
    """
    inner = inscribed_coefficient(mu)
    faces = np.array([[1.0, 0.0, -inner], [-1.0, 0.0, -inner], [0.0, 1.0, -inner], [0.0, -1.0, -inner]])
    rows = np.zeros((4 * n_corners, 3 * n_corners))
    for i in range(n_corners):
        rows[4 * i:4 * i + 4, 3 * i:3 * i + 3] = faces
    return rows


def placement_error(placement: MatrixRows, anchor_rotation_t: MatrixRows,
                    anchor_translation: list[float]) -> list[float]:
    """``e = [R^T (p - p_a), log3(R_a^T R)]`` (local frame) from Python floats: the placement
    ``[[R, p], [0, 1]]`` (rows of the 4 x 4 matrix) of the frame against the anchor ``(R_a, p_a)``,
    given ``R_a^T``."""
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2), _ = placement
    a0, a1, a2 = anchor_translation
    d0, d1, d2 = p0 - a0, p1 - a1, p2 - a2
    return [r00 * d0 + r10 * d1 + r20 * d2, r01 * d0 + r11 * d1 + r21 * d2, r02 * d0 + r12 * d1 + r22 * d2,
            *log3_product(anchor_rotation_t, ((r00, r01, r02), (r10, r11, r12), (r20, r21, r22)))]


def motion_rhs(kp: list[float], kd: list[float], error: list[float], velocity: list[float],
               drift: list[float]) -> np.ndarray:
    """``-Kp e - Kd V - J_dot v`` row by row (six rows, written out: cheaper than a comprehension)."""
    k0, k1, k2, k3, k4, k5 = kp
    d0, d1, d2, d3, d4, d5 = kd
    e0, e1, e2, e3, e4, e5 = error
    v0, v1, v2, v3, v4, v5 = velocity
    a0, a1, a2, a3, a4, a5 = drift
    return np.array((-k0 * e0 - d0 * v0 - a0, -k1 * e1 - d1 * v1 - a1, -k2 * e2 - d2 * v2 - a2,
                     -k3 * e3 - d3 * v3 - a3, -k4 * e4 - d4 * v4 - a4, -k5 * e5 - d5 * v5 - a5))


@dg.register
class Contact6d(AnchoredContact, FrameReader, dg.Entity):
    """A rigid planar contact of a robot frame (thesis §2.4, Eq. 4.10–4.11; TSID's Contact6d).

    Motion: the contact frame must not accelerate, with a PD correction of drift from the
    anchor placement ``M_a`` (the frame's placement when the contact became active):
    ``J a + J_dot v = -Kp e - Kd V``, where ``V = J v`` is the body twist (local frame),
    ``e = [R^T (p - p_a), log3(R_a^T R)]`` and ``J``, ``J_dot v`` are in the local frame.

    Forces: one 3D force per sole corner, wrench ``w = T f`` (Eq. 4.11), friction pyramid per
    corner (inscribed, see :func:`friction_pyramid`), hence unilateral corners, hence a centre
    of pressure inside the sole (Eq. 2.13–2.15); total normal force within
    ``[min_normal_force, max_normal_force]``: these 12 corner forces are the QP's variables
    (``forces: corners``, the default, TSID's formulation).

    ``forces: wrench`` gives the QP the 6 components of ``w`` (contact frame) instead: the 16
    rows of :func:`~dgraph.entities.contacts.wrench_cone.wrench_cone` bound exactly the
    wrenches the corner forces can exert, and the regularisation ``force_weight w^T (T T^T)^-1
    w`` is the least ``force_weight ||f||^2`` that exerts ``w``. The QP is smaller (50
    variables instead of 62 for TALOS on two feet; the solver takes ~22 % less time,
    ``bench/contact_forces.py``) and has the same optimum while no corner pyramid binds. Where one binds (the
    centre of pressure on an edge of the sole), the corner QP also pays for the forces that
    keep the corners in their pyramids and the two answers differ: in ``graphs/talos_sway.yaml``
    (the unloaded sole's centre of pressure reaches its edge at each sway) the soles creep
    ~7.5 mm on the floor in 20 s with wrenches against ~2.6 mm with corner forces
    (``bench/contact_forces.py --closed-loop 20``).

    Parameters: ``frame`` (contact frame, z along the sole normal, origin on the sole),
    ``front``, ``back``, ``half_width`` (sole corners, m; TALOS: 0.10, 0.11, 0.069),
    ``mu`` (0.3), ``min_normal_force`` (N), ``max_normal_force`` (N),
    ``force_weight`` (regularisation of the forces in the cost), ``forces`` (``wrench`` or
    ``corners``: the force variables).
    Inputs: ``robot`` (RobotModel state), ``kp``, ``kd`` (drift correction gains; 0: the
    rigid constraint ``J a + J_dot v = 0``), ``active`` (bool; commands ``activate`` /
    ``deactivate`` set it; an inactive contact adds nothing to the QP), ``normal_force_scale``
    (``s``: the total normal force within ``[min(f_min, s f_max), s f_max]``; a scheduler ramps it
    to 0 before lift-off) and ``force_weight_scale`` (multiplies ``force_weight``; a scheduler
    starts it high at touch-down and ramps it to 1: stack-of-tasks/tsid issue #88).
    State: ``anchor`` (the anchored placement, ``None`` while inactive).
    Outputs: ``contact`` (:class:`ContactConstraint`, with ``e``), ``error`` (``e``, 6).
    """

    frame = dg.Param(kind="str", doc="contact frame (z = sole normal)")
    front = dg.Param(0.10, kind="float", minimum=0.0, doc="sole length in front of the frame origin (m)")
    back = dg.Param(0.11, kind="float", minimum=0.0, doc="sole length behind the frame origin (m)")
    half_width = dg.Param(0.069, kind="float", minimum=0.0, doc="half width of the sole (m)")
    mu = dg.Param(0.3, kind="float", minimum=1e-3, doc="friction coefficient (> 0: the pyramid keeps corners pushing)")
    min_normal_force = dg.Param(1.0, kind="float", minimum=0.0, doc="minimum total normal force (N)")
    max_normal_force = dg.Param(1000.0, kind="float", minimum=0.0, doc="maximum total normal force (N)")
    force_weight = dg.Param(1e-5, kind="float", minimum=0.0, doc="weight of ||f||^2 in the cost")
    forces = dg.Param("corners", kind="str", choices=("corners", "wrench"),
                      doc="force variables: the 4 corner forces, or the 6D wrench in their wrench cone")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, frame: str, front: float = 0.1, back: float = 0.11, half_width: float = 0.069,
            mu: float = 0.3, min_normal_force: float = 1.0, max_normal_force: float = 1000.0,
            force_weight: float = 1e-05, forces: Literal["corners", "wrench"] = "corners",
        ) -> None: ...

    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")
    kp = dg.Input(default=0.0, minimum=0.0, doc="drift-correction stiffness (scalar or 6)")
    kd = dg.Input(default=0.0, minimum=0.0, doc="drift-correction damping (scalar or 6)")

    def configure(self) -> None:
        """Precompute the force generator and the friction rows."""
        corners = corner_positions(self.front, self.back, self.half_width)
        generator = force_generator(corners)
        if self.forces == "wrench":
            self._generator, self._metric = np.eye(6), corner_force_metric(generator)
            cone = wrench_cone(self.front, self.back, self.half_width, inscribed_coefficient(self.mu))
            normal_sum = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])
        else:
            self._generator, self._metric = generator, None
            cone = friction_pyramid(len(corners), self.mu)
            normal_sum = np.zeros((1, 3 * len(corners)))
            normal_sum[0, 2::3] = 1.0
        self._friction = np.vstack([cone, normal_sum])
        self._gains = Gains(self)
        self._lower, self._upper = self.friction_bounds(len(cone))
        self._anchor: tuple[pin.SE3, list[list[float]], list[float]] | None = None  # the anchor taken apart

    def constant_problem(self, name: str, value: object) -> str | None:
        """``kp`` and ``kd`` are a scalar or one gain per motion row."""
        return per_row_problem(value, 6, "motion row (x y z rx ry rz, contact frame)") if name in ("kp", "kd") else None
    def here(self, t: int) -> pin.SE3:
        """The frame's placement at ``t`` (a copy)."""
        state = self.robot(t)
        return state.frame_placement(self.frame_index(state))

    def _anchor_terms(self, t: int) -> tuple[list[list[float]], list[float]]:
        """``(R_a^T, p_a)`` of the anchor as Python floats, taken apart once per anchor."""
        anchor = self.anchor_or_here(t)
        cached = self._anchor
        if cached is None or cached[0] is not anchor:
            cached = self._anchor = (anchor, anchor.rotation.T.tolist(), anchor.translation.tolist())
        return cached[1], cached[2]

    @dg.output(dtype=ContactConstraint, depends=("robot", "kp", "kd", "active", "anchor", "normal_force_scale",
                                                 "force_weight_scale"))
    def contact(self, t: int) -> ContactConstraint:
        """Motion rows, force generator and friction rows at ``t``: ``J a = -Kp e - Kd V - J_dot v``
        (Eq. 4.10 with the drift correction), ``e`` and the right-hand side in Python floats (six
        rows: cheaper than numpy's per-call cost)."""
        state = self.robot(t)
        frame = state.frame(self.frame_index(state), LOCAL)
        rotation = frame.rotation
        error = placement_error(frame.placement.tolist(), *self._anchor_terms(t))
        gains = self._gains
        rhs = motion_rhs(gains.floats("kp", 6, t), gains.floats("kd", 6, t), error, frame.velocity.tolist(),
                         frame.drift.tolist())
        lower, upper, force_weight = self.force_terms(t)
        return ContactConstraint(self.name, bool(self.active(t)), frame.jacobian, rhs, self._generator,
                                 self._friction, lower, upper, force_weight, rotation,
                                 np.array(error), force_metric=self._metric)

    @dg.output(shape=(6,), depends=("contact",))
    def error(self, t: int) -> np.ndarray:
        """``e = [R^T (p - p_a), log3(R_a^T R)]`` (local frame)."""
        return self.contact(t).error
