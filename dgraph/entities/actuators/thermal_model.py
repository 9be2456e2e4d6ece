"""The motor's first-order thermal model (thesis §3.2.2, Eqs. 3.6-3.8) and its exact step.

With ``x = T - T_A`` (the winding's rise over the drive's ambient) and the current ``i``:

* winding resistance (Eq. 3.6): ``R_el(T) = R_TA (1 + alpha_Cu (T - T_A))``,
* Joule power (Eq. 3.7): ``P_J = R_el(T) i²``,
* heat balance (Eq. 3.8): ``C_th T_dot = P_J - (T - T_A) / R_th``.

The thesis writes one resistance for both (``R_TA = R_th``, "we set R_th = R", L3340-3349): here
they are two parameters, the electrical ``R_TA`` (Ω) and the thermal ``R_th`` (K/W).

At a constant current Eq. 3.8 is linear in ``x``: ``x_dot = b - a x`` with
``a = (1/R_th - alpha_Cu R_TA i²) / C_th`` and ``b = R_TA i² / C_th``. Its steady state is
``x_ss = b / a = R_th R_TA i² / (1 - alpha_Cu R_th R_TA i²)``, i.e. ``T_ss = T_A + R_th P_J(T_ss)``,
and there is none (thermal runaway: the resistance rises faster than the losses leave) when
``alpha_Cu R_th R_TA i² >= 1``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

import dgraph as dg
from dgraph.params import MAX_SIZE

T_IDLE = 43.0
"""The elbow motor's temperature when unused (°C): the drives heat it above the 26 °C room (§3.5.1)."""
ALPHA_CU_20 = 3.93e-3
"""Temperature coefficient of copper's resistance referred to 20 °C (1/K), the handbook value; the
thesis gives none."""
ALPHA_CU = ALPHA_CU_20 / (1.0 + ALPHA_CU_20 * (T_IDLE - 20.0))
"""The same coefficient referred to ``T_A`` = 43 °C, where Eq. 3.6 takes ``R_TA`` (1/K): 3.604e-3. Copper's
resistance is linear in T, ``R(T) = R_20 (1 + alpha_20 (T - 20))``, so referred to 43 °C its slope
divides by ``1 + alpha_20 (43 - 20)``; using alpha_20 with ``R_TA`` at 43 °C overstates the rise by 9 %."""


def thermal_step(T: np.ndarray, current: np.ndarray, dt: float, C_th: np.ndarray, R_th: np.ndarray,
                 R_TA: np.ndarray, T_A: np.ndarray, alpha_Cu: np.ndarray) -> np.ndarray:
    """``T`` after ``dt`` seconds of Eq. 3.8 with ``current`` held: the exact solution
    ``x(dt) = x e^{-a dt} + b (1 - e^{-a dt}) / a`` (``x = T - T_A``; ``(1 - e^{-a dt}) / a`` taken
    as ``dt`` when ``a dt`` is negligible). Exact for any ``dt`` under a zero-order hold of the
    current, so stable at any step (explicit Euler would need ``dt < 2 R_th C_th``)."""
    i2 = np.square(current)
    a = (1.0 / R_th - alpha_Cu * R_TA * i2) / C_th
    b = R_TA * i2 / C_th
    ad = a * dt
    small = np.abs(ad) < 1e-9
    safe = np.where(small, 1.0, ad)
    phi = np.where(small, dt * (1.0 - 0.5 * ad), -np.expm1(-safe) / np.where(small, 1.0, a))
    x = T - T_A
    return T_A + x * np.exp(-ad) + b * phi


def steady_temperature(current: ArrayLike, R_th: ArrayLike, R_TA: ArrayLike, T_A: ArrayLike = T_IDLE,
                       alpha_Cu: ArrayLike = ALPHA_CU) -> np.ndarray:
    """``T_ss = T_A + R_th R_TA i² / (1 - alpha_Cu R_th R_TA i²)``, the solution of
    ``T = T_A + R_th R_el(T) i²``; ``inf`` where there is none (thermal runaway)."""
    k = np.asarray(R_th, dtype=float) * np.asarray(R_TA, dtype=float) * np.square(np.asarray(current, dtype=float))
    denominator = 1.0 - np.asarray(alpha_Cu, dtype=float) * k
    with np.errstate(divide="ignore"):
        return np.where(denominator > 0.0, np.asarray(T_A, dtype=float) + k / np.where(denominator > 0.0,
                                                                                       denominator, 1.0), np.inf)


def _n(entity: ThermalModel | dg.Entity) -> tuple[int]:
    """One value per joint (the entity's ``size``): the shape of the actuator entities' signals."""
    return (entity.size,)  # type: ignore[union-attr]


