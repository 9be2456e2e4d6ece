"""ZmpEstimator and DcmAdmittance: the ZMP of known wrenches, the direction of the corrections,
the closed loop on a linear inverted pendulum, and the measured ZMP of TALOS standing in MuJoCo."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.operators import Constant
from dgraph.entities.robot import RobotModel
from dgraph.entities.stabilizers import DcmAdmittance, ZmpEstimator, lipm_zmp, natural_frequency, zero_moment_point

FOOT_MASS = 2.0
FOOT_LEVER = np.array([0.03, 0.0, -0.05])


def two_feet_model() -> pin.Model:
    """Two 'ankles' (revolute joints on the universe) at (0, ±0.1, 0.1), the right one turned 90°
    about z; each carries a 2 kg foot whose CoM is 3 cm ahead of and 5 cm under the joint."""
    model = pin.Model()
    turned = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, np.pi / 2), np.array([0.0, -0.1, 0.1]))
    for name, placement in (("left", pin.SE3(np.eye(3), np.array([0.0, 0.1, 0.1]))), ("right", turned)):
        joint = model.addJoint(0, pin.JointModelRZ(), placement, f"{name}_ankle")
        model.appendBodyToJoint(joint, pin.Inertia(FOOT_MASS, FOOT_LEVER, np.eye(3) * 1e-3), pin.SE3.Identity())
        model.addJointFrame(joint)
    return model


def zmp_graph(**params) -> tuple[dg.Graph, ZmpEstimator]:
    graph = dg.Graph(dt=0.001)
    robot = graph.add(RobotModel("robot", model=two_feet_model()))
    robot.q.set(np.zeros(2))
    robot.v.set(np.zeros(2))
    zmp = graph.add(ZmpEstimator("zmp", sensors=["left", "right"], frames=["left_ankle", "right_ankle"], **params))
    graph.plug("robot.state", "zmp.robot")
    return graph, zmp


def test_the_zmp_of_vertical_forces_is_their_weighted_mean():
    _, zmp = zmp_graph(compensate_feet=False)
    zmp.left.set([0.0, 0.0, 400.0, 0.0, 0.0, 0.0])
    zmp.right.set([0.0, 0.0, 600.0, 0.0, 0.0, 0.0])
    assert np.allclose(zmp.zmp(0), [0.0, (400 * 0.1 - 600 * 0.1) / 1000, 0.0])
    assert zmp.normal_force(0) == pytest.approx(1000.0)


def test_a_sensor_torque_and_a_horizontal_force_move_the_zmp_by_hand_computation():
    """Right sensor turned 90° about z: its x axis is the world y axis. A sensor torque of 12 N m
    about its x axis is 12 N m about world y, moving the ZMP by -12 / 1000 in x. A horizontal
    force of 50 N along world x at the left ankle, 0.1 m above the ground, meets the ground
    0.1 * 50 / 400 behind its point of application: that force alone moves the ZMP by
    -0.1 * 50 / 1000 in x."""
    _, zmp = zmp_graph(compensate_feet=False)
    zmp.left.set([50.0, 0.0, 400.0, 0.0, 0.0, 0.0])
    zmp.right.set([0.0, 0.0, 600.0, 12.0, 0.0, 0.0])
    assert np.allclose(zmp.zmp(0), [-12 / 1000 - 0.1 * 50 / 1000, -0.02, 0.0])
    _, high = zmp_graph(compensate_feet=False, height=0.1)  # on the plane of the ankles
    high.left.set([50.0, 0.0, 400.0, 0.0, 0.0, 0.0])
    high.right.set([0.0, 0.0, 600.0, 12.0, 0.0, 0.0])
    assert np.allclose(high.zmp(0), [-12 / 1000, -0.02, 0.1])


def test_the_feet_weights_are_added_at_their_centres_of_mass():
    _, zmp = zmp_graph()
    zmp.left.set([0.0, 0.0, 400.0, 0.0, 0.0, 0.0])
    zmp.right.set([0.0, 0.0, 600.0, 0.0, 0.0, 0.0])
    weight = FOOT_MASS * 9.81
    # left foot CoM at (0.03, 0.1), right foot (turned 90°) at (0, -0.1 + 0.03)
    expected = np.array([400 * 0.0 + 600 * 0.0 + weight * 0.03,
                         400 * 0.1 - 600 * 0.1 + weight * 0.1 + weight * (-0.07)]) / (1000 + 2 * weight)
    assert np.allclose(zmp.zmp(0)[:2], expected)
    assert zmp.normal_force(0) == pytest.approx(1000 + 2 * weight)


def test_without_contact_the_zmp_is_between_the_sensors():
    _, zmp = zmp_graph(compensate_feet=False)
    zmp.left.set(np.zeros(6))
    zmp.right.set(np.zeros(6))
    assert np.allclose(zmp.zmp(0), [0.0, 0.0, 0.0])


def test_zero_moment_point_is_where_the_moment_vanishes():
    rng = np.random.default_rng(0)
    for _ in range(20):
        wrench = np.r_[rng.normal(size=2) * 50, 800 + rng.uniform(0, 200), rng.normal(size=3) * 20]
        height = rng.uniform(-0.1, 0.1)
        p = zero_moment_point(wrench, height)
        moment = wrench[3:] - np.cross(p, wrench[:3])
        assert p[2] == height and np.allclose(moment[:2], 0.0, atol=1e-9)


# -- DCM control and CoM admittance ---------------------------------------------------------
HEIGHT = 0.88


def stabilizer(**inputs) -> DcmAdmittance:
    entity = DcmAdmittance("stabilizer")
    entity.reference_position.set([0.0, 0.0, HEIGHT])
    entity.com.set([0.0, 0.0, HEIGHT])
    entity.com_velocity.set(np.zeros(3))
    entity.zmp.set(np.zeros(3))
    for name, value in inputs.items():
        entity.signal(name).set(value)
    return entity


def test_a_dcm_ahead_of_its_reference_moves_the_desired_zmp_ahead_further():
    omega = natural_frequency(HEIGHT)
    entity = stabilizer(com_velocity=[0.1, -0.05, 0.0])  # DCM 0.1 / omega ahead, 0.05 / omega right
    dcm = np.array([0.1, -0.05]) / omega
    assert np.allclose(entity.dcm(0), dcm)
    # p* = (1 + kp / omega) xi + (kz / omega)(0 - p): with p = 0
    assert np.allclose(entity.desired_zmp(0)[:2], (1 + 8.0 / omega) * dcm)


def test_the_admittance_moves_the_com_towards_the_zmp_error():
    """Eq. 2.31: a measured ZMP ahead of the desired one accelerates the CoM reference forwards
    (a position-controlled robot then moves its ZMP back: p = c - c_ddot / omega^2)."""
    entity = stabilizer(zmp=[0.02, -0.01, 0.0], kz_dcm=0.0)
    assert np.allclose(entity.correction(0), 12.0 * np.array([0.02, -0.01]))
    assert np.allclose(entity.com_acceleration_reference(0), [0.24, -0.12, 0.0])


def test_the_reference_zmp_and_dcm_follow_the_lipm():
    omega = natural_frequency(HEIGHT)
    entity = stabilizer(reference_velocity=[0.0, 0.2, 0.0], reference_acceleration=[0.0, -0.5, 0.0])
    assert np.allclose(entity.zmp_reference(0), [0.0, 0.5 / omega**2, 0.0])
    assert np.allclose(entity.dcm_reference(0), [0.0, 0.2 / omega])
    assert np.allclose(lipm_zmp(np.array([[0.0, 0.0, HEIGHT]]), np.array([[0.0, -0.5, 0.0]]), [omega]),
                       [[0.0, 0.5 / omega**2]])


def test_on_a_tread_omega_and_the_zmps_are_counted_from_the_ground_height_input():
    """Six 10 cm stairs up, the plan's CoM 0.88 m above the tread at 0.6 m: plugged from the
    pattern's plane, omega is the plan's, and the reference and desired ZMPs lie on the tread;
    unplugged, the height parameter (0) gives the flat ground's."""
    tread = 0.6
    entity = stabilizer(reference_position=[0.0, 0.0, tread + HEIGHT], com=[0.0, 0.0, tread + HEIGHT],
                        reference_acceleration=[0.3, 0.0, 0.0])
    assert entity.omega(0) == pytest.approx(natural_frequency(tread + HEIGHT))  # from z = 0: 2.58 rad/s
    entity.ground_height.set(tread)
    omega = natural_frequency(HEIGHT)
    assert entity.omega(1) == pytest.approx(omega)  # 3.34 rad/s
    assert np.allclose(entity.zmp_reference(1), [-0.3 / omega**2, 0.0, tread])
    assert entity.desired_zmp(1)[2] == tread
    assert DcmAdmittance("other", height=0.2).ground_height(0) == 0.2


