"""FloatingBaseEstimator against MuJoCo's ground truth when TALOS is dropped onto the floor."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

import dgraph as dg
from dgraph.entities.estimators import FloatingBaseEstimator
from dgraph_sim.device import MujocoDevice

SENSORS = ("imu_orientation", "imu_angular_velocity", "imu_linear_acceleration", "encoder_position",
           "encoder_velocity", "ft_left_ankle", "ft_right_ankle")


def test_a_robot_dropped_from_5cm_keeps_its_fall_velocity_at_touch_down():
    g = dg.Graph(dt=0.001)
    standing = MujocoDevice("standing").sim.q0
    q0 = standing.copy()
    q0[2] += 0.05
    device = g.add(MujocoDevice("device", control_mode="position", q0=q0))
    estimator = g.add(FloatingBaseEstimator("estimator", q0=q0))
    for sensor in SENSORS:
        g.plug(f"device.{sensor}", f"estimator.{sensor}")
    model = device.sim.pin_model
    device.control.set(q0[7:])
    device.feedforward_torque.set(pin.rnea(model, model.createData(), standing, np.zeros(38), np.zeros(38))[6:])
    errors, landed = [], None
    for _ in range(400):
        g.step()
        t = g.t
        rotation = pin.Quaternion(device.q(t)[3:7]).toRotationMatrix()
        true_velocity = rotation @ device.v(t)[:3]
        errors.append(abs(estimator.base_velocity_world(t)[2] - true_velocity[2]))
        if landed is None and estimator.contact_left(t):
            landed = t
    assert landed is not None and 80 < landed < 130  # free fall of 5 cm takes 0.1 s
    assert max(errors) < 0.1, f"vertical velocity error up to {max(errors):.3f} m/s"  # 0.9 m/s before the fix
    assert np.abs(estimator.q(g.t)[:3] - device.q(g.t)[:3]).max() < 0.005
