"""Any robot: example-robot-data names and URDF paths for the MuJoCo device and the robot model.

A fixed-base arm (Panda, UR5) is the same rigid-body system in MuJoCo as in Pinocchio (mass
matrix and bias forces), has torque motors with the URDF effort limits, its SRDF's reference
posture, and none of TALOS's sensors or fall detection. A bad robot is refused naming the
entity and the parameter.
"""

from __future__ import annotations

import os
import shutil

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.robot import RobotModel, load_model, load_robot
from dgraph_sim.device import MujocoDevice
from dgraph_sim.model import load
from tests.sim.conftest import mass_matrices

TALOS_ONLY = ("imu_orientation", "imu_angular_velocity", "imu_linear_acceleration", "ft_left_ankle",
              "ft_right_ankle", "ft_left_wrist", "ft_right_wrist", "fallen")


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_fixed_base_arm_is_the_pinocchio_model(name):
    sim = load(name)
    m, jm, model = sim.mj_model, sim.joint_map, sim.pin_model
    assert not jm.floating_base and (jm.nq, jm.nv, jm.na) == (model.nq, model.nv, model.nv)
    assert m.nu == model.nv and not m.dof_damping.any() and not m.dof_frictionloss.any() and m.neq == 0
    np.testing.assert_array_equal(m.actuator_ctrlrange[jm.ctrl_index, 1], model.effortLimit)
    np.testing.assert_array_equal(m.dof_armature[jm.qvel_joints], model.armature)
    d, data = mujoco.MjData(m), model.createData()
    rng = np.random.default_rng(0)
    for _ in range(3):
        q = pin.randomConfiguration(model)
        v = rng.normal(size=model.nv)
        M_mujoco, M_pin, _, _ = mass_matrices(sim, d, data, q, v)
        np.testing.assert_allclose(M_mujoco, M_pin, atol=1e-9)
        np.testing.assert_allclose(jm.generalized_force_from_qfrc(q, d.qfrc_bias.copy()),
                                   pin.nonLinearEffects(model, data, q, v), atol=1e-9)


def test_default_configurations_come_from_the_srdf_or_the_neutral_one_within_the_limits():
    np.testing.assert_array_equal(load("panda").q0, load_robot("panda").q0)  # the SRDF's "default"
    np.testing.assert_array_equal(load("ur5").q0, np.zeros(6))
    panda = load(load_robot("panda").urdf)  # by path: no SRDF, the neutral posture clipped into the limits
    model = panda.pin_model
    assert (panda.q0 >= model.lowerPositionLimit).all() and (panda.q0 <= model.upperPositionLimit).all()
    assert panda.q0[3] == model.upperPositionLimit[3] < 0.0  # joint 4 cannot be at 0


def test_an_arm_device_has_no_talos_sensors_nor_fall_detection():
    g = dg.Graph(dt=0.001)
    arm = g.add(MujocoDevice("arm", model="panda"))
    talos = g.add(MujocoDevice("talos"))
    assert not set(TALOS_ONLY) & set(arm.ports)
    assert set(TALOS_ONLY) <= set(talos.ports)
    np.testing.assert_array_equal(arm.q.value, load_robot("panda").q0)
    arm.control.set(pin.computeGeneralizedGravity(arm.sim.pin_model, arm.sim.pin_model.createData(), arm.q.value))
    talos.control.set(np.zeros(talos.na))
    g.run(ticks=50)
    np.testing.assert_allclose(arm.q.value, load_robot("panda").q0, atol=1e-4)  # gravity compensated: still


@pytest.mark.parametrize(("params", "fragment"), [
    ({"fall_height": 0.5}, "parameter 'fall_height': panda has a fixed base"),
    ({"stop_on_fall": True}, "parameter 'stop_on_fall': panda has no fall detection"),
    ({"control_mode": "position"}, "parameter 'kp': position mode on panda needs kp and kd"),
])
def test_talos_options_are_refused_on_an_arm(params, fragment):
    with pytest.raises(dg.ParamError, match=fragment) as info:
        MujocoDevice("arm", model="panda", **params)
    assert info.value.entity == "arm"


