"""The MuJoCo TALOS is the Pinocchio TALOS: same mass matrix, same bias forces, same frames.

Velocities map as ``qvel = T(q) v`` with ``T = blkdiag(R_base, I3, P)``. Kinetic energy gives
``M_pin = Tᵀ M_mj T``. For the bias forces, ``T`` varies with time: a physical motion has
``qacc = T a + Ṫ v`` where ``Ṫ v = [R_base (ω × v_lin), 0, 0]`` (``ω = v[3:6]``, ``v_lin = v[0:3]``,
both in the base frame). Equating the power of the generalised forces (``f_pin = Tᵀ f_mj``) in
``M_mj qacc + b_mj = f_mj`` gives the identity tested here:

    nle_pin(q, v) = Tᵀ (qfrc_bias + M_mj Ṫ v)        and    rnea_pin(q, v, a) = Tᵀ (M_mj (T a + Ṫ v) + qfrc_bias).

Without the ``M_mj Ṫ v`` term the base rows differ by tens of newtons (checked too).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from dgraph.entities.robot import load_robot
from dgraph_sim.conventions import JointMap, quat_wxyz_from_xyzw, quat_xyzw_from_wxyz
from dgraph_sim.model import load
from dgraph_sim.robots import SOLE_HALF_SIZE
from tests.sim.conftest import mass_matrices


@pytest.fixture(scope="module")
def talos():
    return load("talos", "flat")


def random_states(model, n, seed=0):
    rng = np.random.default_rng(seed)
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    lower[:3], upper[:3] = -1.0, 1.0  # bounded free-flyer position
    np.random.seed(seed)  # pin.randomConfiguration draws from numpy's global generator
    pin.seed(seed)
    for _ in range(n):
        q = pin.randomConfiguration(model, lower, upper)
        yield q, rng.normal(size=model.nv), rng.normal(size=model.nv)


def tdot_v(T, v):
    out = np.zeros(T.shape[0])
    out[:3] = T[:3, :3] @ np.cross(v[3:6], v[:3])
    return out


def test_mass_matrix_and_bias_forces_match_pinocchio(talos):
    m, jm, model = talos.mj_model, talos.joint_map, talos.pin_model
    d, data = mujoco.MjData(m), model.createData()
    errors = {"M": 0.0, "nle": 0.0, "rnea": 0.0, "nle_without_tdot": 0.0}
    for q, v, a in random_states(model, 6):
        M_mujoco, M_pin, M, T = mass_matrices(talos, d, data, q, v)
        errors["M"] = max(errors["M"], np.abs(M_mujoco - M_pin).max())
        nle = pin.nonLinearEffects(model, data, q, v)
        errors["nle"] = max(errors["nle"], np.abs(T.T @ (d.qfrc_bias + M @ tdot_v(T, v)) - nle).max())
        errors["nle_without_tdot"] = max(errors["nle_without_tdot"], np.abs(T.T @ d.qfrc_bias - nle).max())
        tau = pin.rnea(model, data, q, v, a)
        f_mj = M @ (T @ a + tdot_v(T, v)) + d.qfrc_bias
        errors["rnea"] = max(errors["rnea"], np.abs(jm.generalized_force_from_qfrc(q, f_mj) - tau).max())
    assert errors["M"] < 1e-9
    assert errors["nle"] < 1e-9
    assert errors["rnea"] < 1e-9
    assert errors["nle_without_tdot"] > 1.0  # the Ṫ v term is needed: the identity is not vacuous


def test_round_trips_and_velocity_transform(talos):
    jm, model = talos.joint_map, talos.pin_model
    for q, v, _ in random_states(model, 5, seed=1):
        qpos = jm.qpos_from_q(q)
        assert qpos[3] == q[6] and np.array_equal(qpos[4:7], q[3:6])  # wxyz vs xyzw
        np.testing.assert_array_equal(jm.q_from_qpos(qpos), q)
        qvel = jm.qvel_from_v(q, v)
        np.testing.assert_allclose(qvel, jm.velocity_transform(q) @ v, atol=1e-14)
        np.testing.assert_allclose(jm.v_from_qvel(qpos, qvel), v, atol=1e-14)
        rot = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
        np.testing.assert_allclose(qvel[:3], rot @ v[:3], atol=1e-14)  # world-frame linear velocity
        np.testing.assert_array_equal(qvel[3:6], v[3:6])                # local angular velocity
        np.testing.assert_array_equal(jm.joint_positions(qpos), q[7:])
        np.testing.assert_array_equal(jm.joint_velocities(qvel), v[6:])
    xyzw = np.array([0.1, 0.2, 0.3, 0.9])
    np.testing.assert_array_equal(quat_xyzw_from_wxyz(quat_wxyz_from_xyzw(xyzw)), xyzw)


def test_actuators_follow_pinocchio_actuated_order(talos):
    m, jm, model = talos.mj_model, talos.joint_map, talos.pin_model
    assert m.nu == jm.na == 32
    tau = np.arange(32.0)
    ctrl = jm.ctrl_from_tau(tau)
    for k in range(m.nu):
        joint = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, m.actuator_trnid[k, 0])
        assert ctrl[k] == model.getJointId(joint) - 2  # actuated index of that joint
        effort = model.effortLimit[model.joints[model.getJointId(joint)].idx_v]
        np.testing.assert_array_equal(m.actuator_ctrlrange[k], [-effort, effort])
    np.testing.assert_array_equal(jm.tau_from_actuators(ctrl), tau)


def test_model_matches_the_pinocchio_model(talos):
    m, jm, model = talos.mj_model, talos.joint_map, talos.pin_model
    assert (m.nq, m.nv) == (39, 38)
    assert m.body_subtreemass[1] == pytest.approx(pin.computeTotalMass(model), abs=1e-9)
    assert m.opt.timestep == 0.001
    hinge = jm.qvel_joints
    np.testing.assert_array_equal(m.dof_armature[hinge], model.armature[6:])
    assert sorted(set(model.armature[6:])) == [0.0, 0.1]  # grippers 0, others rotor inertia * gear² = 0.1
    assert not m.dof_damping.any() and not m.dof_frictionloss.any()  # RNEA ignores them (see dgraph_sim.robots)


def test_sensor_sites_sit_at_their_pinocchio_frames(talos):
    m, jm, model = talos.mj_model, talos.joint_map, talos.pin_model
    d, data = mujoco.MjData(m), model.createData()
    sites = [talos.robot.imu, *talos.robot.force_torque.values()]
    for q, _, _ in random_states(model, 3, seed=2):
        jm.qpos_from_q(q, d.qpos)
        mujoco.mj_kinematics(m, d)
        pin.framesForwardKinematics(model, data, q)
        for site in sites:
            sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, site.site)
            frame = data.oMf[model.getFrameId(site.pin_frame)]
            np.testing.assert_allclose(d.site_xpos[sid], frame.translation, atol=1e-12)
            np.testing.assert_allclose(d.site_xmat[sid].reshape(3, 3), frame.rotation, atol=1e-12)


def test_default_configuration_puts_the_soles_on_the_floor(talos):
    m, jm, model = talos.mj_model, talos.joint_map, talos.pin_model
    q0 = talos.q0
    np.testing.assert_array_equal(q0[3:], model.referenceConfigurations["half_sitting"][3:])
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)
    soles = [data.oMf[model.getFrameId(f)].translation[2] for f in ("left_sole_link", "right_sole_link")]
    assert min(soles) == pytest.approx(0.0, abs=1e-12) and max(soles) < 1e-4
    d = mujoco.MjData(m)
    q0[2] -= 1e-3  # 1 mm into the floor: every corner of both soles (rolled by 1.7 mrad) touches
    jm.qpos_from_q(q0, d.qpos)
    mujoco.mj_forward(m, d)
    # sole boxes touch the floor (4 corners each), nothing else does
    names = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in d.contact.geom.ravel()}
    assert names == {"floor", "leg_left_6_link_sole", "leg_right_6_link_sole"}
    assert d.ncon == 8
    assert SOLE_HALF_SIZE[:2] == (0.105, 0.069)


def test_extra_joints_of_a_scene_are_ignored():
    sim = load("talos", "block")
    jm, m = sim.joint_map, sim.mj_model
    assert (m.nq, m.nv) == (46, 44)  # TALOS + the block's free joint
    q = sim.q0
    qpos = np.full(m.nq, 7.0)
    jm.qpos_from_q(q, qpos)
    np.testing.assert_array_equal(jm.q_from_qpos(qpos), q)
    assert np.count_nonzero(qpos == 7.0) == 7  # the block's free joint is untouched


def test_joint_map_refuses_mismatched_models(talos):
    with pytest.raises(ValueError, match="free joint on 'base_link'"):  # TALOS's joints on a fixed base
        JointMap(pin.buildModelFromUrdf(load_robot("talos").urdf), talos.mj_model)
    with pytest.raises(ValueError, match="not in the MuJoCo model"):  # a fixed-base arm: its joints are not TALOS's
        JointMap(pin.buildSampleModelManipulator(), talos.mj_model)
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name="b").add_freejoint()
    spec.body("b").add_geom(size=[0.1, 0, 0])
    with pytest.raises(ValueError, match="not in the MuJoCo model"):
        JointMap(talos.pin_model, spec.compile())
