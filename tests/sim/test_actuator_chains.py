"""MuJoCo joints given an actuator chain's parameters reproduce its friction (issue 17, A.1).

The elbow of ``graphs/data/talos_actuators.yaml`` on a one-joint model (vertical axis, no
gravity, the link's inertia I_j = 0.33 of Table 3.1), driven to constant velocities by a
velocity servo that knows nothing of the chain; the friction torque MuJoCo applies is
``-(qfrc_damper + qfrc_constraint)`` (the viscous damping, and the frictionloss constraint row,
the only constraint of this model), compared with ``F_v q_dot + F_s sign(q_dot)`` at the
velocity reached. The device test checks the same file lands on TALOS's elbows.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.actuators import ActuatorModel
from dgraph.entities.actuators.chain import friction, load_chain_file
from dgraph_sim.device import MujocoDevice
from dgraph_sim.robots import apply_chains

FILE = Path(__file__).parents[2] / "graphs" / "data" / "talos_actuators.yaml"
ELBOW = "arm_left_4_joint"
XML = f"""<mujoco><option timestep="0.001" gravity="0 0 0"/><worldbody><body name="forearm">
<joint name="{ELBOW}" type="hinge" axis="0 0 1"/><inertial pos="0 0 0" mass="1" diaginertia="0.33 0.33 0.33"/>
</body></worldbody><actuator><motor joint="{ELBOW}"/></actuator></mujoco>"""
SERVO_GAIN = 300.0  # N m s/rad: ctrl = K (v* - v), independent of the chain's parameters


@pytest.fixture(scope="module")
def elbow():
    m = mujoco.MjModel.from_xml_string(XML)
    chain = load_chain_file(FILE)[ELBOW]
    apply_chains(m, {ELBOW: chain}, str(FILE))
    return m, chain


def run_at(m, target, seconds=0.5, torque=None):
    """Drive the joint from rest towards ``target`` rad/s (or with a constant ``torque``); the
    mean velocity, friction torque and motor torque over the last 0.1 s."""
    d = mujoco.MjData(m)
    d.qvel[0] = target
    log = []
    for _ in range(round(seconds / m.opt.timestep)):
        d.ctrl[0] = SERVO_GAIN * (target - d.qvel[0]) if torque is None else torque
        mujoco.mj_step(m, d)
        log.append((d.qvel[0], -(d.qfrc_damper[0] + d.qfrc_constraint[0]), d.actuator_force[0]))
    return np.mean(log[-100:], axis=0)


def test_parameters_applied(elbow):
    m, _ = elbow
    assert m.dof_armature[0] == pytest.approx(0.45)
    assert m.dof_damping[0] == pytest.approx(5.1 + 0.47)
    assert m.dof_frictionloss[0] == pytest.approx(4.0 + 0.55)
    assert m.actuator_ctrlrange[0] == pytest.approx([-17.86, 17.86])
    assert m.jnt_actfrcrange[0] == pytest.approx([-17.86, 17.86])


@pytest.mark.parametrize("target", [-2.0, -1.0, -0.3, -0.05, 0.05, 0.3, 1.0, 2.0])
def test_friction_matches_model_to_1e_9(elbow, target):
    """Measured: 5e-15 relative (the frictionloss row saturates at exactly F_s once the joint slides)."""
    m, chain = elbow
    velocity, measured, motor = run_at(m, target)
    model = friction(chain.F_v, chain.F_s, 0.0, velocity)
    assert abs(velocity) > 0.5 * abs(target)  # it moves, near the target speed (servo error: friction / K)
    assert abs(measured - model) <= 1e-9 * abs(model), (velocity, measured, model)
    # at constant velocity the motor torque is what the friction takes: an independent reading
    assert abs(motor - model) <= 1e-9 * abs(model), (velocity, motor, model)


def test_near_zero_velocity_friction_is_soft(elbow):
    """Below F_s the dry friction holds the joint, but as MuJoCo's soft constraint: the joint
    creeps (3e-3 rad/s at half F_s: a steep viscous law of about 750 N m s/rad, MuJoCo's
    default solref/solimp) and the friction force is the torque applied, not F_s sign(q_dot);
    above F_s the joint breaks away (1.2 F_s: towards 0.2 F_s / F_v = 0.16 rad/s)."""
    m, chain = elbow
    velocity, measured, _ = run_at(m, 0.0, seconds=1.0, torque=0.5 * chain.F_s)
    assert 0.0 < velocity < 1e-2
    assert measured == pytest.approx(0.5 * chain.F_s, rel=0.05)
    velocity, _, _ = run_at(m, 0.0, seconds=1.0, torque=1.2 * chain.F_s)
    assert velocity > 0.1


def test_device_applies_file_to_talos_elbows():
    g = dg.Graph(dt=0.001)
    dev = g.add(MujocoDevice("sim", actuators=str(FILE), collisions="feet"))
    m = dev.mj_model
    for name in ("arm_left_4_joint", "arm_right_4_joint"):
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        dof = m.jnt_dofadr[jid]
        assert (m.dof_armature[dof], m.dof_damping[dof], m.dof_frictionloss[dof]) == pytest.approx((0.45, 5.57, 4.55))
        assert m.jnt_actfrcrange[jid] == pytest.approx([-17.86, 17.86])
    other = m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "arm_left_3_joint")]
    assert (m.dof_armature[other], m.dof_damping[other], m.dof_frictionloss[other]) == (0.1, 0.0, 0.0)
    plain = g.add(MujocoDevice("plain", collisions="feet"))
    assert plain.mj_model.dof_damping.max() == 0.0  # the cache keeps the two models apart


def test_bad_actuator_file_is_a_located_param_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("joints:\n  arm_left_4_joint: {R_Km: 3.0, i_max: 6.0}\n  no_such_joint: {R_Km: 1.0, i_max: 1.0}\n")
    with pytest.raises(dg.ParamError, match="actuators.*no_such_joint"):
        MujocoDevice("sim", actuators=str(bad), collisions="feet")


def twin_acceleration(m, chain, q_dot: float, target: float, **params) -> float:
    """MuJoCo's acceleration of the one-joint elbow driven through ActuatorModel, whose ``tau_j*``
    comes from a rigid-body model with armature 0.1 (Pinocchio's TALOS) that knows the link and the
    joint-side friction: ``tau_j* = (I_j + 0.1) a + F_vj q_dot + F_sj sign(q_dot)``."""
    g = dg.Graph(dt=0.001)
    model = g.add(ActuatorModel("chain", joints=[ELBOW], path=str(FILE), **params))
    model.tau_desired.set([(0.33 + 0.1) * target + friction(chain.F_vj, chain.F_sj, 0.0, q_dot)])
    model.q_dot.set([q_dot])
    model.q_ddot.set([target])
    assert not model.saturated(0)[0]
    d = mujoco.MjData(m)
    d.qvel[0] = q_dot
    d.ctrl[0] = model.motor_torque(0)[0]
    mujoco.mj_forward(m, d)
    return float(d.qacc[0])


@pytest.mark.parametrize(("q_dot", "target"), [(1.0, 2.0), (-0.5, 3.0), (1.5, -4.0)])
def test_actuator_model_drives_the_mujoco_twin_exactly(elbow, q_dot, target):
    """compensate_offsets false (the twin has no offset) and controller_armature 0.1 (already in
    tau_j*): the sliding joint accelerates as commanded. The defaults (off_m compensated, the 0.1
    counted twice) miss by (0.86 + 0.1 a) / (I_j + I_m)."""
    m, chain = elbow
    fixed = twin_acceleration(m, chain, q_dot, target, compensate_offsets=False, controller_armature=0.1)
    assert fixed == pytest.approx(target, rel=1e-9)
    default = twin_acceleration(m, chain, q_dot, target)
    assert default - target == pytest.approx((0.86 + 0.1 * target) / (0.33 + 0.45), rel=1e-9)
