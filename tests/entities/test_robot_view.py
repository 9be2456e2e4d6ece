"""RobotView: TALOS meshes and link poses in the same .rrd as the Recorder's series."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.devices import KinematicDevice
from dgraph.entities.operators import Constant
from dgraph.entities.recording import Recorder, RobotView, open_stream, read_series
from dgraph.entities.recording.robot_view import quaternions_xyzw
from dgraph.entities.robot.loading import load_robot
from tests.conftest import Scale, Ticker

pin = pytest.importorskip("pinocchio")
chunk = pytest.importorskip("rerun.chunk")

ELBOW = "arm_left_4_joint"


def talos_graph(rrd: Path, ticks_per_flush: int = 50) -> tuple[dg.Graph, RobotView]:
    g = dg.Graph(dt=0.001, name="talos_view")
    dev = g.add(KinematicDevice("dev", model="talos"))
    u = np.zeros(dev.nv)
    u[dev.pin_model.joints[dev.pin_model.getJointId(ELBOW)].idx_v] = -2.0  # the left elbow bends at 2 rad/s
    g.add(Constant("u", value=u))
    g.plug("u.output", "dev.control")
    g.add(Recorder("rec", signals=["dev.q"], rrd_path=str(rrd), npz_path=str(rrd.with_suffix(".npz"))))
    view = g.add(RobotView("view", rrd_path=str(rrd), decimation=20, flush_every=ticks_per_flush))
    g.plug("dev.q", "view.q")
    return g, view


def read_rrd(rrd: Path) -> dict[str, list[dict[str, list]]]:
    """Entity path -> the chunks logged there, each as column name -> values."""
    out: dict[str, list[dict[str, list]]] = {}
    for ch in chunk.RrdReader(str(rrd)).stream():
        batch = ch.to_record_batch()
        out.setdefault(str(ch.entity_path), []).append(
            {name: batch.column(name).to_pylist() for name in batch.schema.names})
    return out


def poses_over_time(chunks: list[dict[str, list]]) -> dict[int, pin.SE3]:
    poses = {}
    for c in chunks:
        if "tick" not in c:
            continue
        for tick, tr, quat in zip(c["tick"], c["Transform3D:translation"], c["Transform3D:quaternion"], strict=True):
            x, y, z, w = quat[0]
            poses[tick] = pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(tr[0]))
    return dict(sorted(poses.items()))


def static_placement(chunks: list[dict[str, list]]) -> tuple[pin.SE3, np.ndarray]:
    (c,) = [c for c in chunks if "Transform3D:mat3x3" in c]
    rotation = np.array(c["Transform3D:mat3x3"][0][0]).reshape(3, 3, order="F")  # stored column-major
    return pin.SE3(rotation, np.array(c["Transform3D:translation"][0][0])), np.array(c["Transform3D:scale"][0][0])


@pytest.fixture(scope="module")
def talos_run(tmp_path_factory):
    rrd = tmp_path_factory.mktemp("view") / "talos.rrd"
    g, view = talos_graph(rrd)
    g.run(ticks=200)
    g.close()
    return rrd, view, np.load(rrd.with_suffix(".npz"))


def test_meshes_are_logged_once_and_poses_every_decimation(talos_run):
    rrd, view, _ = talos_run
    entities = read_rrd(rrd)
    robot = load_robot("talos")
    assert len(view.links) == 52 and view.skipped == []
    for link in view.links:
        poses = poses_over_time(entities[f"/world/robot/{link.name}"])
        assert list(poses) == list(range(0, 200, 20)), link.name
        for geom in link.geometries:
            chunks = entities[f"/world/robot/{link.name}/{geom.name}"]
            assert all("tick" not in c for c in chunks)  # static
            names = {n for c in chunks for n in c}
            kind = "Asset3D:blob" if geom.meshPath.lower().endswith(".stl") else (
                "Cylinders3D:radii" if geom.meshPath == "CYLINDER" else "Boxes3D:half_sizes")
            assert kind in names, geom.name
    n_meshes = sum(g.meshPath.lower().endswith(".stl") for g in robot.visual_model.geometryObjects)
    assert n_meshes > 40
    assert {"/world", "/world/floor", "/world/axes"} <= set(entities)
    # the recorder's series is in the same file
    ticks, q = read_series(str(rrd))["/signals/dev/q"]
    assert np.array_equal(ticks, np.arange(200)) and q.shape == (200, 39)


def test_logged_poses_place_every_geometry_where_pinocchio_does(talos_run):
    rrd, view, data = talos_run
    entities = read_rrd(rrd)
    robot = load_robot("talos")
    gdata = robot.visual_model.createData()
    mdata = robot.model.createData()
    for tick in (0, 100, 180):
        pin.forwardKinematics(robot.model, mdata, data["dev.q"][tick])
        pin.updateGeometryPlacements(robot.model, mdata, robot.visual_model, gdata)
        for link in view.links:
            oMf = poses_over_time(entities[f"/world/robot/{link.name}"])[tick]
            for geom in link.geometries:
                fMg, scale = static_placement(entities[f"/world/robot/{link.name}/{geom.name}"])
                expected = gdata.oMg[robot.visual_model.getGeometryId(geom.name)]
                assert np.allclose((oMf * fMg).homogeneous, expected.homogeneous, atol=1e-5), (tick, geom.name)
                assert np.allclose(scale, geom.meshScale)


def test_the_elbow_moves_and_the_legs_do_not(talos_run):
    rrd, _, data = talos_run
    entities = read_rrd(rrd)
    hand = poses_over_time(entities["/world/robot/arm_left_7_link"])
    foot = poses_over_time(entities["/world/robot/leg_left_6_link"])
    model = load_robot("talos").model
    iq = model.joints[model.getJointId(ELBOW)].idx_q
    assert data["dev.q"][180, iq] == pytest.approx(data["dev.q"][0, iq] - 2.0 * 0.18)
    moved = np.linalg.norm(hand[180].translation - hand[0].translation)
    assert moved > 0.05  # 0.36 rad of elbow with a ~0.3 m forearm
    assert np.allclose(foot[180].homogeneous, foot[0].homogeneous, atol=1e-6)


def test_rrd_with_robot_view_passes_rerun_verify(talos_run):
    rerun_cli = Path(sys.executable).with_name("rerun")
    result = subprocess.run([str(rerun_cli), "rrd", "verify", str(talos_run[0])],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr


def test_quaternions_match_pinocchio(rng):
    rotations = [pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3)) for _ in range(200)]
    rotations += [pin.exp3(np.pi * axis) for axis in np.eye(3)]  # half turns: w = 0
    rotations += [np.eye(3)]
    q = quaternions_xyzw(np.array(rotations))
    for rotation, quat in zip(rotations, q, strict=True):
        x, y, z, w = quat
        assert np.allclose(pin.Quaternion(w, x, y, z).matrix(), rotation, atol=1e-12)
        assert np.linalg.norm(quat) == pytest.approx(1.0)


def test_a_failed_tick_logs_nothing(tmp_path):
    g = dg.Graph(dt=0.001, name="fail")
    dev = g.add(KinematicDevice("dev", model="talos"))
    g.add(Constant("u", value=np.zeros(dev.nv)))
    g.plug("u.output", "dev.control")
    view = g.add(RobotView("view", rrd_path=str(tmp_path / "f.rrd")))
    g.plug("dev.q", "view.q")
    g.add(Scale("bad"))  # its input is unplugged: the recorder's read fails after the view observed
    g.add(Recorder("rec", signals=["bad.y"], rerun="off"))
    with pytest.raises(dg.UnpluggedInputError):
        g.step()
    assert view._ticks == [] and not view._statics_sent
    g.remove("rec")
    g.run(ticks=3)
    g.close()
    assert list(poses_over_time(read_rrd(tmp_path / "f.rrd")["/world/robot/base_link"])) == [0]


def test_a_configuration_of_the_wrong_size_fails_the_tick_where_it_is_read(tmp_path):
    class Short(dg.Entity):
        @dg.output(shape=(39,), depends=())
        def q(self, t):
            return np.zeros(38)  # computed values are not checked on the hot path

    g = dg.Graph(dt=0.001, name="short_q")
    g.add(Ticker("dev"))
    g.add(Short("short"))
    view = g.add(RobotView("view", rrd_path=str(tmp_path / "s.rrd")))
    g.plug("short.q", "view.q")
    with pytest.raises(dg.SpecError, match=r"view\.q: expected shape \(39,\), got \(38,\) at tick 0"):
        g.step()
    assert view._ticks == [] and view._qs == []
    g.close()


def test_streams_are_shared_per_file_and_graph_and_closed_by_the_last_user(tmp_path):
    graph, other = object(), object()
    a = open_stream("app", "save", str(tmp_path / "s.rrd"), 0.001, graph)
    b = open_stream("app", "save", str(tmp_path / ".." / tmp_path.name / "s.rrd"), 0.001, graph)
    c = open_stream("app", "save", str(tmp_path / "t.rrd"), 0.001, graph)
    assert a is b and a is not c and a.users == 2
    with pytest.raises(dg.GraphError, match="rec: the Rerun sink .* already open with dt=0.001") as err:
        open_stream("app", "save", str(tmp_path / "s.rrd"), 0.01, graph, "rec")
    assert err.value.entity == "rec"
    with pytest.raises(dg.GraphError, match="view: the Rerun sink .*s.rrd is already in use by another graph"):
        open_stream("app", "save", str(tmp_path / "s.rrd"), 0.001, other, "view")
    a.close()
    assert open_stream("app", "save", str(tmp_path / "s.rrd"), 0.001, graph) is a  # still open: shared again
    a.close()
    b.close()
    c.close()
    d = open_stream("app", "save", str(tmp_path / "s.rrd"), 0.001, other)
    assert d is not a and d.users == 1  # closed: a new stream
    d.close()


def test_parameters_are_checked():
    with pytest.raises(dg.ParamError, match="path must be an entity path"):
        RobotView("v", path="world//robot")
    with pytest.raises(dg.ParamError, match="cannot load robot model 'no_such_robot'"):
        RobotView("v", model="no_such_robot")
    with pytest.raises(dg.ParamError, match="decimation"):
        RobotView("v", decimation=0)
    assert RobotView("v").q.spec.shape == (39,)
    assert RobotView("v").flush_every == 1000 and RobotView("v", rerun="spawn").flush_every == 200


def test_the_kinematics_and_the_3d_view_share_one_load_of_the_robot():
    """TALOS's URDF and meshes are read once per process (~0.6 s): the Pinocchio model the
    entities use is the one of the loaded robot the view draws."""
    from dgraph.entities.robot import load_model

    assert load_model("talos") is load_robot("talos").model


def test_a_view_that_records_nothing_reads_no_mesh():
    """With Rerun off (the library's default) the view loads the kinematics only; its meshes are
    read when it first draws (here: asked for its links)."""
    from dgraph.entities.robot.loading import robots_with_meshes  # load_robot's cache

    robots_with_meshes.cache_clear()
    view = RobotView("view", model="ur5", rerun="off")
    assert view.nq == 6 and robots_with_meshes.cache_info().currsize == 0
    assert len(view.links) > 0 and robots_with_meshes.cache_info().currsize == 1
