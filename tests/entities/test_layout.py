"""The Rerun blueprint sent with every recording, read back from the .rrd file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.recording import Recorder, read_blueprint
from dgraph.entities.recording.layout import Panel, default_panels, parse_layout
from dgraph.entities.references import Sinusoid
from tests.conftest import Ticker

ROOT = Path(__file__).resolve().parents[2]
PD = ROOT / "graphs" / "pd_double_integrator.yaml"
SWAY_RECORD = ["com_reference.output", "robot.com_position", "com.error", "solver.contact_wrenches",
               "solver.normal_force_total", "solver.tau", "solver.status", "solver.iterations", "solver.solve_time",
               "device.q", "estimator.q", "device.contact_force_total", "device.fallen"]
"""What graphs/base/talos.yaml records (the sway's recording)."""


class Measured(dg.Entity):
    """Outputs named like a robot graph's: a CoM, torques, a solver's status and solve time."""

    @dg.output(shape=(3,), depends=("t",))
    def com_position(self, t):
        return np.array([0.0, 0.01 * t, 0.87])

    @dg.output(shape=(2,), depends=("t",))
    def tau(self, t):
        return np.array([1.0, -1.0]) * t

    @dg.output(shape=(), depends=())
    def status(self, t):
        return 0.0

    @dg.output(shape=(), depends=("t",))
    def solve_time(self, t):
        return 1e-4 * t

    @dg.output(shape=(6,), depends=())
    def contact_wrenches(self, t):
        return np.ones(6)


def robot_like_graph(rrd: Path, **recorder: object) -> dg.Graph:
    g = dg.Graph(dt=0.01, name="layout_test")
    g.add(Ticker("dev"))
    g.add(Sinusoid("com_reference", amplitude=[0.0, 0.05, 0.0], frequency=0.5, offset=[0.0, 0.0, 0.87]))
    g.add(Measured("robot"))
    g.add(Recorder("rec", signals=["com_reference.output", "robot.com_position", "robot.tau", "robot.status",
                                   "robot.solve_time", "robot.contact_wrenches", "dev.x"],
                   rrd_path=str(rrd), flush_every=5, **recorder))
    return g


def views_by_name(rrd: Path) -> dict[str, dict]:
    return {view["name"]: view for view in read_blueprint(str(rrd))["views"].values()}


def test_the_default_blueprint_overlays_reference_and_measured_in_one_plot(tmp_path):
    rrd = tmp_path / "layout.rrd"
    g = robot_like_graph(rrd)
    g.run(ticks=12)
    g.close()
    views = views_by_name(rrd)
    assert set(views) == {"com", "contact forces", "torques", "solver status", "solve time", "dev.x", "faults"}
    assert views["com"]["kind"] == "TimeSeries"
    assert views["com"]["contents"] == ["/signals/com_reference/output", "/signals/robot/com_position"]
    assert views["torques"]["contents"] == ["/signals/robot/tau"]
    assert views["solve time"]["contents"] == ["/signals/robot/solve_time"]
    assert views["faults"]["kind"] == "TextLog" and views["faults"]["origin"] == "/faults"
    assert not any(view["kind"] == "3D" for view in views.values())  # no robot view in this graph


def test_a_robot_view_in_the_recording_gets_the_large_3d_view(tmp_path):
    from tests.entities.test_robot_view import talos_graph

    rrd = tmp_path / "talos.rrd"
    g, _ = talos_graph(rrd)
    g.run(ticks=30)
    g.close()
    blueprint = read_blueprint(str(rrd))
    root = blueprint["containers"][blueprint["root"].split("/", 1)[1]]
    assert root["kind"] == "horizontal" and root["col_shares"] == [3.0, 2.0]
    first = blueprint["views"][root["contents"][0].split("/", 1)[1]]  # the left, wider column
    assert (first["kind"], first["origin"], first["name"]) == ("3D", "/world", "robot")
    assert {view["name"] for view in blueprint["views"].values()} == {"robot", "dev.q", "faults"}


def test_a_layout_of_panels_and_none(tmp_path):
    rrd = tmp_path / "custom.rrd"
    g = robot_like_graph(rrd, layout=[{"title": "CoM y", "signals": ["com_reference.output", "robot.com_position"]},
                                      {"title": "effort", "signals": ["robot.tau", "robot.contact_wrenches"]}])
    g.run(ticks=6)
    g.close()
    views = views_by_name(rrd)
    assert set(views) == {"CoM y", "effort", "faults"}
    assert views["effort"]["contents"] == ["/signals/robot/tau", "/signals/robot/contact_wrenches"]
    g = robot_like_graph(tmp_path / "none.rrd", layout="none")
    g.run(ticks=6)
    g.close()
    assert read_blueprint(str(tmp_path / "none.rrd")) == {"views": {}, "containers": {}, "root": None}


def test_the_default_panels_of_the_talos_recordings():
    panels = default_panels(SWAY_RECORD)
    assert panels[:5] == [
        Panel("com", ("com_reference.output", "robot.com_position")),
        Panel("contact forces", ("solver.contact_wrenches", "solver.normal_force_total", "device.contact_force_total")),
        Panel("torques", ("solver.tau",)),
        Panel("solver status", ("solver.status", "solver.iterations")),
        Panel("solve time", ("solver.solve_time",))]
    assert [p.title for p in panels[5:]] == ["com.error", "device.q", "estimator.q", "device.fallen"]
    tsid_position = ["com_reference.output", "robot.com_position", "com_reference.acceleration",
                     "stabilizer.com_reference", "stabilizer.desired_zmp", "stabilizer.zmp_reference", "zmp.zmp",
                     "measured.com_position", "device.joint_torque", "device.ft_left_ankle"]
    panels = {p.title: p.signals for p in default_panels(tsid_position)}
    assert panels["com"] == ("com_reference.output", "stabilizer.com_reference", "robot.com_position",
                             "measured.com_position")  # the reference's acceleration is not a position
    assert panels["zmp"] == ("stabilizer.zmp_reference", "zmp.zmp")
    assert panels["torques"] == ("device.joint_torque",) and panels["contact forces"] == ("device.ft_left_ankle",)
    assert panels["com_reference.acceleration"] == ("com_reference.acceleration",)
    push = ["force_reference.position", "force_task.force", "wrist_force.force", "tank.energy"]
    assert default_panels(push)[0] == Panel("force", ("force_reference.position", "force_task.force",
                                                      "wrist_force.force"))


@pytest.mark.parametrize(("layout", "message"), [
    ("grid", "must be 'default', 'none' or a list of panels"),
    ([], "non-empty list of panels"),
    (["com"], "panel 0: expected a mapping"),
    ([{"title": "a", "signals": ["dev.x"], "kind": "3d"}], "panel 0: unknown key"),
    ([{"title": "", "signals": ["dev.x"]}], "panel 0: title must be a non-empty string"),
    ([{"title": "a", "signals": "dev.x"}], r"panel 0 \(a\): signals must be a non-empty list"),
    ([{"title": "a", "signals": ["dev.x"]}, {"title": "b", "signals": ["dev.y"]}],
     r"panel 1 \(b\): 'dev.y' not recorded; recorded: dev.x"),
])
def test_a_wrong_layout_is_refused_naming_the_panel(layout, message):
    with pytest.raises(dg.ParamError, match=message):
        Recorder("rec", signals=["dev.x"], layout=layout)
    assert parse_layout([{"title": "a", "signals": ["dev.x"]}], ["dev.x"], "rec") == [Panel("a", ("dev.x",))]


def test_a_wrong_layout_in_a_graph_file_is_an_error_at_its_line(tmp_path):
    text = PD.read_text().replace("set:\n", "set:\n  recorder.layout: [{title: position, signals: [robot.qq]}]\n")
    bad = tmp_path / "bad_layout.yaml"
    bad.write_text(text)
    # the recorder of `record:` is defined after the setting: the file's later place is blamed, as for
    # any parameter of that recorder (recorder.decimation: 0 is reported there too)
    line = next(i for i, text_line in enumerate(text.splitlines(), 1) if text_line.startswith("record:"))
    with pytest.raises(dg.GraphFileError) as error:
        dg.load(str(bad))
    assert str(error.value).startswith(f"{bad}:{line} [record]: recorder: parameter 'layout': "
                                       "panel 0 (position): 'robot.qq' not recorded")
    own = tmp_path / "own_recorder.yaml"  # a recorder of its own: its parameter's line
    own.write_text(text.replace("set:\n  recorder.layout: [{title: position, signals: [robot.qq]}]\n", "set:\n")
                   .replace("record: [robot.q, robot.v, command.output, error.output]\n", "")
                   .replace("entities:\n", "entities:\n  rec:\n    type: Recorder\n    params:\n"
                            "      signals: [robot.q]\n      layout: [{title: q, signals: [robot.v]}]\n"))
    line = own.read_text().splitlines().index("    params:") + 1  # a constructor's refusal: at its params
    with pytest.raises(dg.GraphFileError, match=rf"{own}:{line} \[entities.rec.params\]: rec: parameter "
                                                r"'layout': panel 0 \(q\): 'robot.v' not recorded"):
        dg.load(str(own))
    good = tmp_path / "good_layout.yaml"
    good.write_text(text.replace("robot.qq", "robot.q").replace("set:\n", "set:\n  recorder.rerun: save\n"))
    with dg.load(str(good)) as g:
        g.run(ticks=5, progress=False)
    assert set(views_by_name(tmp_path / "out" / "pd_double_integrator.rrd")) == {"position", "faults"}


def test_loading_and_running_graph_files_from_python_writes_nothing(tmp_path):
    """The library records nothing unless asked: the shipped graphs, loaded and run as they are."""
    for name in ("pd_double_integrator", "talos_sway"):
        with dg.load(str(ROOT / "graphs" / f"{name}.yaml")) as g:
            g.run(ticks=5, progress=False)
        assert all(e.rerun == "off" for e in g if e.type_name in ("Recorder", "RobotView")), name
    assert list(tmp_path.rglob("*")) == []  # the test runs in tmp_path


def test_a_walking_view_adds_its_top_view_and_the_planned_vs_measured_panels(tmp_path):
    """Rule 0 and the top view, from the graph's entities: the blueprint they make, sent to the
    walking view's recording and read back."""
    from dgraph.entities.operators import Constant
    from dgraph.entities.recording.layout import blueprint, walking_top_views
    from tests.entities.test_walking_view import walking_graph

    rrd = tmp_path / "walking.rrd"
    g, view = walking_graph(rrd)
    g.add(Constant("robot_com", value=[0.0, 0.0, 0.87]))
    g.plug("robot_com.output", "walking.com_measured")
    g.run(ticks=40)
    recorded = ["pattern.zmp", "zmp.zmp", "pattern.com_position", "robot_com.output", "pattern.dcm", "dev.x"]
    panels = default_panels(recorded, g)
    assert [(p.title, p.signals) for p in panels] == [
        ("ZMP x/y: planned vs measured", ("pattern.zmp", "zmp.zmp")),
        ("CoM x/y: planned vs measured", ("pattern.com_position", "robot_com.output")),
        ("pattern.dcm", ("pattern.dcm",)), ("dev.x", ("dev.x",))]
    assert default_panels(recorded) == [Panel(name, (name,)) for name in recorded]  # without the graph: rule 6
    assert walking_top_views(g, None) == [] and walking_top_views(g, object()) == []
    assert view.stream is not None and view.stream.send_blueprint(blueprint(panels, [], top_views=walking_top_views(
        g, view.stream)))
    g.close()
    saved = read_blueprint(str(rrd))
    views = {v["name"]: v for v in saved["views"].values()}
    assert set(views) == {"walking (top view)", "ZMP x/y: planned vs measured", "CoM x/y: planned vs measured",
                          "pattern.dcm", "dev.x", "faults"}
    zmp = views["ZMP x/y: planned vs measured"]
    assert zmp["contents"] == ["/signals/pattern/zmp", "/signals/zmp/zmp"]
    roles = {"/signals/pattern/zmp": "planned", "/signals/zmp/zmp": "measured"}
    assert zmp["overrides"] == {path: {"names": [f"{role} x", f"{role} y", f"{role} z"],
                                       "visible_series": [True, True, False]} for path, role in roles.items()}
    top = views["walking (top view)"]
    assert (top["kind"], top["origin"]) == ("3D", "/world/walking")
    plan = g["footsteps"].plan(0)
    corners = np.vstack([plan.sole.corners(p) for p in (plan.initial_left, plan.initial_right,
                                                       *(s.placement for s in plan.steps))])
    centre = 0.5 * (corners.min(axis=0) + corners.max(axis=0))
    length = np.ptp(corners[:, 0])  # 1.2 m of walk and a sole: the largest extent
    assert np.allclose(top["eye"]["look_target"], centre, atol=1e-6)
    assert np.allclose(top["eye"]["position"], centre + 1.5 * length * np.array([-0.1, 0.0, 1.0]), atol=1e-5)
    root = saved["containers"][saved["root"].split("/", 1)[1]]
    assert saved["views"][root["contents"][0].split("/", 1)[1]]["name"] == "walking (top view)"  # on the left