def test_an_arm_in_position_mode_with_gains_holds_a_target():
    g = dg.Graph(dt=0.001)
    dev = g.add(MujocoDevice("arm", model="ur5", control_mode="position", kp=500.0, kd=20.0))
    target = np.array([0.3, -1.0, 1.2, -0.5, 0.4, 0.2])
    dev.control.set(target)
    g.run(ticks=4000)  # settled (|v| < 1e-4)
    model = dev.sim.pin_model
    gravity = pin.computeGeneralizedGravity(model, model.createData(), dev.q.value)
    # the PD's steady state: kp (q* - q) = g(q), no feed-forward
    np.testing.assert_allclose(500.0 * (target - dev.q.value), gravity, atol=0.05)
    assert abs(dev.q.value[1] - target[1]) > 0.05  # gravity does bend the shoulder: the check is not vacuous


@pytest.mark.parametrize("entity", [MujocoDevice, RobotModel])
def test_an_unknown_robot_names_the_entity_the_parameter_and_the_nearest_names(entity):
    with pytest.raises(dg.ParamError, match=r"robot: cannot load robot model 'pandaa' \(parameter 'model'\): "
                                            r"unknown robot; did you mean 'panda'") as info:
        entity("robot", model="pandaa")
    assert info.value.entity == "robot"
    with pytest.raises(dg.ParamError, match=r"robot: cannot load robot model '/nowhere/arm.urdf' \(parameter "
                                            r"'model'\): no such URDF file"):
        entity("robot", model="/nowhere/arm.urdf")


def test_a_users_urdf_finds_its_meshes_relative_or_through_package_dirs(tmp_path):
    source = load_robot("panda").urdf
    share = os.path.realpath(os.path.join(os.path.dirname(source), "..", "..", "..", ".."))
    assert os.path.isdir(os.path.join(share, "example-robot-data", "robots", "panda_description"))
    copied = tmp_path / "panda.urdf"
    shutil.copy(source, copied)  # its meshes are package://example-robot-data/robots/...: not under tmp
    with pytest.raises(dg.ParamError, match="arm: parameter 'model': cannot build .*package_dirs"):
        MujocoDevice("arm", model=str(copied))
    with_dirs = MujocoDevice("arm", model=str(copied), package_dirs=[share])
    assert with_dirs.na == 9
    meshes = os.path.join(os.path.dirname(source), "..", "meshes")
    (tmp_path / "relative").mkdir()
    os.symlink(os.path.realpath(meshes), tmp_path / "relative" / "meshes")
    relative = tmp_path / "relative" / "panda.urdf"
    relative.write_text(copied.read_text().replace("package://example-robot-data/robots/panda_description/", ""))
    assert MujocoDevice("arm", model=str(relative)).na == 9
    assert load_model(str(relative)).nq == 9


def test_models_and_meshes_are_loaded_once():
    assert load("panda") is load("panda")
    path = load_robot("panda").urdf
    assert load_model(path) is load_model(path)
    assert load_model("panda") is load_robot("panda").model


def test_an_edited_urdf_gives_a_new_simulation_model(tmp_path):
    share = os.path.realpath(os.path.join(os.path.dirname(load_robot("panda").urdf), "..", "..", "..", ".."))
    arm = tmp_path / "arm.urdf"
    shutil.copy(load_robot("panda").urdf, arm)
    first = load(str(arm), package_dirs=(share,))
    link1 = mujoco.mj_name2id(first.mj_model, mujoco.mjtObj.mjOBJ_BODY, "panda_link1")
    assert first.mj_model.body_mass[link1] == pytest.approx(4.970684)
    assert load(str(arm), package_dirs=(share,)) is first
    text = arm.read_text()
    before = arm.stat().st_mtime_ns
    arm.write_text(text.replace('<mass value="4.970684"', '<mass value="7.970684"'))  # same size
    os.utime(arm, ns=(before + 1_000_000_000, before + 1_000_000_000))  # saved a second later
    edited = load(str(arm), package_dirs=(share,))
    assert edited.mj_model.body_mass[link1] == pytest.approx(7.970684)
    assert edited.pin_model.inertias[1].mass == pytest.approx(7.970684)
