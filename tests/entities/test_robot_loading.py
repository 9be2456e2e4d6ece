"""describe_robot: an example-robot-data model without its meshes, the same as the loader's."""

import os
import shutil

import example_robot_data as erd
import numpy as np
import pinocchio as pin
import pytest

from dgraph.entities.robot.loading import describe_robot, load_model, load_robot

MODEL_ARRAYS = ("armature", "rotorInertia", "rotorGearRatio", "effortLimit", "velocityLimit",
                "lowerPositionLimit", "upperPositionLimit")


@pytest.mark.parametrize("name", ["talos", "panda", "ur5", "talos_legs"])
def test_the_model_without_meshes_is_the_loaders_model(name):
    described, loaded = describe_robot(name), erd.load(name)
    model, reference = described.model, loaded.model
    assert list(model.names) == list(reference.names) and model.nq == reference.nq
    for field in MODEL_ARRAYS:  # the SRDF's rotor parameters (armature) and the free flyer's bounds
        np.testing.assert_array_equal(getattr(model, field), getattr(reference, field), err_msg=field)
    assert [c.key() for c in model.referenceConfigurations] == [c.key() for c in reference.referenceConfigurations]
    np.testing.assert_array_equal(described.q0, loaded.q0)
    assert described.urdf == loaded.urdf
    q = pin.randomConfiguration(reference)
    np.testing.assert_allclose(pin.crba(model, model.createData(), q), pin.crba(reference, reference.createData(), q),
                               atol=1e-12)


def test_the_kinematics_read_no_mesh_and_the_3d_view_adds_them_to_the_same_model():
    assert describe_robot("talos").visual_model is None  # 3 ms of URDF instead of 0.6 s of meshes
    robot = load_robot("talos")
    assert robot.model is load_model("talos") is describe_robot("talos").model
    reference = erd.load("talos")
    names = [g.name for g in robot.visual_model.geometryObjects]
    assert names == [g.name for g in reference.visual_model.geometryObjects]
    np.testing.assert_array_equal(robot.q0, reference.q0)


def test_a_loader_that_builds_its_own_model_is_run_as_it_is():
    legs = describe_robot("talos_legs")  # a model reduced by its loader: meshes included
    assert legs.visual_model is not None and load_robot("talos_legs") is legs


@pytest.mark.parametrize(("name", "floating"), [("talos", True), ("panda", False), ("ur5", False)])
def test_has_free_flyer_tells_a_floating_base(name, floating):
    from dgraph.entities.robot.loading import has_free_flyer

    assert has_free_flyer(load_model(name)) is floating
    assert not has_free_flyer(pin.Model())  # the universe joint only


def test_the_free_flyer_test_and_the_loaders_live_in_loading_only():
    """One ``has_free_flyer``; ``load_model`` imported from ``loading``, not from ``robot_state``."""
    import pathlib

    import dgraph
    import dgraph_sim
    from dgraph.entities.robot import robot_state

    assert not hasattr(robot_state, "load_model") and not hasattr(robot_state, "load_robot")
    roots = [pathlib.Path(dgraph.__file__).parent, pathlib.Path(dgraph_sim.__file__).parent]
    twins = [str(path) for root in roots for path in root.rglob("*.py")
             if path.name != "loading.py" and '"JointModelFreeFlyer"' in path.read_text()]
    assert twins == []


def _edit(path, old, new):
    """Rewrite ``path`` with ``old`` replaced (same size) and a later modification time, as an
    editor saving the file a second later does."""
    text = path.read_text()
    assert text.count(old) == 1 and len(old) == len(new)
    before = path.stat().st_mtime_ns
    path.write_text(text.replace(old, new))
    os.utime(path, ns=(before + 1_000_000_000, before + 1_000_000_000))


def test_an_edited_urdf_is_read_again(tmp_path):
    arm = tmp_path / "arm.urdf"
    shutil.copy(describe_robot("panda").urdf, arm)
    first = load_model(str(arm))
    assert first.inertias[1].mass == pytest.approx(4.970684)
    assert load_model(str(arm)) is first  # unchanged: cached
    _edit(arm, '<mass value="4.970684"', '<mass value="7.970684"')
    edited = load_model(str(arm))
    assert edited.inertias[1].mass == pytest.approx(7.970684)
    assert load_model(str(arm)) is edited


def test_an_edited_urdf_is_drawn_again(tmp_path):
    arm = tmp_path / "arm.urdf"
    arm.write_text(_meshless_arm(1.5))
    assert load_robot(str(arm)).model.inertias[1].mass == pytest.approx(1.5)
    _edit(arm, 'value="1.5"', 'value="2.5"')
    robot = load_robot(str(arm))
    assert robot.model.inertias[1].mass == pytest.approx(2.5) and robot.model is load_model(str(arm))


def _meshless_arm(mass: float) -> str:
    """A one-joint URDF with a box for its geometry (no mesh file)."""
    inertia = '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>'
    box = '<geometry><box size="0.1 0.1 0.4"/></geometry>'
    return f"""<robot name="arm">
  <link name="base"><inertial><mass value="1.0"/>{inertia}</inertial></link>
  <link name="upper"><inertial><mass value="{mass}"/>{inertia}</inertial>
    <visual>{box}</visual><collision>{box}</collision></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="50" velocity="3"/></joint>
</robot>
"""
