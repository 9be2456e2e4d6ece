"""Contact6d: the placement error and the motion rows against their definitions (Eq. 4.10)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.contacts import Contact6d
from dgraph.entities.robot import RobotModel
from dgraph.entities.robot.robot_state import LOCAL
from dgraph.entities.robot.rotations import log3_product


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-5, 1e-2, 0.5, 2.0, 2.2, 3.0, np.pi - 1e-6])
def test_log3_product_is_pinocchios_log3_of_the_product(angle):
    rng = np.random.default_rng(int(angle * 1e3))
    for _ in range(50):
        axis = rng.normal(size=3)
        b = pin.exp3(rng.normal(size=3))
        a = pin.exp3(angle * axis / np.linalg.norm(axis)) @ b.T  # A B turns by angle
        tolerance = 1e-12 if angle < 2.5 else 1e-9  # the log is ill-conditioned near pi
        np.testing.assert_allclose(log3_product(a.tolist(), b.tolist()), pin.log3(a @ b), atol=tolerance)


def test_the_error_and_the_motion_rows_are_their_definitions():
    g = dg.Graph(dt=0.001)
    robot = g.add(RobotModel("robot"))
    foot = g.add(Contact6d("foot", frame="left_sole_link"))
    g.plug("robot.state", "foot.robot")
    model = robot.pin_model
    q = model.referenceConfigurations["half_sitting"].copy()
    robot.q.set(q)
    robot.v.set(np.zeros(model.nv))
    foot.kp.set(np.array([30.0, 31.0, 32.0, 33.0, 34.0, 35.0]))
    foot.kd.set(11.0)
    g.step()  # anchored at the half-sitting placement
    anchor = foot.anchor(1)
    rng = np.random.default_rng(3)
    q[7:13] += rng.normal(scale=0.1, size=6)  # the left leg moves
    robot.q.set(q)
    robot.v.set(rng.normal(size=model.nv))
    contact = foot.contact(1)
    frame = robot.state(1).frame(model.getFrameId("left_sole_link"), LOCAL)
    rotation, translation = frame.rotation, frame.translation
    error = np.concatenate([rotation.T @ (translation - anchor.translation), pin.log3(anchor.rotation.T @ rotation)])
    assert np.linalg.norm(error) > 0.01
    np.testing.assert_allclose(contact.error, error, atol=1e-14)
    rhs = -np.array([30.0, 31.0, 32.0, 33.0, 34.0, 35.0]) * error - 11.0 * frame.velocity - frame.drift
    np.testing.assert_allclose(contact.motion_rhs, rhs, atol=1e-12)
    assert contact.jacobian is frame.jacobian and contact.rotation is rotation


def test_the_gains_are_checked_where_they_are_set():
    foot = Contact6d("foot", frame="left_sole_link")
    foot.kd.set(np.ones(6))
    with pytest.raises(dg.SpecError, match=r"foot\.kp: expected a scalar or 6 values, one per motion row "
                                           r"\(x y z rx ry rz, contact frame\), got 3 values"):
        foot.kp.set([30.0, 30.0, 30.0])
    with pytest.raises(dg.SpecError, match=r"foot\.kd: must be >= 0"):
        foot.kd.set([11.0, 11.0, 11.0, -11.0, 11.0, 11.0])
    assert foot.kp.value == 0.0 and foot.kd.value.tolist() == [1.0] * 6
