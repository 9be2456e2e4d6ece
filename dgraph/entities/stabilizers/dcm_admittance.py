"""DcmAdmittance: the DCM controller and CoM admittance of the position schemes (Eq. 2.30–2.31)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

import dgraph as dg
from dgraph.entities.discrete.configuration_integrator import integration_step
from dgraph.entities.stabilizers.lipm import divergent_component, lipm_zmp, natural_frequency


@dg.register
class DcmAdmittance(dg.Entity):
    """Corrects the planned CoM with the measured ZMP and DCM (thesis §2.2.3.b, Fig. 4.2).

    With ``ω = √(g / (c_ref,z − h))``, on the horizontal axes:

    - references from the plan (LIPM, Eq. 2.22, 2.27): ``p_ref = c_ref − c̈_ref / ω²``,
      ``ξ_ref = c_ref + ċ_ref / ω``; measured DCM ``ξ = c + ċ / ω`` (estimated CoM);
    - DCM control, desired ZMP (Eq. 2.30):
      ``p* = p_ref − (1 + K_P / ω)(ξ_ref − ξ) + (K_Z / ω)(p_ref − p) − (K_I / ω) ∫(ξ_ref − ξ)``;
    - CoM admittance (Eq. 2.31): ``c̈* = c̈_ref + K_adm (p − p*)``, ``p`` the measured ZMP.

    The correction ``Δc̈ = K_adm (p − p*)`` is integrated (semi-implicit Euler) into ``Δċ``,
    ``Δc``, and the CoM task receives ``(c_ref + Δc, ċ_ref + Δċ, c̈_ref + Δc̈)``; the height is
    not corrected. Bounds the thesis does not give: ``|Δc| ≤ max_offset`` per axis (the
    velocity of a clipped axis is zeroed) and ``|∫(ξ_ref − ξ)| ≤ integral_limit``.

    ``h`` is the height of the ground the ZMPs are on: ``ground_height(t)``, on stairs the plane the
    pattern generator plans the ZMP in (``ZmpPatternGenerator.zmp_plane_height``), so that
    ``ω = √(g / (c_ref,z − h))`` is the plan's on every tread (counted from z = 0 it drops from
    3.50 to 2.65 rad/s at the top of six 10 cm stairs).

    Parameters: ``height`` (ground, m: the default of ``ground_height``), ``max_offset`` (m),
    ``integral_limit`` (m s), ``dt`` (default: the graph's).
    Inputs: ``reference_position``, ``reference_velocity``, ``reference_acceleration`` (3, the
    plan), ``com``, ``com_velocity`` (3, estimated), ``zmp`` (3, measured), ``ground_height``
    (scalar, m; default ``height``); gains ``kp_dcm``,
    ``ki_dcm``, ``kz_dcm``, ``kp_admittance`` (Table 4.3, TSID position: 8, 1, 1, 12; IK uses
    15 for the admittance).
    States: ``offset``, ``offset_velocity`` (2: ``Δc``, ``Δċ``), ``dcm_integral`` (2).
    Outputs: ``com_reference``, ``com_velocity_reference``, ``com_acceleration_reference`` (3: the
    corrected reference for the CoM task), ``correction`` (2: ``Δc̈``),
    ``zmp_reference``, ``desired_zmp`` (3), ``dcm``, ``dcm_reference`` (2), ``omega``.
    """

    has_state = True

    height = dg.Param(0.0, kind="float", doc="ground height (m) when ground_height is not plugged or set")
    max_offset = dg.Param(0.05, kind="float", minimum=0.0, doc="bound of the CoM correction per axis (m)")
    integral_limit = dg.Param(0.1, kind="float", minimum=0.0, doc="bound of the DCM error integral (m s)")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, height: float = 0.0, max_offset: float = 0.05, integral_limit: float = 0.1,
            dt: float | None = None,
        ) -> None: ...

    reference_position = dg.Input(shape=(3,), doc="planned CoM c_ref")
    reference_velocity = dg.Input(shape=(3,), default=np.zeros(3), doc="planned CoM velocity")
    reference_acceleration = dg.Input(shape=(3,), default=np.zeros(3), doc="planned CoM acceleration")
    com = dg.Input(shape=(3,), doc="estimated CoM")
    com_velocity = dg.Input(shape=(3,), doc="estimated CoM velocity")
    zmp = dg.Input(shape=(3,), doc="measured ZMP")
    kp_dcm = dg.Input(shape=(), default=8.0, minimum=0.0, doc="K_Pdcm (1/s)")
    ki_dcm = dg.Input(shape=(), default=1.0, minimum=0.0, doc="K_Idcm (1/s²)")
    kz_dcm = dg.Input(shape=(), default=1.0, minimum=0.0, doc="K_Zdcm (1/s)")
    kp_admittance = dg.Input(shape=(), default=12.0, minimum=0.0, doc="K_Padm (1/s²)")

    offset = dg.State(shape=(2,), initial=np.zeros(2), doc="Δc")
    offset_velocity = dg.State(shape=(2,), initial=np.zeros(2), doc="Δċ")
    dcm_integral = dg.State(shape=(2,), initial=np.zeros(2), doc="∫(ξ_ref − ξ) dt")

    def configure(self) -> None:
        """Declare ``ground_height``, its default the ``height`` parameter."""
        self.declare("ground_height", dg.Input(shape=(), default=self.height,
                                               doc="height of the ground the ZMPs are on (m)"))

    @dg.output(shape=(), depends=("reference_position", "ground_height"))
    def omega(self, t: int) -> float:
        """``√(g / (c_ref,z − h))``."""
        return float(natural_frequency(self.reference_position(t)[2] - self.ground_height(t)))

    @dg.output(shape=(3,), depends=("reference_position", "reference_acceleration", "omega", "ground_height"),
               labels=("x", "y", "z"))
    def zmp_reference(self, t: int) -> np.ndarray:
        """``p_ref`` (Eq. 2.22), on the ground plane."""
        p = lipm_zmp(self.reference_position(t), self.reference_acceleration(t), self.omega(t))
        return np.array([p[0], p[1], self.ground_height(t)])

    @dg.output(shape=(2,), depends=("reference_position", "reference_velocity", "omega"))
    def dcm_reference(self, t: int) -> np.ndarray:
        """``ξ_ref``."""
        return divergent_component(self.reference_position(t), self.reference_velocity(t), self.omega(t))

    @dg.output(shape=(2,), depends=("com", "com_velocity", "omega"))
    def dcm(self, t: int) -> np.ndarray:
        """``ξ`` from the estimated CoM."""
        return divergent_component(self.com(t), self.com_velocity(t), self.omega(t))

    @dg.output(shape=(3,), depends=("zmp_reference", "dcm_reference", "dcm", "zmp", "dcm_integral", "omega",
                                    "kp_dcm", "ki_dcm", "kz_dcm", "ground_height"), labels=("x", "y", "z"))
    def desired_zmp(self, t: int) -> np.ndarray:
        """``p*`` (Eq. 2.30)."""
        omega, p_ref = self.omega(t), self.zmp_reference(t)[:2]
        dcm_error = self.dcm_reference(t) - self.dcm(t)
        p = (p_ref - (1.0 + self.kp_dcm(t) / omega) * dcm_error + self.kz_dcm(t) / omega * (p_ref - self.zmp(t)[:2])
             - self.ki_dcm(t) / omega * self.dcm_integral(t))
        return np.array([p[0], p[1], self.ground_height(t)])

    @dg.output(shape=(2,), depends=("zmp", "desired_zmp", "kp_admittance"))
    def correction(self, t: int) -> np.ndarray:
        """``Δc̈ = K_adm (p − p*)`` (Eq. 2.31)."""
        return self.kp_admittance(t) * (self.zmp(t)[:2] - self.desired_zmp(t)[:2])

    @dg.output(shape=(3,), depends=("reference_position", "offset"), labels=("x", "y", "z"))
    def com_reference(self, t: int) -> np.ndarray:
        """``c* = c_ref + Δc``."""
        return self.reference_position(t) + np.append(self.offset(t), 0.0)

    @dg.output(shape=(3,), depends=("reference_velocity", "offset_velocity"))
    def com_velocity_reference(self, t: int) -> np.ndarray:
        """``ċ* = ċ_ref + Δċ``."""
        return self.reference_velocity(t) + np.append(self.offset_velocity(t), 0.0)

    @dg.output(shape=(3,), depends=("reference_acceleration", "correction"))
    def com_acceleration_reference(self, t: int) -> np.ndarray:
        """``c̈* = c̈_ref + Δc̈`` (Eq. 2.31)."""
        return self.reference_acceleration(t) + np.append(self.correction(t), 0.0)

    def prepare_state(self, t: int) -> None:
        """Integrate the correction and the DCM error, within their bounds."""
        offset, velocity = integration_step(np.add, self.offset(t), self.offset_velocity(t), self.correction(t),
                                            self.dt, "acceleration")
        clipped = np.abs(offset) > self.max_offset
        self.offset.stage(np.clip(offset, -self.max_offset, self.max_offset))
        self.offset_velocity.stage(np.where(clipped, 0.0, velocity))
        integral = self.dcm_integral(t) + self.dt * (self.dcm_reference(t) - self.dcm(t))
        self.dcm_integral.stage(np.clip(integral, -self.integral_limit, self.integral_limit))

    def commit_state(self, t_next: int) -> None:
        """Publish the states at ``t + 1``."""
        self.offset.commit(t_next)
        self.offset_velocity.commit(t_next)
        self.dcm_integral.commit(t_next)
