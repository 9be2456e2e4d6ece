"""Synthetic TALOS sensor data: a kinematically exact sway with the soles fixed on the ground.

The base follows sinusoids (position and a rotation about a fixed body axis), the torso, arm
and head joints too; each tick the leg joints are solved by Newton iterations on the sole
placements (6x6 square Jacobians), and their velocities from ``J_foot v = v_foot`` (zero for a
stance foot). Sensors are synthesised with Pinocchio from the true state:

* IMU orientation: quaternion of ``oMf[imu].rotation`` (``pin.Quaternion``, xyzw);
* gyro: ``getFrameVelocity(imu, LOCAL).angular``;
* accelerometer: ``R_WI^T (pdd_I - g)``, ``pdd_I`` the classical acceleration of the IMU
  origin (the IMU is on the torso: it depends on the base and torso accelerations only, so
  the leg accelerations are left at zero);
* encoders: ``q[7:]``, ``v[6:]``;
* F/T: a vertical force of prescribed magnitude expressed in the ankle sensor frame.

Optionally the right foot lifts: its force ramps to zero, it moves up and forward along a
smooth arc, lands, and its force ramps up again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.entities.estimators.leg_odometry import standing_configuration
from dgraph.entities.robot import load_model

DT = 0.001
SOLES = ("left_sole_link", "right_sole_link")
ANKLES = ("leg_left_6_joint", "leg_right_6_joint")
SENSORS = {"imu_orientation": 4, "imu_angular_velocity": 3, "imu_linear_acceleration": 3,
           "encoder_position": 32, "encoder_velocity": 32, "ft_left_ankle": 6, "ft_right_ankle": 6}


@dataclass
class Lift:
    """Right foot: force down over [t0, t0 + ramp], swing over [t1, t2], force up over [t3, t3 + ramp]."""

    t0: float = 0.8
    t1: float = 1.2
    t2: float = 1.8
    t3: float = 1.9
    ramp: float = 0.3
    forward: float = 0.08
    height: float = 0.05


@dataclass
class Trajectory:
    """Per-tick arrays (one row per tick)."""

    q: np.ndarray
    v: np.ndarray
    sensors: dict[str, np.ndarray]
    normal_force: np.ndarray  # (N, 2) prescribed normal forces, left and right
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.q)


def _smooth(s: float) -> tuple[float, float]:
    """Smoothstep 3s^2 - 2s^3 on [0, 1] and its derivative (per unit s)."""
    s = min(max(s, 0.0), 1.0)
    return 3 * s * s - 2 * s**3, 6 * s - 6 * s * s


def generate(duration: float = 3.0, lift: Lift | None = None, sway: float = 1.0) -> Trajectory:
    """Sensor data of TALOS swaying for ``duration`` s (``sway`` scales the base motion)."""
    model = load_model("talos")
    data = model.createData()
    q = standing_configuration(model, SOLES)
    p0, r0 = q[:3].copy(), pin.Quaternion(q[3:7]).toRotationMatrix()
    soles = [model.getFrameId(f) for f in SOLES]
    ankles = [model.getFrameId(f) for f in ANKLES]
    imu = model.getFrameId("imu_link")
    pin.framesForwardKinematics(model, data, q)
    targets = [data.oMf[f].copy() for f in soles]
    legs_q = [np.arange(7, 13), np.arange(13, 19)]
    legs_v = [np.arange(6, 12), np.arange(12, 18)]
    upper_q = np.arange(19, model.nq)
    q_upper0 = q[upper_q].copy()
    rng = np.random.default_rng(1)
    b_up = rng.uniform(0.05, 0.15, upper_q.size)
    w_up = 2 * math.pi * rng.uniform(0.3, 1.0, upper_q.size)
    b_up[:2] = [0.15, 0.1]  # torso yaw and pitch: the IMU moves relative to the base

    amp = sway * np.array([0.02, 0.04, 0.01])
    w_b = 2 * math.pi * np.array([0.5, 0.5, 1.0])
    phase = np.array([0.0, 0.5 * math.pi, 0.0])
    axis = np.array([1.0, 0.6, 0.3]) / np.linalg.norm([1.0, 0.6, 0.3])
    rot_amp, w_rot = sway * 0.04, 2 * math.pi * 0.7
    gravity = model.gravity.linear

    n = round(duration / DT) + 1
    out_q, out_v = np.zeros((n, model.nq)), np.zeros((n, model.nv))
    sensors = {k: np.zeros((n, size)) for k, size in SENSORS.items()}
    forces = np.zeros((n, 2))
    for i in range(n):
        t = i * DT
        # base and upper body: analytic position, velocity, acceleration
        p = p0 + amp * np.sin(w_b * t + phase)
        pd = amp * w_b * np.cos(w_b * t + phase)
        pdd = -amp * w_b**2 * np.sin(w_b * t + phase)
        phi, phid, phidd = (rot_amp * math.sin(w_rot * t), rot_amp * w_rot * math.cos(w_rot * t),
                            -rot_amp * w_rot**2 * math.sin(w_rot * t))
        rot = r0 @ pin.exp3(axis * phi)
        q[:3], q[3:7] = p, pin.Quaternion(rot).coeffs()
        q[upper_q] = q_upper0 + b_up * np.sin(w_up * t)

        # right foot target (lift), and the prescribed normal forces
        target_r, vel_r = targets[1].copy(), np.zeros(3)
        f_left, f_right = 430.0 + 120.0 * math.sin(w_b[0] * t), 430.0 - 120.0 * math.sin(w_b[0] * t)
        if lift is not None:
            down, _ = _smooth((t - lift.t0) / lift.ramp)
            up, _ = _smooth((t - lift.t3) / lift.ramp)
            f_right = 430.0 * (1 - down + up)
            f_left = 860.0 - f_right
            span = lift.t2 - lift.t1
            s = (t - lift.t1) / span
            x, xd = _smooth(s)
            z = lift.height * math.sin(math.pi * s) ** 2 if 0 < s < 1 else 0.0
            zd = lift.height * math.pi * math.sin(2 * math.pi * s) if 0 < s < 1 else 0.0
            target_r.translation = targets[1].translation + np.array([lift.forward * x, 0.0, z])
            vel_r = np.array([lift.forward * xd, 0.0, zd]) / span
        goals = [targets[0], target_r]

        # legs: Newton on the sole placements
        for _ in range(30):
            pin.forwardKinematics(model, data, q)
            worst = 0.0
            for k in range(2):
                oMf = pin.updateFramePlacement(model, data, soles[k])
                err = pin.log6(oMf.actInv(goals[k])).vector
                worst = max(worst, np.abs(err).max())
                jac = pin.computeFrameJacobian(model, data, q, soles[k], pin.LOCAL)[:, legs_v[k]]
                q[legs_q[k]] += np.linalg.solve(jac, err)
            if worst < 1e-13:
                break
        else:
            raise RuntimeError(f"leg IK did not converge at t={t}")

        v = np.zeros(model.nv)
        v[:3], v[3:6] = rot.T @ pd, axis * phid
        v[18:] = b_up * w_up * np.cos(w_up * t)
        pin.computeJointJacobians(model, data, q)
        for k, foot_vel in enumerate([np.zeros(3), vel_r]):
            jac = pin.getFrameJacobian(model, data, soles[k], pin.LOCAL_WORLD_ALIGNED)
            rhs = np.concatenate([foot_vel, np.zeros(3)]) - jac @ v
            v[legs_v[k]] = np.linalg.solve(jac[:, legs_v[k]], rhs)

        a = np.zeros(model.nv)
        a[:3] = rot.T @ pdd - np.cross(v[3:6], v[:3])
        a[3:6] = axis * phidd
        a[18:] = -b_up * w_up**2 * np.sin(w_up * t)
        pin.forwardKinematics(model, data, q, v, a)
        pin.updateFramePlacements(model, data)
        r_wi = data.oMf[imu].rotation
        sensors["imu_orientation"][i] = pin.Quaternion(r_wi).coeffs()
        sensors["imu_angular_velocity"][i] = pin.getFrameVelocity(model, data, imu, pin.LOCAL).angular
        acc_local = pin.getFrameClassicalAcceleration(model, data, imu, pin.LOCAL).linear
        sensors["imu_linear_acceleration"][i] = acc_local - r_wi.T @ gravity
        sensors["encoder_position"][i], sensors["encoder_velocity"][i] = q[7:], v[6:]
        for k, (name, f_n) in enumerate([("ft_left_ankle", f_left), ("ft_right_ankle", f_right)]):
            sensors[name][i, :3] = data.oMf[ankles[k]].rotation.T @ np.array([0.0, 0.0, f_n])
            forces[i, k] = f_n
        out_q[i], out_v[i] = q, v
    return Trajectory(out_q, out_v, sensors, forces)


class Playback(dg.Device):
    """A test device replaying a :class:`Trajectory`: its states at tick t are row t."""

    trajectory = dg.Param(kind="object")
    q = dg.State(shape=(39,))
    v = dg.State(shape=(38,))
    imu_orientation = dg.State(shape=(4,))
    imu_angular_velocity = dg.State(shape=(3,))
    imu_linear_acceleration = dg.State(shape=(3,))
    encoder_position = dg.State(shape=(32,))
    encoder_velocity = dg.State(shape=(32,))
    ft_left_ankle = dg.State(shape=(6,))
    ft_right_ankle = dg.State(shape=(6,))

    def _row(self, i: int) -> dict[str, np.ndarray]:
        traj = self.trajectory
        i = min(i, len(traj) - 1)
        return {"q": traj.q[i], "v": traj.v[i], **{k: a[i] for k, a in traj.sensors.items()}}

    def reset(self) -> None:
        for name, value in self._row(0).items():
            self.signal(name).set(value, 0)

    def prepare_state(self, t: int) -> None:
        for name, value in self._row(t + 1).items():
            self.signal(name).stage(value)

    def commit_state(self, t_next: int) -> None:
        for name in self._row(0):
            self.signal(name).commit(t_next)