class PositionControlledLipm(dg.Device):
    """A linear inverted pendulum ``c_ddot = omega^2 (c - p) + f / m`` (horizontal), balanced by a
    position controller: it tracks the CoM reference with ``c_ddot_d = c_ddot* + kp (c* - c) +
    kd (c_dot* - c_dot)`` and produces the ZMP that this needs in its model, ``c - c_ddot_d /
    omega^2``, through a first-order lag (servo and structure). ``push`` (m/s^2, x) starts at 1 s
    and is unknown to the controller. Its ZMP is what the force sensors measure."""

    push = dg.Param(0.0, kind="float")
    lag = dg.Param(0.02, kind="float")
    com_reference = dg.Input(shape=(3,))
    com_velocity_reference = dg.Input(shape=(3,))
    com_acceleration_reference = dg.Input(shape=(3,))
    com = dg.State(shape=(3,))
    com_velocity = dg.State(shape=(3,))
    zmp = dg.State(shape=(3,))

    def reset(self) -> None:
        self.com.set(np.array([0.0, 0.0, HEIGHT]), 0)
        self.com_velocity.set(np.zeros(3), 0)
        self.zmp.set(np.zeros(3), 0)

    def prepare_state(self, t: int) -> None:
        c, c_dot, p = self.com(t), self.com_velocity(t), self.zmp(t)
        omega2 = natural_frequency(HEIGHT) ** 2
        wanted = (self.com_acceleration_reference(t) + 100.0 * (self.com_reference(t) - c)
                  + 20.0 * (self.com_velocity_reference(t) - c_dot))
        p_next = p + self.dt / self.lag * (c - wanted / omega2 - p)
        push = np.array([self.push if t * self.dt >= 1.0 else 0.0, 0.0, 0.0])
        c_ddot = omega2 * (c - p) + push
        c_ddot[2] = p_next[2] = 0.0
        self.com_velocity.stage(c_dot + self.dt * c_ddot)
        self.com.stage(c + self.dt * (c_dot + self.dt * c_ddot))
        self.zmp.stage(p_next)

    def commit_state(self, t_next: int) -> None:
        self.com.commit(t_next)
        self.com_velocity.commit(t_next)
        self.zmp.commit(t_next)


