"""The parameters of a rigid actuator chain (thesis Ch. 3, Eqs. 3.1-3.5) and its friction.

One joint's chain: a current-controlled brushless motor, a harmonic drive of ratio R, a joint
torque sensor and the link. With ``q`` the joint position (motor and link encoders taken as
equal, the drive being stiff):

* motor side (Eq. 3.1): ``tau_m = (I_m + I_j) q_ddot + g (M_Y sin q + M_X cos q) + tau_fm + tau_fj``
* joint side: ``tau_j = I_j q_ddot + g (M_Y sin q + M_X cos q) + tau_fj``
* friction (Eq. 3.2): ``tau_fm = F_vm q_dot + F_sm sign(q_dot) + off_m`` and the same with ``j``
* current to torque (Eq. 3.3): ``tau_m = R K_m i_m``; sensor (Eq. 3.4): ``tau_j = K_j tau_js``

so the torque the chain delivers to the joint is ``tau_m - I_m q_ddot - tau_fm``: the motor's
torque less what the rotor's inertia and the motor-side friction take. ``M_X``, ``M_Y`` and
``I_j`` describe the link (the rigid-body model has them); the chain's own parameters are the
motor side's, the joint side's friction, ``R K_m`` and ``K_j``.

:data:`TALOS_ELBOW` holds the thesis's identified values (Table 3.1, joint-level SI units).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike

GRAVITY = 9.81
"""g (m/s²), as in the chain's gravity torque ``g (M_Y sin q + M_X cos q)`` (shared by the actuator
modules)."""


@dataclass(frozen=True)
class ChainParameters:
    """One joint's chain (thesis Table 3.1 names; SI units at the joint: kg m, kg m², N m, N m s/rad)."""

    M_X: float = 0.0
    """first moment of the link along X (kg m): gravity torque ``g M_X cos q``"""
    M_Y: float = 0.0
    """first moment of the link along Y (kg m): gravity torque ``g M_Y sin q``"""
    I_j: float = 0.0
    """link inertia about the joint axis (kg m²)"""
    I_m: float = 0.0
    """rotor inertia reflected at the joint (kg m²): MuJoCo's joint armature"""
    F_vm: float = 0.0
    """motor-side viscous friction (N m s/rad)"""
    F_sm: float = 0.0
    """motor-side dry (Coulomb) friction (N m)"""
    off_m: float = 0.0
    """motor-side torque offset (N m)"""
    F_vj: float = 0.0
    """joint-side viscous friction (N m s/rad)"""
    F_sj: float = 0.0
    """joint-side dry friction (N m)"""
    off_j: float = 0.0
    """joint-side torque offset (N m)"""
    R_Km: float = 1.0
    """gear ratio times the drive's current-to-torque gain (N m/A, Eq. 3.3)"""
    K_j: float = 1.0
    """joint torque sensor gain (Eq. 3.4)"""
    i_max: float = float("inf")
    """motor current limit (A)"""

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The parameter names, in declaration order."""
        return tuple(f.name for f in fields(cls))

    @property
    def F_v(self) -> float:
        """Total viscous friction ``F_vm + F_vj`` (Eq. 3.5)."""
        return self.F_vm + self.F_vj

    @property
    def F_s(self) -> float:
        """Total dry friction ``F_sm + F_sj`` (Eq. 3.5)."""
        return self.F_sm + self.F_sj


def friction(viscous: float | np.ndarray, dry: float | np.ndarray, offset: float | np.ndarray,
             velocity: np.ndarray | float,
             smoothing: float | None = None) -> np.ndarray:
    """``F_v q_dot + F_s sign(q_dot) + off`` (Eq. 3.2); with ``smoothing`` = mu, ``sign`` is
    ``tanh(mu q_dot)`` (Eq. 3.18, mu = 1000 in the thesis's MPC)."""
    velocity = np.asarray(velocity, dtype=float)
    sign = np.sign(velocity) if smoothing is None else np.tanh(smoothing * velocity)
    return viscous * velocity + dry * sign + offset


def desired_current(chains: Sequence[ChainParameters], torque: ArrayLike, q_dot: ArrayLike, q_ddot: ArrayLike,
                    smoothing: float | None = None, compensate_offsets: bool = True,
                    controller_armature: ArrayLike = 0.0) -> np.ndarray:
    """``i_m* = (tau_j* + (I_m - a_c) q_ddot + tau_fm(q_dot)) / (R K_m)`` per joint (Eq. 3.1's two lines
    subtracted, Eq. 3.3): the current whose motor torque delivers ``tau_j*`` to the joint, one value
    per chain of ``chains``. ``tau_fm = F_vm q_dot + F_sm sign(q_dot) + off_m`` (:func:`friction`,
    ``sign`` smoothed by ``smoothing``), without ``off_m`` if ``compensate_offsets`` is false (a plant
    with no offset torque, MuJoCo's twin); ``a_c`` = ``controller_armature`` (scalar or per joint), the
    rotor inertia the controller's model already puts in ``tau_j*`` (Pinocchio's armature). Shared by
    :class:`~dgraph.entities.actuators.ActuatorModel` and
    :class:`~dgraph.entities.actuators.TorqueProtection` (its reference ``u*``)."""
    def col(name: str) -> np.ndarray:
        return np.array([getattr(c, name) for c in chains], dtype=float)
    offset = col("off_m") if compensate_offsets else np.zeros(len(chains))
    tau_fm = friction(col("F_vm"), col("F_sm"), offset, q_dot, smoothing)
    inertia = col("I_m") - np.asarray(controller_armature, dtype=float)
    return (np.asarray(torque, dtype=float) + inertia * np.asarray(q_ddot, dtype=float) + tau_fm) / col("R_Km")


TALOS_ELBOW = ChainParameters(M_X=-0.11, M_Y=1.1, I_j=0.33, I_m=0.45, F_vm=5.1, F_sm=4.0, off_m=0.86,
                              F_vj=0.47, F_sj=0.55, off_j=-0.27, K_j=1.015, i_max=6.0)
"""TALOS's elbow, thesis Table 3.1 (identified column), ``K_j`` = 1.015 and the 6 A a-priori
current limit (§3.5.3). ``R K_m`` is not disclosed (the identified value differs from the
manufacturer's by 16 %): it stays 1 here and is set where it is known."""


TALOS_ELBOW_R_KM = 17.86 / 6.0
"""``R K_m`` of TALOS's elbow used by ``graphs/data/talos_actuators.yaml`` (N m/A), a gap-filler:
the thesis does not disclose it. The URDF's effort limit of ``arm_*_4_joint`` (17.86 N m) taken
as the torque at the thesis's 6 A current limit: 2.977 N m/A. Cross-check with the thesis's
simulated 30 kg case (§3.5.3: with the barrier the current plateaus at about 5.6 A, without it
the 6 A limit is exceeded): holding 30 kg at 5 cm (14.7 N m) with the forearm near the lower
limit -2.35 rad (``g (M_Y sin q + M_X cos q)`` = -6.9 N m, same side) needs about 21.6 N m
statically, 7.3 A at 2.977 N m/A: more than 6 A, as the thesis observes. That observation bounds
``R K_m`` from above (21.6 N m / 6 A = 3.6 N m/A, more if the motion's friction is counted); it
does not fix it."""

MAX_CHAIN_FILE_BYTES = 1 << 20
"""Largest actuator parameter file read (bytes)."""


class ChainFileError(ValueError):
    """An actuator parameter file that cannot be used; the message names the file and the joint or line."""


def _load_unique_keys(text: str, path: str) -> object:
    """The document of ``text`` read with dgraph's bounded safe loader
    (:data:`dgraph.files.source._SAFE_LOADER`, the graph files'), refusing a key written twice in
    one mapping (YAML would keep the last silently) with the line of the second; anchors, aliases
    and merge keys stay allowed (the shipped file writes the right elbow as ``*elbow``)."""
    import yaml

    from dgraph.files.source import _SAFE_LOADER, _LimitExceeded

    loader = _SAFE_LOADER(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        stack, seen = [node], set()
        while stack:
            current = stack.pop()
            if id(current) in seen:
                continue
            seen.add(id(current))
            if isinstance(current, yaml.MappingNode):
                keys: dict[str, int] = {}
                for key_node, value_node in current.value:
                    if isinstance(key_node, yaml.ScalarNode) and key_node.tag != "tag:yaml.org,2002:merge":
                        line = key_node.start_mark.line + 1
                        if key_node.value in keys:
                            raise ChainFileError(f"{path}, line {line}: duplicate key {key_node.value!r} (first at "
                                                 f"line {keys[key_node.value]})")
                        keys[key_node.value] = line
                    stack.append(value_node)
            elif isinstance(current, yaml.SequenceNode):
                stack.extend(current.value)
        return loader.construct_document(node)
    except _LimitExceeded as exc:
        raise ChainFileError(f"{path}{'' if exc.line is None else f', line {exc.line}'}: {exc}") from None
    finally:
        loader.dispose()


def load_chain_file(path: str | os.PathLike[str]) -> dict[str, ChainParameters]:
    """The chains of an actuator parameter file (YAML, read with the safe loader), by joint name.

    The file::

        joints:
          arm_left_4_joint: {I_m: 0.45, F_vm: 5.1, ..., R_Km: 2.977, K_j: 1.015, i_max: 6.0}

    Every key of a joint is a :class:`ChainParameters` field (a finite number; ``i_max``
    positive, may be ``.inf``; ``R_Km`` and ``K_j`` positive; ``I_m``, the viscous and dry
    frictions non-negative); ``R_Km`` and ``i_max`` are required (their defaults mean nothing
    for a real chain), the others default to the dataclass's. Other top-level keys than
    ``joints`` (``source``, ``notes``...) are allowed and ignored. A bad file raises
    :class:`ChainFileError` naming the file and the joint and key, or the line of a YAML error or
    of a key written twice in one mapping (a joint, or a parameter of a joint).
    """
    import yaml

    from dgraph.files.source import _yaml_reason

    path = os.fspath(path)
    try:
        size = os.stat(path).st_size
        if size > MAX_CHAIN_FILE_BYTES:
            raise ChainFileError(f"{path}: {size} bytes, more than the {MAX_CHAIN_FILE_BYTES} allowed")
        with open(path, encoding="utf-8") as f:
            document = _load_unique_keys(f.read(), path)
    except OSError as exc:
        raise ChainFileError(f"cannot read actuator file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ChainFileError(f"{path}: not UTF-8 text ({exc.reason})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark is not None else ""
        problem = _yaml_reason(exc, getattr(exc, "problem", None) or str(exc)).removeprefix("invalid YAML")
        raise ChainFileError(f"{path}{where}: not valid YAML{problem}") from None
    if not isinstance(document, dict) or not isinstance(document.get("joints"), dict) or not document["joints"]:
        raise ChainFileError(f"{path}: expected a mapping with a non-empty 'joints' mapping (joint name -> parameters)")
    names = set(ChainParameters.names())
    chains = {}
    for joint, values in document["joints"].items():  # keys are unique: _load_unique_keys
        where = f"{path}: joint {joint!r}"
        if not isinstance(joint, str) or not isinstance(values, dict):
            raise ChainFileError(f"{where}: expected a joint name mapped to its parameters")
        unknown = sorted(str(k) for k in values if k not in names)
        if unknown:
            raise ChainFileError(f"{where}: unknown parameter(s) {unknown}; known: {sorted(names)}")
        missing = [k for k in ("R_Km", "i_max") if k not in values]
        if missing:
            raise ChainFileError(f"{where}: missing {missing} (no default is meaningful for a real chain)")
        checked = {}
        for key, value in values.items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ChainFileError(f"{where}: {key} must be a number, got {value!r}")
            value = float(value)
            if np.isnan(value) or (np.isinf(value) and key != "i_max"):
                raise ChainFileError(f"{where}: {key} must be finite, got {value!r}")
            if key in ("R_Km", "K_j", "i_max") and not value > 0.0:
                raise ChainFileError(f"{where}: {key} must be positive, got {value!r}")
            if key in ("I_m", "I_j", "F_vm", "F_sm", "F_vj", "F_sj") and value < 0.0:
                raise ChainFileError(f"{where}: {key} must not be negative, got {value!r}")
            checked[key] = value
        chains[joint] = ChainParameters(**checked)
    return chains


def mujoco_joint(chain: ChainParameters) -> dict[str, float]:
    """What a MuJoCo joint driven by ``chain`` gets: ``armature`` = I_m (the link's inertia stays
    the rigid body's), ``damping`` = F_v = F_vm + F_vj, ``frictionloss`` = F_s = F_sm + F_sj,
    ``force_limit`` = R K_m i_max (the actuator's force range ±, and its ``ctrlrange``). The
    offsets ``off_m``, ``off_j`` have no MuJoCo counterpart and are left out: an
    :class:`~dgraph.entities.actuators.ActuatorModel` driving this twin takes
    ``compensate_offsets: false``, and ``controller_armature`` = the armature of the controller's
    own model (Pinocchio's), which its ``tau_j*`` already holds."""
    return {"armature": chain.I_m, "damping": chain.F_v, "frictionloss": chain.F_s,
            "force_limit": chain.R_Km * chain.i_max}
