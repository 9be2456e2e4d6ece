"""A robot described for MuJoCo by an MJCF file while Pinocchio keeps the URDF (``MujocoDevice(mjcf=...)``).

The MJCFs are written here from our own URDF-built specs (``MjSpec.to_xml``, meshes by absolute
path), with a marker site so that a test can see the MJCF, not the URDF, was simulated; each
error path edits one thing of that file.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph_sim.device import MujocoDevice
from dgraph_sim.model import load
from dgraph_sim.robots import MjcfWarning, compare_dynamics, robot_spec

ROOT = Path(__file__).resolve().parents[2]
TARGET = np.array([0.45, 0.2, 0.3])
MARKER = "mjcf_marker"


def write_mjcf(path: Path, edit: Callable[[mujoco.MjSpec], None] | None = None, robot: str = "panda",
               marker_body: str = "panda_hand") -> str:
    """Write the MJCF of our spec of ``robot`` (with a marker site on ``marker_body``), edited by ``edit``."""
    spec, _ = robot_spec(robot)
    spec.body(marker_body).add_site(name=MARKER, size=[0.01, 0.01, 0.01])
    if edit is not None:
        edit(spec)
    path.write_text(spec.to_xml())
    return str(path)


def has_marker(device: MujocoDevice) -> bool:
    return mujoco.mj_name2id(device.mj_model, mujoco.mjtObj.mjOBJ_SITE, MARKER) >= 0


@pytest.fixture(scope="module")
def panda_xml(tmp_path_factory) -> str:
    return write_mjcf(tmp_path_factory.mktemp("mjcf") / "panda.xml")


@pytest.mark.sim
def test_the_panda_reach_graph_reaches_its_target_with_the_mjcf(panda_xml, tmp_path):
    text = Path(panda_xml).read_text()
    assert '<actuator>' in text and "/meshes/" in text and 'file="/' in text  # its motors, absolute mesh paths
    graph = dg.load(str(ROOT / "graphs" / "panda_reach.yaml"), {"device.mjcf": panda_xml,
                                                                "recorder.npz_path": str(tmp_path / "reach.npz"),
                                                                "recorder.rrd_path": str(tmp_path / "reach.rrd")})
    device = graph["device"]
    assert device.mjcf == panda_xml and has_marker(device)  # MuJoCo runs the MJCF
    with graph:
        graph.run(duration=graph.duration, progress=False)
    rec = graph["recorder"].data()
    model = graph["robot"].pin_model
    data, frame = model.createData(), model.getFrameId("panda_hand_tcp")
    position = []
    for q in rec["device.q"]:
        pin.framesForwardKinematics(model, data, q)
        position.append(data.oMf[frame].translation.copy())
    error = np.linalg.norm(np.array(position) - TARGET, axis=1)
    assert error[0] > 0.28                                       # it starts 0.29 m away
    assert error[rec["time"] >= 2.3].max() < 1e-3                # within a millimetre, as from the URDF
    assert not rec["solver.status"].any() and np.isfinite(rec["device.joint_torque"]).all()


def test_the_written_mjcf_agrees_with_pinocchio_and_the_check_measures(panda_xml, tmp_path):
    sim = load("panda", mjcf=panda_xml)
    same = compare_dynamics(sim.mj_model, sim.joint_map, sim.pin_model, sim.q0)
    assert set(same) == {"link_mass", "mass_matrix", "gravity"} and max(same.values()) < 1e-4  # XML round trip
    heavier = write_mjcf(tmp_path / "heavy.xml", lambda s: setattr(s.body("panda_link5"), "mass",
                                                                    1.2 * s.body("panda_link5").mass))
    sim = load("panda", mjcf=heavier, mjcf_tolerance=0.5)  # accepted with a loose tolerance: measured
    measured = compare_dynamics(sim.mj_model, sim.joint_map, sim.pin_model, sim.q0, tolerance=1.0)
    assert measured["link_mass"] == pytest.approx(0.2 / 1.2, rel=1e-4)  # |1.2 m - m| / 1.2 m
    assert measured["mass_matrix"] > 0.01 and measured["gravity"] > 0.01


def test_a_body_mass_changed_by_20_percent_is_refused(tmp_path):
    path = write_mjcf(tmp_path / "heavy.xml",
                      lambda s: setattr(s.body("panda_link5"), "mass", 1.2 * s.body("panda_link5").mass))
    with pytest.raises(dg.ParamError, match=r"arm: parameter 'mjcf': .*heavy.xml and the URDF of the Pinocchio "
                                            r"model disagree beyond the relative tolerance 0.01 .*joint "
                                            r"'panda_joint5' weighs 1.47\d* kg in the MJCF, 1.22\d* kg in the URDF"
                       ) as info:
        MujocoDevice("arm", model="panda", mjcf=path)
    assert info.value.entity == "arm"
    assert "mass matrix entry" in str(info.value) and "gravity torque" in str(info.value)


def _rename_joint(spec: mujoco.MjSpec) -> None:
    spec.joint("panda_joint4").name = "elbow"
    spec.actuator("panda_joint4").target = "elbow"


def _remove_joint(spec: mujoco.MjSpec) -> None:
    spec.delete(spec.actuator("panda_finger_joint2"))
    spec.delete(spec.joint("panda_finger_joint2"))


def _slide_joint(spec: mujoco.MjSpec) -> None:
    spec.joint("panda_joint4").type = mujoco.mjtJoint.mjJNT_SLIDE


def _position_servo(spec: mujoco.MjSpec) -> None:
    spec.actuator("panda_joint2").set_to_position(kp=100.0)


def _gear(spec: mujoco.MjSpec) -> None:
    spec.actuator("panda_joint6").gear = [2.0, 0.0, 0.0, 0.0, 0.0, 0.0]


def _no_motor(spec: mujoco.MjSpec) -> None:
    spec.delete(spec.actuator("panda_joint7"))


def _free_base(spec: mujoco.MjSpec) -> None:
    spec.body("panda_link0").add_freejoint(name="base")


def _floor(spec: mujoco.MjSpec) -> None:
    spec.worldbody.add_geom(name="my_floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1.0, 1.0, 0.1])


@pytest.mark.parametrize(("edit", "message"), [
    (_rename_joint, r"joint\(s\) \['panda_joint4'\] of the Pinocchio model are not in the MJCF; joint\(s\) "
                    r"\['elbow'\] of the MJCF are not in the Pinocchio model"),
    (_remove_joint, r"joint\(s\) \['panda_finger_joint2'\] of the Pinocchio model are not in the MJCF \(9 actuated "
                    r"joints in the Pinocchio model, 8 in the MJCF"),
    (_slide_joint, r"joint 'panda_joint4' is a slide joint in the MJCF but a hinge joint in the Pinocchio model"),
    (_position_servo, r"actuator 'panda_joint2' on joint 'panda_joint2' is a servo \(biased\).*give one motor"),
    (_gear, r"actuator 'panda_joint6' on joint 'panda_joint6' has gear \[2.0, 0.0"),
    (_no_motor, r"joint\(s\) \['panda_joint7'\] have no actuator \(8 actuators for 9 actuated joints\)"),
    (_free_base, r"joint 'base': the Pinocchio model has a fixed base but the MJCF a free joint on body 'panda_link0'"),
    (_floor, r"the worldbody holds geoms \['my_floor'\]: the MJCF describes the robot only"),
])
def test_an_mjcf_of_another_robot_is_refused_naming_the_entity_the_parameter_and_the_joint(tmp_path, edit, message):
    path = write_mjcf(tmp_path / "edited.xml", edit)
    with pytest.raises(dg.ParamError, match=r"^arm: parameter 'mjcf': .*edited.xml: " + message) as info:
        MujocoDevice("arm", model="panda", mjcf=path)
    assert info.value.entity == "arm"


def test_without_actuators_the_device_adds_motors_with_the_urdf_effort_limits(tmp_path):
    def strip(spec: mujoco.MjSpec) -> None:
        for actuator in list(spec.actuators):
            spec.delete(actuator)

    arm = MujocoDevice("arm", model="panda", mjcf=write_mjcf(tmp_path / "bare.xml", strip))
    m, jm = arm.mj_model, arm.joint_map
    assert has_marker(arm) and m.nu == 9 and (m.actuator_gear[:, 0] == 1.0).all()
    np.testing.assert_array_equal(m.actuator_ctrlrange[jm.ctrl_index, 1], arm.sim.pin_model.effortLimit)


def test_a_motor_range_other_than_the_urdf_effort_limit_is_kept_and_warned_about(tmp_path):
    def weaker(spec: mujoco.MjSpec) -> None:
        spec.actuator("panda_joint1").ctrlrange = [-40.0, 40.0]

    with pytest.warns(MjcfWarning, match=r"actuator 'panda_joint1' on joint 'panda_joint1' has ctrlrange ±40, the "
                                         r"URDF effort limit is ±87"):
        arm = MujocoDevice("arm", model="panda", mjcf=write_mjcf(tmp_path / "weaker.xml", weaker))
    assert arm.mj_model.actuator("panda_joint1").ctrlrange.tolist() == [-40.0, 40.0]


def test_a_relative_mjcf_in_a_graph_file_is_read_from_the_files_folder(panda_xml, tmp_path):
    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "arm.xml").write_text(Path(panda_xml).read_text())
    graph_file = tmp_path / "arm.yaml"
    graph_file.write_text("name: arm\ndt: 0.001\nentities:\n"
                          "  device: {type: MujocoDevice, params: {model: panda, mjcf: robots/arm.xml}}\n")
    graph = dg.load(str(graph_file))
    assert graph["device"].mjcf == str(tmp_path / "robots" / "arm.xml") and has_marker(graph["device"])
    graph_file.write_text(graph_file.read_text().replace("robots/arm.xml", "nowhere.xml"))
    with pytest.raises(dg.GraphFileError, match=r"arm.yaml:4 .*cannot read data file .*nowhere.xml"):
        dg.load(str(graph_file))


def test_collisions_feet_is_refused_with_an_mjcf(panda_xml):
    with pytest.raises(dg.ParamError, match=r"arm: parameter 'collisions': 'feet' applies to a robot built from its "
                                            r"URDF"):
        MujocoDevice("arm", model="panda", mjcf=panda_xml, collisions="feet")


def _talos_without_sensors(spec: mujoco.MjSpec) -> None:
    for sensor in list(spec.sensors):
        spec.delete(sensor)
    for site in list(spec.sites):
        if site.name != MARKER:
            spec.delete(site)


def test_talos_from_an_mjcf_has_its_free_joint_and_its_sensors_where_the_urdf_puts_them(tmp_path):
    path = write_mjcf(tmp_path / "talos.xml", _talos_without_sensors, robot="talos", marker_body="base_link")
    g = dg.Graph(dt=0.001)
    talos = g.add(MujocoDevice("talos", mjcf=path))
    reference = g.add(MujocoDevice("reference"))  # TALOS from the URDF
    assert has_marker(talos) and not has_marker(reference)
    assert talos.joint_map.floating_base and talos.na == 32
    assert {"imu_orientation", "ft_left_ankle", "ft_right_wrist", "fallen"} <= set(talos.ports)
    for device in (talos, reference):
        device.control.set(np.zeros(device.na))
    g.run(ticks=20)  # limp: the same fall has begun in both
    assert talos.q.value[2] < talos.sim.q0[2] - 1e-4
    for state in ("q", "imu_orientation", "imu_linear_acceleration", "ft_left_ankle", "ft_right_wrist"):
        np.testing.assert_allclose(getattr(talos, state).value, getattr(reference, state).value, atol=1e-3,
                                   err_msg=state)

    def no_free_joint(spec: mujoco.MjSpec) -> None:
        _talos_without_sensors(spec)
        spec.delete(spec.joint("root_joint"))

    fixed = write_mjcf(tmp_path / "fixed.xml", no_free_joint, robot="talos", marker_body="base_link")
    with pytest.raises(dg.ParamError, match=r"talos: parameter 'mjcf': .*joint 'root_joint': the Pinocchio model has "
                                            r"a free-flyer root but the MJCF has no free joint") as info:
        MujocoDevice("talos", mjcf=fixed)
    assert info.value.entity == "talos"