def pendulum_run(seconds: float, stabilised: bool = True, plugged: dict[str, float] | None = None,
                 **gains) -> np.ndarray:
    """CoM x of every tick of a pushed pendulum (0.2 m/s^2, i.e. 18 N on TALOS); ``gains`` are
    set, ``plugged`` ones come from Constant entities."""
    graph = dg.Graph(dt=0.001)
    plant = graph.add(PositionControlledLipm("plant", push=0.2))
    entity = graph.add(stabilizer(**gains))
    for name, value in (plugged or {}).items():
        graph.add(Constant(f"{name}_source", value=value))
        graph.plug(f"{name}_source.output", f"stabilizer.{name}")
    for name in ("com", "com_velocity", "zmp"):
        graph.plug(f"plant.{name}", f"stabilizer.{name}")
    for name in ("com_reference", "com_velocity_reference", "com_acceleration_reference"):
        if stabilised:
            graph.plug(f"stabilizer.{name}", f"plant.{name}")
        else:
            plant.signal(name).set(entity.reference_position.value if name == "com_reference" else np.zeros(3))
    com = []
    for _ in range(round(seconds / graph.dt)):
        graph.step()
        com.append(plant.com(graph.t)[0])
    return np.array(com)


def test_the_stabilised_pendulum_absorbs_a_push_and_returns_to_its_reference():
    """The admittance yields to the push (the CoM moves with it), the integral of Eq. 2.30 then
    brings the DCM, hence the CoM, back; the position controller alone keeps f / (m kp) = 2 mm."""
    com = pendulum_run(30.0)
    assert np.isfinite(com).all() and np.abs(com).max() < 0.02
    assert abs(com[-1]) < 0.5e-3
    assert abs(pendulum_run(30.0, stabilised=False)[-1] - 0.2 / 100.0) < 1e-5


def test_a_reversed_admittance_makes_the_pendulum_diverge():
    """The sign of Eq. 2.31 is the one implemented: a negative gain, refused as a constant (the
    gains are >= 0 where they are set), diverges when a plug feeds it."""
    with pytest.raises(dg.SpecError, match=r"stabilizer\.kp_admittance: must be >= 0, got -12\.0"):
        stabilizer(kp_admittance=-12.0)
    com = pendulum_run(3.0, plugged={"kp_admittance": -12.0})
    assert np.abs(com[-1]) > 1.0


def test_talos_standing_in_mujoco_has_its_zmp_under_its_com():
    """The ankle sensors' frames and sign (dgraph_sim.device): TALOS held by stiff joint servos at
    half-sitting settles with its measured ZMP under its CoM, carrying its weight."""
    from dgraph_sim.device import MujocoDevice

    graph = dg.Graph(dt=0.001)
    grippers = [21, 29]
    kp, kd = np.full(32, 10000.0), np.full(32, 100.0)
    kp[grippers], kd[grippers] = 100.0, 1.0
    device = graph.add(MujocoDevice("device", control_mode="position", kp=kp, kd=kd))
    device.control.set(device.q.value[7:].copy())
    robot = graph.add(RobotModel("robot"))
    zmp = graph.add(ZmpEstimator("zmp"))
    graph.plug("device.q", "robot.q")
    graph.plug("device.v", "robot.v")
    graph.plug("robot.state", "zmp.robot")
    graph.plug("device.ft_left_ankle", "zmp.ft_left_ankle")
    graph.plug("device.ft_right_ankle", "zmp.ft_right_ankle")
    graph.run(ticks=3000)
    t = graph.t
    assert np.abs(zmp.zmp(t)[:2] - robot.com_position(t)[:2]).max() < 2e-3
    weight = robot.state(t).total_mass * 9.81
    assert zmp.normal_force(t) == pytest.approx(weight, rel=2e-3)
    assert zmp.normal_force(t) == pytest.approx(device.contact_force_total(t)[2], rel=1e-3)
    assert np.abs(device.encoder_velocity(t)).max() < 0.01  # settled, no joint chattering
