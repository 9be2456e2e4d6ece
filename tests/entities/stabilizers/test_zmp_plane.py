"""ZmpEstimator on a plane whose height is an input (issue 14: the ZMP plane follows the support
on stairs): known forces on two soles at different heights, read on planes at several heights."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.robot import RobotModel
from dgraph.entities.stabilizers import ZmpEstimator

LEFT_CONTACT = np.array([0.05, 0.1, 0.30])
RIGHT_CONTACT = np.array([-0.25, -0.1, 0.20])
"""The sensor origins: the left foot on a tread 10 cm above the right one's, 0.30 m ahead."""
PLANES = (0.0, 0.2, 0.25, 0.3, 0.45)
"""Plane heights (m): the floor, each sole's, between them and above both."""
LEFT_FORCE, RIGHT_FORCE = 400.0, 600.0
"""Vertical forces (N)."""


def stairs_feet_model() -> pin.Model:
    """Two 'ankles' (revolute joints on the universe, not turned) at the contacts."""
    model = pin.Model()
    for name, contact in (("left", LEFT_CONTACT), ("right", RIGHT_CONTACT)):
        joint = model.addJoint(0, pin.JointModelRZ(), pin.SE3(np.eye(3), contact), f"{name}_ankle")
        model.appendBodyToJoint(joint, pin.Inertia(1.0, np.zeros(3), np.eye(3) * 1e-3), pin.SE3.Identity())
        model.addJointFrame(joint)
    return model


def estimator(**params) -> tuple[dg.Graph, ZmpEstimator]:
    graph = dg.Graph(dt=0.001)
    robot = graph.add(RobotModel("robot", model=stairs_feet_model()))
    robot.q.set(np.zeros(2))
    robot.v.set(np.zeros(2))
    zmp = graph.add(ZmpEstimator("zmp", sensors=["left", "right"], frames=["left_ankle", "right_ankle"],
                                 compensate_feet=False, **params))
    graph.plug("robot.state", "zmp.robot")
    return graph, zmp


def expected_zmp(left_horizontal: np.ndarray, right_horizontal: np.ndarray, plane: float) -> np.ndarray:
    """By hand: ``p_xy = Σ (f_iz c_i,xy - f_i,xy (c_iz - h)) / f_z`` on the plane ``z = h``."""
    total = LEFT_FORCE + RIGHT_FORCE
    weighted = (LEFT_FORCE * LEFT_CONTACT[:2] + RIGHT_FORCE * RIGHT_CONTACT[:2]) / total
    shift = -(left_horizontal * (LEFT_CONTACT[2] - plane) + right_horizontal * (RIGHT_CONTACT[2] - plane)) / total
    return np.array([*(weighted + shift), plane])


def test_vertical_forces_give_the_same_point_on_every_plane():
    _, zmp = estimator()
    zmp.left.set([0.0, 0.0, LEFT_FORCE, 0.0, 0.0, 0.0])
    zmp.right.set([0.0, 0.0, RIGHT_FORCE, 0.0, 0.0, 0.0])
    weighted = [(400 * 0.05 - 600 * 0.25) / 1000, (400 * 0.1 - 600 * 0.1) / 1000]
    for plane in PLANES:
        zmp.plane_height.set(plane)
        np.testing.assert_allclose(zmp.zmp(0), [*weighted, plane], atol=1e-12)
        np.testing.assert_allclose(zmp.zmp(0), expected_zmp(np.zeros(2), np.zeros(2), plane), atol=1e-12)


@pytest.mark.parametrize("plane", PLANES)
def test_a_horizontal_force_moves_the_zmp_along_its_line_of_action(plane):
    """50 N along x on the left sole, -30 N along y on the right one: each moves the ZMP by
    ``-f_xy (c_z - h) / f_z``, behind a force applied above the plane, ahead of one below it."""
    _, zmp = estimator()
    left, right = np.array([50.0, 0.0]), np.array([0.0, -30.0])
    zmp.left.set([*left, LEFT_FORCE, 0.0, 0.0, 0.0])
    zmp.right.set([*right, RIGHT_FORCE, 0.0, 0.0, 0.0])
    zmp.plane_height.set(plane)
    vertical_only = np.array([-0.13, -0.02])
    shift = np.array([-50.0 * (0.30 - plane) / 1000, 30.0 * (0.20 - plane) / 1000])
    np.testing.assert_allclose(zmp.zmp(0), [*(vertical_only + shift), plane], atol=1e-12)
    np.testing.assert_allclose(zmp.zmp(0), expected_zmp(left, right, plane), atol=1e-12)


class SupportHeight(dg.Entity):
    """The support's height over the ticks: the lower sole's until tick 3, then the upper one's."""

    @dg.output(shape=(), depends=("t",))
    def height(self, t: int) -> float:
        return float(RIGHT_CONTACT[2] if t < 3 else LEFT_CONTACT[2])


def test_the_plane_follows_a_plugged_height_per_tick_and_defaults_to_the_height_parameter():
    graph, zmp = estimator(height=0.25)
    left = np.array([50.0, 0.0])
    zmp.left.set([*left, LEFT_FORCE, 0.0, 0.0, 0.0])
    zmp.right.set([0.0, 0.0, RIGHT_FORCE, 0.0, 0.0, 0.0])
    assert zmp.plane_height(0) == 0.25  # neither plugged nor set: the parameter
    np.testing.assert_allclose(zmp.zmp(0), expected_zmp(left, np.zeros(2), 0.25), atol=1e-12)
    zmp.plane_height.set(0.45)  # the cached ZMP is recomputed on the new plane
    np.testing.assert_allclose(zmp.zmp(0), expected_zmp(left, np.zeros(2), 0.45), atol=1e-12)
    graph.add(SupportHeight("support"))
    graph.plug("support.height", "zmp.plane_height")
    for t, plane in ((1, 0.2), (2, 0.2), (3, 0.3), (4, 0.3)):
        np.testing.assert_allclose(zmp.zmp(t), expected_zmp(left, np.zeros(2), plane), atol=1e-12)
    zmp.plane_height.unplug()
    assert zmp.zmp(5)[2] == 0.25


def test_without_contact_the_fallback_point_is_on_the_plane():
    _, zmp = estimator()
    zmp.left.set(np.zeros(6))
    zmp.right.set(np.zeros(6))
    zmp.plane_height.set(0.3)
    np.testing.assert_allclose(zmp.zmp(0), [-0.1, 0.0, 0.3], atol=1e-12)


def test_a_sensor_may_not_take_the_plane_height_name():
    with pytest.raises(dg.ParamError, match="'plane_height' cannot name an input"):
        ZmpEstimator("zmp", sensors=["left", "plane_height"], frames=["left_ankle", "right_ankle"])