@dg.register
class ThermalModel(dg.Entity):
    """Winding temperature of ``size`` motors from their currents (thesis Eqs. 3.6-3.8).

    Per joint (a parameter is a scalar for all or one value per joint): ``R_el(T) = R_TA (1 +
    alpha_Cu (T - T_A))`` (3.6), ``P_J = R_el(T) i_m²`` (3.7), ``C_th T_dot = P_J - (T - T_A) /
    R_th`` (3.8). State ``temperature`` at ``t + 1`` is the exact solution of Eq. 3.8 over one
    tick with ``current(t)`` held (:func:`thermal_step`: exact, so stable at any ``dt``); it
    starts at ``T0`` (default ``T_A``).

    Defaults: ``T_A`` = 43 °C (the thesis's idle motor temperature: the drives heat it, §3.5.1),
    ``alpha_Cu`` = 3.604e-3 /K (copper's 3.93e-3 at 20 °C referred to 43 °C, ``R_TA``'s temperature:
    :data:`ALPHA_CU`; give ``alpha_20 / (1 + alpha_20 (T_A - 20))`` with another ``T_A``).
    Gap-fillers (the thesis prints no values; its identified ``C_th``, ``R_th`` are only in
    Fig. 3.3): ``R_TA`` = 0.6 Ω (winding resistance of a small 48 V
    frameless brushless motor, the order of TALOS's arm motors), ``R_th`` = 1.5 K/W (winding to
    the drive's ambient), ``C_th`` = 400 J/K (a time constant ``R_th C_th`` = 600 s, the ten-minute
    scale of the heating run of Fig. 3.3), ``T_max`` = 100 °C (a casing-side limit well under
    class-F insulation's 155 °C). Identify them from a heating run before trusting a temperature.

    Inputs: ``current`` (i_m, A). States: ``temperature`` (T, °C). Outputs: ``headroom``
    (``T_max - T``, K), ``joule_power`` (P_J at ``T(t)`` and ``i_m(t)``, W), ``resistance``
    (``R_el(T)``, Ω).
    """

    has_state = True
    size = dg.Param(kind="int", minimum=1, maximum=MAX_SIZE, doc="number of motors")
    C_th = dg.Param(400.0, kind="vector", minimum=1e-9, doc="thermal capacity, J/K (gap-filler)")
    R_th = dg.Param(1.5, kind="vector", minimum=1e-9, doc="thermal resistance winding to ambient, K/W (gap-filler)")
    R_TA = dg.Param(0.6, kind="vector", minimum=0.0, doc="winding resistance at T_A, Ohm (gap-filler)")
    T_A = dg.Param(T_IDLE, kind="vector", minimum=-273.15, doc="ambient of the motor, °C (thesis: 43 idle)")
    alpha_Cu = dg.Param(ALPHA_CU, kind="vector", minimum=0.0, doc="copper resistance coefficient referred to T_A, "
                        "1/K (default: 3.93e-3 at 20 °C referred to 43 °C)")
    T_max = dg.Param(100.0, kind="vector", minimum=-273.15, doc="temperature limit, °C (gap-filler)")
    T0 = dg.Param(None, kind="vector", minimum=-273.15, doc="initial temperature, °C (default: T_A)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, size: int, C_th: ArrayLike = 400.0, R_th: ArrayLike = 1.5, R_TA: ArrayLike = 0.6,
            T_A: ArrayLike = 43.0, alpha_Cu: ArrayLike = 0.003604215005640184, T_max: ArrayLike = 100.0,
            T0: ArrayLike | None = None,
        ) -> None: ...

    current = dg.Input(shape=_n, doc="motor current i_m, A")
    temperature = dg.State(shape=_n, doc="winding (and casing) temperature T, °C")

    def configure(self) -> None:
        """Broadcast every parameter to one value per motor."""
        for name in ("C_th", "R_th", "R_TA", "T_A", "alpha_Cu", "T_max", "T0"):
            value = getattr(self, name)
            if value is None:
                continue
            array = np.asarray(value, dtype=float)
            if array.shape not in ((), (1,), (self.size,)):
                raise dg.ParamError(f"{self.name}: parameter {name!r} must be a scalar or {self.size} values, got "
                                    f"shape {array.shape}", entity=self.name)
            setattr(self, f"_{name}", np.broadcast_to(array.reshape(-1) if array.ndim else array,
                                                      (self.size,)).astype(float))

    def reset(self) -> None:
        """``T(0) = T0`` (default ``T_A``)."""
        self.temperature.set((self._T_A if self.T0 is None else self._T0).copy(), 0)

    def prepare_state(self, t: int) -> None:
        """Stage ``T(t + 1)``: Eq. 3.8 solved exactly over ``dt`` with ``current(t)`` held."""
        self.temperature.stage(thermal_step(self.temperature(t), self.current(t), self.dt, self._C_th, self._R_th,
                                            self._R_TA, self._T_A, self._alpha_Cu))

    def commit_state(self, t_next: int) -> None:
        """Publish ``T(t + 1)``."""
        self.temperature.commit(t_next)

    @dg.output(shape=_n, depends=("temperature",))
    def resistance(self, t: int) -> np.ndarray:
        """``R_el(T) = R_TA (1 + alpha_Cu (T - T_A))`` (Eq. 3.6), Ω."""
        return self._R_TA * (1.0 + self._alpha_Cu * (self.temperature(t) - self._T_A))

    @dg.output(shape=_n, depends=("resistance", "current"))
    def joule_power(self, t: int) -> np.ndarray:
        """``P_J = R_el(T) i_m²`` (Eq. 3.7), W."""
        return self.resistance(t) * np.square(self.current(t))

    @dg.output(shape=_n, depends=("temperature",))
    def headroom(self, t: int) -> np.ndarray:
        """``T_max - T``, K (negative: over the limit)."""
        return self._T_max - self.temperature(t)
