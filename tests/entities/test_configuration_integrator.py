"""ConfigurationIntegrator: one and two integrations, the free-flyer base on SE(3), re-synchronisation."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.discrete import ConfigurationIntegrator
from tests.conftest import Ticker

DT = 0.01


def floating_model() -> pin.Model:
    """A free-flyer base carrying two revolute joints (nq 9, nv 8)."""
    model = pin.Model()
    base = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "base")
    first = model.addJoint(base, pin.JointModelRZ(), pin.SE3.Identity(), "first")
    model.addJoint(first, pin.JointModelRY(), pin.SE3.Identity(), "second")
    return model


def start_state(model: pin.Model) -> tuple[np.ndarray, np.ndarray]:
    q0 = pin.neutral(model)
    q0[:3] = [0.1, -0.2, 1.0]
    q0[7:] = [0.3, -0.4]
    return q0, np.zeros(model.nv)


def make(mode: str, **params) -> tuple[dg.Graph, ConfigurationIntegrator, np.ndarray]:
    graph = dg.Graph(dt=DT)
    graph.add(Ticker("clock"))
    model = floating_model()
    integrator = graph.add(ConfigurationIntegrator("integrator", model=model, control_mode=mode, **params))
    q0, v0 = start_state(model)
    integrator.measured_q.set(q0)
    integrator.measured_v.set(v0)
    return graph, integrator, q0


def test_one_integration_of_a_constant_joint_velocity_is_linear():
    graph, integrator, q0 = make("velocity")
    u = np.zeros(8)
    u[6:] = [0.5, -1.0]
    integrator.command.set(u)
    graph.run(ticks=100)  # 1 s
    assert np.allclose(integrator.q(graph.t)[7:], q0[7:] + u[6:] * 1.0)
    assert np.allclose(integrator.q(graph.t)[:7], q0[:7])
    assert np.allclose(integrator.v(graph.t), u)
    # the command sent at t is the position to reach at t + 1
    assert np.allclose(integrator.joint_position(graph.t), q0[7:] + u[6:] * 1.01)
    assert np.allclose(integrator.joint_velocity(graph.t), u[6:])


def test_two_integrations_of_a_constant_acceleration_match_the_closed_form():
    graph, integrator, q0 = make("acceleration")
    a = np.zeros(8)
    a[6:] = [2.0, -3.0]
    integrator.command.set(a)
    n = 150
    graph.run(ticks=n)
    # semi-implicit Euler: v_n = n dt a, q_n = q0 + dt^2 a n (n + 1) / 2
    assert np.allclose(integrator.v(n)[6:], n * DT * a[6:])
    assert np.allclose(integrator.q(n)[7:], q0[7:] + DT**2 * a[6:] * n * (n + 1) / 2)
    # ... which is the continuous q0 + a T^2 / 2 to within dt a T / 2
    T = n * DT
    assert np.abs(integrator.q(n)[7:] - (q0[7:] + a[6:] * T**2 / 2)).max() <= DT * np.abs(a).max() * T / 2 + 1e-12


def test_the_base_follows_a_constant_twist_on_se3():
    """Body-frame forward speed s with yaw rate w: a circle of radius s / w, heading w T."""
    graph, integrator, q0 = make("velocity")
    s, w = 0.4, 0.8
    u = np.zeros(8)
    u[0], u[5] = s, w
    integrator.command.set(u)
    n = 250
    graph.run(ticks=n)
    T = n * DT
    q = integrator.q(n)
    assert np.allclose(q[:3], q0[:3] + np.array([s / w * np.sin(w * T), s / w * (1 - np.cos(w * T)), 0.0]), atol=1e-9)
    rotation = pin.Quaternion(q[3:7]).toRotationMatrix()
    assert np.allclose(rotation, pin.rpy.rpyToMatrix(0.0, 0.0, w * T), atol=1e-9)
    assert np.allclose(q[7:], q0[7:])


def test_the_base_twist_is_integrated_in_the_body_frame():
    """A pitched base moving 'forward' in its own frame climbs in the world."""
    graph, integrator, _ = make("velocity")
    q0 = integrator.measured_q.value.copy()
    pitch = 0.3
    q0[3:7] = pin.Quaternion(pin.rpy.rpyToMatrix(0.0, -pitch, 0.0)).coeffs()
    integrator.measured_q.set(q0)
    u = np.zeros(8)
    u[0] = 1.0
    integrator.command.set(u)
    graph.run(ticks=100)
    assert np.allclose(integrator.q(100)[:3] - q0[:3], [np.cos(pitch), 0.0, np.sin(pitch)])


def test_the_integration_starts_from_the_measured_state_and_resynchronises():
    graph, integrator, q0 = make("acceleration", sync_period=50)
    a = np.zeros(8)
    a[6] = 1.0
    integrator.command.set(a)
    assert np.array_equal(integrator.q(0), q0)
    graph.run(ticks=49)
    assert not np.allclose(integrator.q(49), q0)  # integrating away from the measurement
    graph.run(ticks=1)
    assert np.array_equal(integrator.q(50), q0) and np.array_equal(integrator.v(50), np.zeros(8))
    graph.run(ticks=10)
    assert integrator.v(60)[6] == pytest.approx(10 * DT)
    # the sync input: the measured state at the very tick it is true
    measured = q0.copy()
    measured[7] = -1.0
    integrator.measured_q.set(measured)
    integrator.sync.set(True)
    assert np.array_equal(integrator.q(graph.t), measured)
    graph.run(ticks=1)  # integrated from the measured state (zero velocity)
    integrator.sync.set(False)
    assert integrator.q(graph.t)[7] == pytest.approx(-1.0 + DT * DT)


def test_the_integrated_state_never_reads_the_measurement_between_synchronisations():
    graph, integrator, q0 = make("velocity")
    integrator.command.set(np.zeros(8))
    graph.run(ticks=3)
    moved = q0.copy()
    moved[0] += 1.0
    integrator.measured_q.set(moved)  # the measurement changes, the integration does not see it
    graph.run(ticks=3)
    assert np.allclose(integrator.q(graph.t), q0)


def test_the_command_does_not_close_a_loop_through_the_fed_back_state():
    """The QP reads q, v and produces the command: legal, q and v depend on states only."""
    graph, _, _ = make("velocity")
    graph.plug("integrator.v", "integrator.command")  # q -> QP -> command, here the identity
    graph.validate()


def test_a_fixed_base_robot_commands_its_whole_configuration():
    model = pin.Model()
    model.addJoint(0, pin.JointModelRX(), pin.SE3.Identity(), "only")
    graph = dg.Graph(dt=DT)
    graph.add(Ticker("clock"))
    integrator = graph.add(ConfigurationIntegrator("integrator", model=model))
    integrator.measured_q.set([0.5])
    integrator.measured_v.set([0.0])
    integrator.command.set([2.0])
    assert np.allclose(integrator.joint_position(0), [0.5 + 2.0 * DT])
    assert np.allclose(integrator.joint_velocity(0), [2.0])


def test_the_measured_state_is_computed_only_when_the_integrator_synchronises():
    """``measured_q`` and ``measured_v`` are read on demand: at tick 0 and every sync tick."""

    class Measurement(dg.Entity):
        @dg.output(shape=(9,), depends=("t",))
        def q(self, t):
            return start_state(floating_model())[0]

        @dg.output(shape=(8,), depends=("t",))
        def v(self, t):
            return np.zeros(8)

    graph, integrator, _ = make("velocity", sync_period=5)
    measurement = graph.add(Measurement("measured"))
    graph.plug("measured.q", "integrator.measured_q")
    graph.plug("measured.v", "integrator.measured_v")
    integrator.command.set(np.zeros(8))
    for _ in range(10):
        integrator.q(graph.t)
        integrator.v(graph.t)
        graph.step()
    assert (measurement.q.count, measurement.v.count) == (2, 2)  # ticks 0 and 5
