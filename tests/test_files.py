"""Graph files: load, save, fixed point, and every kind of bad file."""

from __future__ import annotations

import os
import re
import socket
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import dgraph as dg
from dgraph.files import dumps, loads

ROOT = Path(__file__).resolve().parents[1]
PD = ROOT / "graphs" / "pd_double_integrator.yaml"

GOOD = """\
name: small
dt: 0.01
entities:
  dev: {type: KinematicDevice, params: {size: 2}}
  k:
    type: Gain
    params: {size: 2}
plugs:
  - dev.q -> k.input
set:
  k.gain: 2.0
"""


def test_load_builds_the_described_graph():
    g = dg.load(PD)
    assert g.name == "pd_double_integrator" and g.dt == 0.001 and g.duration == 3.0
    assert set(g.entities) == {"robot", "setpoint", "error", "kp", "kd", "command", "recorder"}
    assert ("command.output", "robot.control") in g.plugs()
    assert g["kp.gain"].value == 25.0 and g["recorder"].signals[0] == "robot.q"
    g.validate()


GRAPH_FILES = sorted(p for p in (ROOT / "graphs").rglob("*.yaml") if "data" not in p.relative_to(ROOT / "graphs").parts)
"""Every graph file (graphs/data holds the data files they read: trajectories, actuator chains)."""


@pytest.mark.parametrize("path", GRAPH_FILES, ids=lambda p: str(p.relative_to(ROOT / "graphs")))
def test_load_save_elsewhere_load_save_is_a_fixed_point(path, tmp_path):
    """Saved to one folder, loaded, saved to another: the same text, and the same graph."""
    first = dg.load(path)
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
    dg.save(first, tmp_path / "a" / "x.yaml")
    second = dg.load(tmp_path / "a" / "x.yaml")
    dg.save(second, tmp_path / "b" / "y.yaml")
    assert (tmp_path / "a" / "x.yaml").read_text() == (tmp_path / "b" / "y.yaml").read_text()
    assert first.plugs() == second.plugs() and list(first.entities) == list(second.entities)
    for name, e in first.entities.items():
        assert second[name].type_name == e.type_name
        for key, value in e.params.items():
            assert np.array_equal(np.asarray(second[name].params[key], dtype=object), np.asarray(value, dtype=object))


def test_a_saved_graph_reads_its_data_files_from_another_folder(tmp_path):
    """A path parameter is written relative to the saved file: the copy finds the CSV."""
    graph = dg.load(ROOT / "graphs" / "talos_push_tank.yaml")
    dg.save(graph, tmp_path / "copy.yaml")
    written = tmp_path.joinpath("copy.yaml").read_text()
    relative = os.path.relpath(ROOT / "graphs" / "data" / "push_force.csv", tmp_path)
    assert f"path: {relative}" in written and not Path(relative).is_absolute()
    copy = dg.load(tmp_path / "copy.yaml")
    assert Path(copy["force_reference"].params["path"]).resolve() == (ROOT / "graphs" / "data" / "push_force.csv")
    assert np.array_equal(copy["force_reference"].position(3000), graph["force_reference"].position(3000))


def test_a_saved_graph_runs_the_same(tmp_path):
    a = dg.load(PD)
    dg.save(a, tmp_path / "copy.yaml")
    b = dg.load(tmp_path / "copy.yaml")
    for g in (a, b):
        with g:  # one after the other: both record to out/pd_double_integrator.rrd
            g.run(ticks=500)
    assert np.array_equal(a["robot.q"].value, b["robot.q"].value)


def test_overrides_set_parameters_and_constants():
    g = loads(GOOD, overrides={"dev.q0": [1.0, 2.0], "k.gain": 3.0})
    assert np.array_equal(g["dev.q"].value, [1.0, 2.0]) and g["k.gain"].value == 3.0
    with pytest.raises(dg.GraphFileError, match="no entity 'nope'"):
        loads(GOOD, overrides={"nope.x": 1})


@dg.register(name="TestNamesAndPaths")
class NamesAndPaths(dg.Entity):
    """A name or a file's path, and folders: what a robot's ``model`` and ``package_dirs`` are."""

    model = dg.Param("talos", kind="name_or_path")
    package_dirs = dg.Param([], kind="path_list")


NAMES_AND_PATHS = """\
name: names_and_paths
robot: arm.urdf
entities:
  a: {type: TestNamesAndPaths, params: {package_dirs: [meshes, ../shared]}}
  b: {type: TestNamesAndPaths, params: {model: talos}}
  c: {type: TestNamesAndPaths, params: {model: sub/other.urdf}}
"""


def _project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A graph file in ``tmp_path/project`` naming files next to it; the working directory elsewhere."""
    project = tmp_path / "project"
    for folder in (project / "sub", project / "meshes", project / "talos", tmp_path / "shared", tmp_path / "cwd"):
        folder.mkdir(parents=True)  # project/talos: a folder, so 'talos' stays a name
    (project / "arm.urdf").write_text("<robot/>")
    (project / "sub" / "other.urdf").write_text("<robot/>")
    (project / "g.yaml").write_text(NAMES_AND_PATHS)
    monkeypatch.chdir(tmp_path / "cwd")
    return project


def test_a_robot_a_name_or_path_and_a_path_list_are_taken_from_the_files_folder(tmp_path, monkeypatch):
    project = _project(tmp_path, monkeypatch)
    graph = dg.load(project / "g.yaml")
    assert graph["a"].model == str(project / "arm.urdf")  # robot: a path, from the file's folder
    assert graph["a"].package_dirs == [str(project / "meshes"), str(tmp_path / "shared")]
    assert graph["b"].model == "talos"  # a name stays a name
    assert graph["c"].model == str(project / "sub" / "other.urdf")


def test_names_and_paths_are_saved_relative_to_the_saved_file_a_fixed_point(tmp_path, monkeypatch):
    project = _project(tmp_path, monkeypatch)
    first = dg.load(project / "g.yaml")
    (tmp_path / "out").mkdir()
    dg.save(first, tmp_path / "out" / "x.yaml")
    written = (tmp_path / "out" / "x.yaml").read_text()
    assert "robot: ../project/arm.urdf" in written and "model: talos" in written
    assert "package_dirs: [../project/meshes, ../shared]" in written and "model: ../project/sub/other.urdf" in written
    second = dg.load(tmp_path / "out" / "x.yaml")
    assert [e.params for e in second] == [e.params for e in first]
    (tmp_path / "out2").mkdir()
    dg.save(second, tmp_path / "out2" / "y.yaml")
    assert (tmp_path / "out2" / "y.yaml").read_text() == written


def test_a_robot_path_of_a_base_file_is_the_base_files(tmp_path, monkeypatch):
    """``extends``: the base's ``robot`` is taken from the base's folder, written from the top file's."""
    project = _project(tmp_path, monkeypatch)
    (tmp_path / "top.yaml").write_text("extends: project/g.yaml\nname: top\n")
    assert dg.files.parse((tmp_path / "top.yaml").read_text(), str(tmp_path / "top.yaml"))["robot"] == \
        "project/arm.urdf"
    assert dg.load(tmp_path / "top.yaml")["a"].model == str(project / "arm.urdf")


def test_in_python_and_with_set_a_path_is_the_working_directorys(tmp_path, monkeypatch):
    project = _project(tmp_path, monkeypatch)
    assert NamesAndPaths("p", model="arm.urdf", package_dirs=["meshes"]).params == \
        {"model": "arm.urdf", "package_dirs": ["meshes"]}
    with pytest.raises(dg.GraphFileError, match=r"--set b.model.*cannot read data file 'arm.urdf'"):
        dg.load(project / "g.yaml", {"b.model": "arm.urdf"})  # not in the working directory
    monkeypatch.chdir(project)
    assert dg.load(project / "g.yaml", {"b.model": "arm.urdf", "b.package_dirs": ["meshes"]})["b"].params == \
        {"model": "arm.urdf", "package_dirs": ["meshes"]}


def test_unsaveable_parameter_is_reported():
    import pinocchio as pin

    g = dg.Graph()
    g.add(dg.get_type("KinematicDevice")("dev", model=pin.buildSampleModelHumanoidRandom()))
    with pytest.raises(dg.GraphError, match=r"dev\.model: a Model cannot be written"):
        dumps(g)


BAD_FILES = [
    # (text, line, message fragment)
    (GOOD.replace("type: Gain", "type: Gian"), 6, "unknown entity type 'Gian'; did you mean Gain"),
    (GOOD.replace("params: {size: 2}\nplugs", "params: {size: 2, gain: 1}\nplugs"), 7, "unknown parameter(s) gain"),
    (GOOD.replace("params: {size: 2}}", "params: {size: two}}"), 4, "parameter 'size': expected an int"),
    (GOOD.replace("dev.q -> k.input", "dev.qq -> k.input"), 9, "has no signal 'qq'"),
    (GOOD.replace("dev.q -> k.input", "dev.q => k.input"), 9, "must read 'entity.output -> entity.input'"),
    (GOOD.replace("k.gain: 2.0", "k.output: 2.0"), 11, "k.output is an output"),
    (GOOD.replace("k.gain: 2.0", "k.gain: abc"), 11, "k.gain: expected a scalar float, got 'abc'"),
    (GOOD.replace("k.gain: 2.0", "k.gain: .nan"), 11, "NaN"),
    (GOOD.replace("{size: 2}}", "{size: 3}}", 1), 9, "shape or dtype mismatch"),
    (GOOD + "extra: 1\n", 12, "unknown key 'extra' (allowed: name, dt"),
    (GOOD.replace("  k:\n", "  1k:\n"), 5, "invalid entity name '1k'"),
    (GOOD.replace("k.gain: 2.0", "kgain: 2.0"), 11, "'kgain' must read 'entity.signal'"),
    (GOOD + "record: [nope.output]\n", 12, "recorded signal 'nope.output'"),
    ("entities:\n  off: {type: Gain}\nplugs: [off.output -> off.input]\n", 3, "closes a loop"),
    ("entities: {}\ndt: !!float abc\n", 2, "'abc' is not a valid float"),
    ("entities: {}\ndt: 1" + "0" * 400 + "\n", 2, "not a supported number"),
    ("entities: {}\ndt: 1" + "0" * 30 + "\n", 2, "too large"),
    ("entities: {}\nduration: 1" + ":1" * 1000 + "\n", 2, "not a supported number"),
    ("entities: {}\ndt: .inf\n", 2, "dt must be positive and finite"),
    ("entities: {}\nduration: .inf\n", 2, "duration must be finite"),
    (GOOD.replace("dt: 0.01", "dt: -1"), 2, "dt"),
    (GOOD.replace("  k:\n", "  dev:\n"), 5, "duplicate key 'dev'"),
    ("entities: {a: {type: Gain}\n", 2, "invalid YAML"),
    ("- just\n- a list\n", 1, "must be a mapping"),
    ("", 1, "empty"),
    ("name: x\n", 1, "'entities' is a required property"),
    ("entities:\n  a: !!python/object/apply:os.system ['true']\n", 2, "tag"),
    ("entities:\n  a: &x {type: Gain}\n  b: *x\n", 2, "anchors and aliases"),
    ("entities:\n  a: {type: Gain}\n  <<: {b: 1}\n", 3, "merge keys"),
    ("entities: {}\nset: {'a.b': !custom 1}\n", 2, "tag"),
    (GOOD.replace("plugs:\n  - dev.q -> k.input", "plugs:\n  - k.output -> k.input"), 9, "closes a loop"),
]


@pytest.mark.parametrize(("text", "line", "fragment"), BAD_FILES)
def test_bad_files_give_file_line_and_reason(text, line, fragment, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(dg.GraphFileError) as info:
        dg.load(path)
    assert info.value.file == str(path)
    assert info.value.line == line, str(info.value)
    assert fragment in str(info.value)
    assert str(info.value).startswith(f"{path}:{line}")


def test_unreadable_files(tmp_path):
    with pytest.raises(dg.GraphFileError, match="cannot read"):
        dg.load(tmp_path / "missing.yaml")
    with pytest.raises(dg.GraphFileError, match="not a regular file"):
        dg.load("/dev/zero")  # never read (it would never end)
    with pytest.raises(dg.GraphFileError, match="not a regular file"):
        dg.load(tmp_path)
    (tmp_path / "latin1.yaml").write_bytes(b"name: caf\xe9\n")
    with pytest.raises(dg.GraphFileError, match="not UTF-8"):
        dg.load(tmp_path / "latin1.yaml")
    with pytest.raises(dg.GraphFileError, match="nested more than 64 deep"):
        loads("entities: " + "[" * 5000 + "]" * 5000)


def test_no_code_runs_from_a_file(tmp_path):
    marker = tmp_path / "pwned"
    attacks = [
        f"entities: !!python/object/apply:os.system ['touch {marker}']\n",
        "entities:\n  a: {type: !!python/name:os.system , params: {}}\n",
        f"x: !!python/object/new:os.system ['touch {marker}']\nentities: {{}}\n",
        "entities:\n  a: {type: '__import__(\"os\").system'}\n",
        "entities:\n  a: {type: dgraph.files.os.system}\n",
    ]
    for text in attacks:
        with pytest.raises(dg.GraphFileError):
            loads(text)
    assert not marker.exists()


VALID_LINES = GOOD.splitlines(keepends=True)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=300))
def test_fuzz_random_text_gives_only_graph_file_errors(text):
    try:
        loads(text)
    except dg.GraphFileError:
        pass


yaml_scalar = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=True),
                        st.text(max_size=12))
yaml_value = st.recursive(yaml_scalar, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)), max_leaves=12)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, len(VALID_LINES) - 1), st.text(max_size=40), st.sampled_from(["replace", "insert", "delete"]))
def test_fuzz_mutated_valid_file(index, fragment, how):
    lines = list(VALID_LINES)
    if how == "replace":
        lines[index] = fragment + "\n"
    elif how == "insert":
        lines.insert(index, fragment + "\n")
    else:
        del lines[index]
    try:
        loads("".join(lines))
    except dg.GraphFileError:
        pass


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(["Gain", "Add", "Constant", "KinematicDevice", "Sinusoid", "Selector", "Switch",
                        "Delay", "Integrator", "Saturation", "Recorder"]),
       st.dictionaries(st.sampled_from(["size", "value", "n_inputs", "coefficients", "indices", "amplitude",
                                        "frequency", "initial", "control_mode", "signals", "rerun", "model",
                                        "q0", "dt", "period"]), yaml_value, max_size=4),
       yaml_value)
def test_fuzz_structured_params_and_values(type_name, params, value):
    import yaml

    doc = {"entities": {"e": {"type": type_name, "params": params}}, "set": {"e.input": value}}
    try:
        loads(yaml.safe_dump(doc))
    except dg.GraphFileError:
        pass


def test_environment_is_untouched_by_loading():
    before = dict(os.environ)
    dg.load(PD)
    assert dict(os.environ) == before


# -- a file extending another ------------------------------------------------------------------

BASE = GOOD.replace("dt: 0.01\n", "dt: 0.01\nduration: 2.0\n")


def write(directory: Path, name: str, text: str) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / name).write_text(text)
    return directory / name


def test_a_derived_file_builds_the_base_graph_with_its_name_duration_and_overrides(tmp_path):
    write(tmp_path / "graphs", "base.yaml", BASE)
    derived = write(tmp_path / "graphs", "derived.yaml",
                    "extends: base.yaml\nname: variant\nduration: 5.0\n"
                    "overrides:\n  k.gain: 3.0\n  dev.q0: [1.0, 2.0]\n")
    base = dg.load(tmp_path / "graphs" / "base.yaml")
    g = dg.load(derived)  # the base is found next to the derived file, not in the working directory
    assert (g.name, g.duration, g.dt) == ("variant", 5.0, 0.01)
    assert (base.name, base.duration, base["k.gain"].value) == ("small", 2.0, 2.0)
    assert list(g.entities) == list(base.entities) and g.plugs() == base.plugs()
    assert g["k.gain"].value == 3.0 and np.array_equal(g["dev.q"].value, [1.0, 2.0])
    assert g["dev"].params["q0"] is not None and base["dev"].params["q0"] is None
    # without name and duration, the base's are kept
    plain = write(tmp_path / "graphs", "plain.yaml", "extends: base.yaml\n")
    g = dg.load(plain)
    assert (g.name, g.duration, g["k.gain"].value) == ("small", 2.0, 2.0)


def test_command_line_overrides_win_and_the_nearest_file_wins_in_a_chain(tmp_path):
    write(tmp_path, "base.yaml", BASE)
    middle = write(tmp_path, "middle.yaml",
                   "extends: base.yaml\nname: middle\noverrides: {k.gain: 3.0, dev.q0: [1, 1]}\n")
    top = write(tmp_path, "top.yaml", "extends: middle.yaml\noverrides: {k.gain: 4.0}\n")
    assert dg.load(middle, overrides={"k.gain": 7.0})["k.gain"].value == 7.0
    g = dg.load(top)
    assert g.name == "middle" and g["k.gain"].value == 4.0 and np.array_equal(g["dev.q"].value, [1.0, 1.0])
    g = dg.load(top, overrides={"k.gain": 9.0, "dev.q0": [0.0, 5.0]})
    assert g["k.gain"].value == 9.0 and np.array_equal(g["dev.q"].value, [0.0, 5.0])


EXTENSION_ERRORS = [
    # (derived text, line, message fragment)
    ("extends: base.yaml\nname: x\noverrides:\n  k.gain: 3.0\n  nope.gain: 1.0\n", 5, "no entity 'nope' in"),
    ("name: x\nextends: missing.yaml\n", 2, "cannot extend 'missing.yaml'"),
    ("extends: base.yaml\nentitys:\n  k: {type: Gain}\n", 2, "unknown key 'entitys' (allowed: name, dt"),
    ("extends: base.yaml\ndt: -0.1\n", 2, "-0.1 is less than or equal to the minimum of 0"),
    ("extends: base.yaml\noverrides:\n  kgain: 1.0\n", 3, "'kgain' must read 'entity.signal'"),
]


@pytest.mark.parametrize(("text", "line", "fragment"), EXTENSION_ERRORS)
def test_errors_of_a_derived_file_point_at_its_lines(text, line, fragment, tmp_path):
    write(tmp_path, "base.yaml", BASE)
    derived = write(tmp_path, "derived.yaml", text)
    with pytest.raises(dg.GraphFileError) as info:
        dg.load(derived)
    assert info.value.file == str(derived)
    assert info.value.line == line, str(info.value)
    assert fragment in str(info.value)


def test_an_unknown_entity_two_files_up_is_blamed_on_that_file(tmp_path):
    write(tmp_path, "base.yaml", BASE)
    write(tmp_path, "middle.yaml", "extends: base.yaml\n")
    top = write(tmp_path, "top.yaml", "extends: middle.yaml\nname: top\noverrides:\n  nope.gain: 1.0\n")
    with pytest.raises(dg.GraphFileError, match="no entity 'nope'") as info:
        dg.load(top)
    assert (info.value.file, info.value.line) == (str(top), 4)


def test_an_error_in_the_base_file_names_the_base_and_its_line(tmp_path):
    write(tmp_path, "bad_base.yaml", GOOD.replace("type: Gain", "type: Gian"))
    derived = write(tmp_path, "derived.yaml", "extends: bad_base.yaml\n")
    with pytest.raises(dg.GraphFileError, match=r"bad_base\.yaml:6.*unknown entity type 'Gian'"):
        dg.load(derived)
    unparsable = write(tmp_path, "unparsable.yaml", "entities: {a: {type: Gain}\n")
    derived.write_text("name: x\nextends: unparsable.yaml\n")
    with pytest.raises(dg.GraphFileError, match="invalid YAML") as info:
        dg.load(derived)
    assert (info.value.file, info.value.line) == (str(unparsable), 2)


def test_a_cycle_of_files_extending_one_another_is_refused(tmp_path):
    a = write(tmp_path, "a.yaml", "extends: b.yaml\n")
    write(tmp_path, "b.yaml", "extends: a.yaml\n")
    myself = write(tmp_path, "self.yaml", "extends: self.yaml\n")
    for path in (a, myself):
        with pytest.raises(dg.GraphFileError, match="a cycle") as info:
            dg.load(path)
        assert info.value.line == 1


def test_extends_reads_only_yaml_graph_files(tmp_path):
    for target in ("/etc/hostname", "/dev/zero", "../x.txt"):
        derived = write(tmp_path, "derived.yaml", f"extends: {target}\n")
        with pytest.raises(dg.GraphFileError, match="only extend a .yaml graph file") as info:
            dg.load(derived)
        assert (info.value.file, info.value.line) == (str(derived), 1)


def test_a_bad_override_value_is_located_at_the_extending_file(tmp_path):
    write(tmp_path, "base.yaml", GOOD)
    derived = write(tmp_path, "derived.yaml", "extends: base.yaml\noverrides:\n  k.size: -1\n")
    with pytest.raises(dg.GraphFileError, match="size") as info:
        dg.load(derived)
    assert (info.value.file, info.value.line) == (str(derived), 3), str(info.value)
    derived.write_text("extends: base.yaml\noverrides:\n  k.nope: 1\n")
    with pytest.raises(dg.GraphFileError, match="nope") as info:
        dg.load(derived)
    assert (info.value.file, info.value.line) == (str(derived), 3), str(info.value)


def test_the_push_graph_without_tank_is_the_tank_graph_with_the_tank_disabled():
    tank = dg.load(ROOT / "graphs" / "talos_push_tank.yaml")
    no_tank = dg.load(ROOT / "graphs" / "talos_push_no_tank.yaml")
    assert (no_tank.name, tank.name) == ("talos_push_no_tank", "talos_push_tank")
    assert no_tank.duration == tank.duration == 20.0
    assert list(no_tank.entities) == list(tank.entities) and no_tank.plugs() == tank.plugs()
    assert tank["tank"].params["enabled"] is True and no_tank["tank"].params["enabled"] is False


# -- composition: a scenario adds, replaces and removes what its base has --------------------

COMPOSED_BASE = """\
dt: 0.01
entities:
  dev: {type: KinematicDevice, params: {size: 2}}
  ref: {type: Constant, params: {value: [1.0, 2.0]}}
  err: {type: Add, params: {size: 2, coefficients: [1.0, -1.0]}}
  k:   {type: Gain, params: {size: 2}}
plugs:
  - ref.output -> err.in0
  - dev.q -> err.in1
  - err.output -> k.input
  - k.output -> dev.control
set:
  k.gain: 2.0
record: [dev.q, err.output, k.output]
"""


def scenario(tmp_path: Path, text: str, base: str = COMPOSED_BASE) -> Path:
    write(tmp_path, "base.yaml", base)
    return write(tmp_path, "scenario.yaml", "extends: base.yaml\n" + text)


def test_a_scenario_adds_entities_plugs_settings_and_records(tmp_path):
    g = dg.load(scenario(tmp_path, "entities:\n  bias: {type: Constant, params: {value: 0.5}}\n"
                                   "  sum: {type: Add, params: {size: 2}}\n"
                                   "plugs: [k.output -> sum.in0]\nset: {sum.in1: [0.0, 1.0]}\nrecord: [sum.output]\n"))
    assert list(g.entities) == ["dev", "ref", "err", "k", "bias", "sum", "recorder"]
    assert ("k.output", "sum.in0") in g.plugs() and np.array_equal(g["sum.in1"].value, [0.0, 1.0])
    assert g["recorder"].signals == ["dev.q", "err.output", "k.output", "sum.output"]
    assert g["k.gain"].value == 2.0 and g.name == "scenario"  # no file names it: the scenario's stem


def test_an_entity_of_the_base_is_replaced_in_its_place_with_its_plugs_settings_and_records(tmp_path):
    g = dg.load(scenario(tmp_path, "entities:\n  ref: {type: Sinusoid, params: {amplitude: [0.1, 0.1],"
                                   " frequency: 1.0, offset: [1.0, 2.0]}}\n  k: {type: Gain, params: {size: 2}}\n"))
    assert list(g.entities) == ["dev", "ref", "err", "k", "recorder"]
    assert g["ref"].type_name == "Sinusoid" and ("ref.output", "err.in0") in g.plugs()
    assert g["k.gain"].value == 2.0 and "k.output" in g["recorder"].signals


def test_a_chain_holds_at_most_max_extends_files(tmp_path):
    from dgraph.files import MAX_EXTENDS

    write(tmp_path, "f0.yaml", "entities:\n  k: {type: Gain, params: {size: 1}}\n")
    for i in range(1, MAX_EXTENDS + 1):
        write(tmp_path, f"f{i}.yaml", f"extends: f{i - 1}.yaml\nname: f{i}\n")
    assert dg.load(tmp_path / f"f{MAX_EXTENDS - 1}.yaml").name == f"f{MAX_EXTENDS - 1}"  # 8 files
    with pytest.raises(dg.GraphFileError, match=f"f1.yaml:1 \\[extends\\]: a chain of more than {MAX_EXTENDS} files"):
        dg.load(tmp_path / f"f{MAX_EXTENDS}.yaml")  # 9 files


LAYER_A = ("extends: base.yaml\nname: a\nentities:\n  bias: {type: Constant, params: {value: [0.5, 0.5]}}\n"
           "plugs: [bias.output -> err.in0]\nset: {k.gain: 3.0}\nrecord: [bias.output]\n")
LAYER_B = ("extends: base.yaml\nname: b\nremove: {record: [err.output]}\n"
           "entities:\n  sum: {type: Add, params: {size: 2}}\nplugs: [k.output -> sum.in0]\nset: {k.gain: 5.0}\n")


def test_a_file_extending_several_lays_their_chains_in_order_their_shared_base_once(tmp_path):
    write(tmp_path, "base.yaml", COMPOSED_BASE)
    write(tmp_path, "a.yaml", LAYER_A)
    write(tmp_path, "b.yaml", LAYER_B)
    top = write(tmp_path, "top.yaml", "extends: [a.yaml, b.yaml]\nname: top\n")
    g = dg.load(top)  # base, a, b, top: base's records once (a second base.yaml would record dev.q twice)
    assert list(g.entities) == ["dev", "ref", "err", "k", "bias", "sum", "recorder"]
    assert ("bias.output", "err.in0") in g.plugs() and ("k.output", "sum.in0") in g.plugs()
    assert g["k.gain"].value == 5.0 and g.name == "top"  # b's setting, laid over a's
    assert g["recorder"].signals == ["dev.q", "k.output", "bias.output"]  # b removed what the base recorded
    top.write_text("extends: [b.yaml, a.yaml]\n")
    assert dg.load(top)["k.gain"].value == 3.0


def test_a_mistake_in_a_list_of_bases_is_located_at_its_item(tmp_path):
    write(tmp_path, "base.yaml", COMPOSED_BASE)
    write(tmp_path, "a.yaml", LAYER_A)
    write(tmp_path, "loop.yaml", "extends: [base.yaml, top.yaml]\n")
    top = tmp_path / "top.yaml"
    for extends, fragment in (("[a.yaml, notes.txt]", "only extend a .yaml graph file, not 'notes.txt'"),
                              ("[a.yaml, missing.yaml]", "cannot extend 'missing.yaml'"),
                              ("[a.yaml, loop.yaml]", "a cycle")):
        top.write_text(f"name: top\nextends: {extends}\n")
        with pytest.raises(dg.GraphFileError, match=fragment) as info:
            dg.load(top)
        where = (info.value.file, info.value.line, info.value.key)
        assert where == ((str(top), 2, "extends.1") if "cycle" not in fragment else
                         (str(tmp_path / "loop.yaml"), 1, "extends.1")), str(info.value)
    top.write_text("name: top\nextends: []\n")
    with pytest.raises(dg.GraphFileError, match="extends") as info:
        dg.load(top)
    assert info.value.line == 2


def test_a_graph_of_files_holds_at_most_max_extends_distinct_files(tmp_path):
    from dgraph.files import MAX_EXTENDS

    write(tmp_path, "f0.yaml", "entities:\n  k: {type: Gain, params: {size: 1}}\n")
    for i in range(1, MAX_EXTENDS - 1):  # f1 .. f6 extend f0, each with its own setting
        write(tmp_path, f"f{i}.yaml", f"extends: f0.yaml\nset: {{k.gain: {float(i)}}}\n")
    bases = ", ".join(f"f{i}.yaml" for i in range(1, MAX_EXTENDS - 1))
    top = write(tmp_path, "top.yaml", f"extends: [{bases}]\n")
    assert dg.load(top)["k.gain"].value == MAX_EXTENDS - 2  # 8 files: the top, f0 once, f1 .. f6
    write(tmp_path, f"f{MAX_EXTENDS - 1}.yaml", "extends: f0.yaml\n")
    top.write_text(f"extends: [{bases}, f{MAX_EXTENDS - 1}.yaml]\n")
    with pytest.raises(dg.GraphFileError, match=f"a chain of more than {MAX_EXTENDS} files") as info:
        dg.load(top)
    assert info.value.key == f"extends.{MAX_EXTENDS - 2}"


def test_a_redefinition_gives_its_parameters_over_the_settings_of_the_files_below(tmp_path):
    write(tmp_path, "base.yaml", "entities:\n  c: {type: Constant, params: {value: [1.0]}}\n"
                                 "  k: {type: Gain, params: {size: 1}}\nset:\n  c.value: [2.0]\n  k.gain: 3.0\n")
    top = write(tmp_path, "top.yaml", "extends: base.yaml\nentities:\n  c: {type: Constant, params: {value: [5.0]}}\n"
                                      "  k: {type: Gain, params: {size: 1}}\n")
    g = dg.load(top)
    assert g["c"].given_params["value"] == [5.0] and g["c"].output(0).tolist() == [5.0]
    assert g["k.gain"].value == 3.0  # an input's constant is not a parameter of the definition: it stays


def test_removing_an_entity_removes_its_plugs_settings_and_records(tmp_path):
    g = dg.load(scenario(tmp_path, "remove:\n  entities: [k]\n"))
    assert "k" not in g.entities and all("k." not in f"{a} {b}" for a, b in g.plugs())
    assert g["recorder"].signals == ["dev.q", "err.output"] and g["dev.control"].source is None
    g = dg.load(scenario(tmp_path, "remove: {entities: [k]}\nentities:\n  k: {type: Gain, params: {size: 2}}\n"))
    assert list(g.entities) == ["dev", "ref", "err", "k", "recorder"]  # k is new: after the base's
    assert g["k.gain"].value == 1.0 and g["k.input"].source is None  # a new entity: nothing of the old one


def test_remove_takes_plugs_by_text_or_input_settings_and_records(tmp_path):
    g = dg.load(scenario(tmp_path, "remove:\n  plugs: [ref.output -> err.in0, dev.control]\n"
                                   "  set: [k.gain]\n  record: [err.output]\n"))
    assert ("ref.output", "err.in0") not in g.plugs() and g["dev.control"].source is None
    assert not g["k.gain"].is_set and g["recorder"].signals == ["dev.q", "k.output"]
    assert ("dev.q", "err.in1") in g.plugs()


def test_a_plug_or_a_setting_of_an_input_replaces_what_the_base_gave_it(tmp_path):
    g = dg.load(scenario(tmp_path, "entities:\n  two: {type: Constant, params: {value: 3.0}}\n"
                                   "set:\n  err.in0: [0.5, 0.5]\nplugs:\n  - ref.output -> err.in1\n"
                                   "  - two.output -> k.gain\n"))
    plugs = dict((b, a) for a, b in g.plugs())
    assert plugs["err.in1"] == "ref.output" and plugs["k.gain"] == "two.output" and "err.in0" not in plugs
    assert g["err.in0"].is_set and not g["k.gain"].is_set


def test_set_names_parameters_too_and_the_nearest_file_wins(tmp_path):
    write(tmp_path, "base.yaml", COMPOSED_BASE)
    write(tmp_path, "middle.yaml", "extends: base.yaml\nset: {dev.q0: [1.0, 1.0], k.gain: 3.0}\n")
    top = write(tmp_path, "top.yaml", "extends: middle.yaml\ndt: 0.02\nset: {dev.q0: [4.0, 5.0]}\n")
    g = dg.load(top)
    assert g.dt == 0.02 and np.array_equal(g["dev.q"].value, [4.0, 5.0]) and g["k.gain"].value == 3.0
    assert g["dev"].given_params["size"] == 2  # the definition's other parameters stay
    g = dg.load(top, overrides={"dev.q0": [7.0, 7.0], "k.gain": 9.0})  # the command line wins over every file
    assert np.array_equal(g["dev.q"].value, [7.0, 7.0]) and g["k.gain"].value == 9.0


def test_the_robot_is_the_model_of_every_entity_that_sets_none(tmp_path):
    text = ("robot: talos\nentities:\n  robot: {type: RobotModel}\n  posture: {type: JointPosture}\n"
            "  dev: {type: KinematicDevice, params: {size: 2, model: null}}\nplugs: [robot.state -> posture.robot]\n")
    g = loads(text)
    assert g["robot"].given_params["model"] == g["posture"].given_params["model"] == "talos"
    assert g["dev"].params["model"] is None  # its own
    saved = dumps(g)
    assert saved.count("talos") == 1 and "robot: talos" in saved and "model: null" in saved
    assert dumps(loads(saved)) == saved


def test_a_saved_graph_names_its_robot_once_and_keeps_the_models_that_differ():
    from dgraph.entities.robot import RobotModel

    g = dg.Graph()
    g.add(RobotModel("a", model="talos"), RobotModel("b", model="talos"))
    g.add(dg.get_type("KinematicDevice")("dev", size=2))  # its default model (none) is not the robot
    saved = dumps(g)
    assert saved.count("talos") == 1 and "dev:\n    type: KinematicDevice\n    params: {size: 2, model: null}" in saved
    again = loads(saved)
    assert again["dev"].params["model"] is None and again["b"].given_params["model"] == "talos"


def test_path_parameters_are_taken_from_the_file_that_wrote_them(tmp_path):
    csv = "time, x\n0.0, 0.0\n1.0, 2.0\n"
    write(tmp_path / "base", "data.csv", csv)
    write(tmp_path, "other.csv", csv.replace("2.0", "4.0"))
    write(tmp_path / "base", "traj.yaml", "entities:\n  traj: {type: TrajectoryFile, params: {path: data.csv,"
                                          " interpolation: linear}}\n")
    top = write(tmp_path, "top.yaml", "extends: base/traj.yaml\n")
    assert dg.load(top)["traj"].position(1000)[0] == 2.0
    data = dg.files.parse(top.read_text(), str(top))
    assert data["entities"]["traj"]["params"]["path"] == os.path.join("base", "data.csv")
    top.write_text("extends: base/traj.yaml\nset: {traj.path: other.csv}\n")
    assert dg.load(top)["traj"].position(1000)[0] == 4.0


def test_parse_gives_the_composed_graph_as_one_file(tmp_path):
    path = scenario(tmp_path, "name: s\nremove: {entities: [ref]}\nset: {dev.q0: [1.0, 1.0], err.in0: [0.0, 0.0]}\n")
    data = dg.files.parse(path.read_text(), str(path))
    assert data["name"] == "s" and list(data["entities"]) == ["dev", "err", "k"]
    assert data["entities"]["dev"]["params"] == {"size": 2, "q0": [1.0, 1.0]}
    assert data["set"] == {"k.gain": 2.0, "err.in0": [0.0, 0.0]} and "ref.output -> err.in0" not in data["plugs"]
    assert dumps(loads(yaml_dump(data))) == dumps(dg.load(path))


def yaml_dump(data: dict) -> str:
    import yaml

    return yaml.safe_dump(data, sort_keys=False)


def test_the_command_line_runs_a_composed_file(tmp_path, capsys):
    from dgraph.cli import main

    path = scenario(tmp_path, "duration: 0.05\nset: {k.gain: 4.0}\n")
    assert main(["run", str(path), "--no-rerun", "-q", "--set", "k.gain=5.0",
                 "--npz", str(tmp_path / "run.npz")]) == 0
    assert np.load(tmp_path / "run.npz")["k.output"].shape == (5, 2)


COMPOSITION_ERRORS = [
    # (scenario text after 'extends: base.yaml', the file to blame, line, message fragment)
    ("entities:\n  x: {type: Gian}\n", "scenario", 3, "unknown entity type 'Gian'"),
    ("plugs:\n  - dev.qq -> err.in1\n", "scenario", 3, "has no signal 'qq'"),
    ("set:\n  k.gain: abc\n", "scenario", 3, "k.gain: expected a scalar float, got 'abc'"),
    ("set:\n  k.size: 0\n", "scenario", 3, "parameter 'size' must be within"),
    ("set:\n  nope.gain: 1.0\n", "scenario", 3, "no entity 'nope' in"),
    ("remove:\n  entities: [kk]\n", "scenario", 3, "no entity 'kk' to remove in the files this one extends; did you"),
    ("remove:\n  plugs: [dev.q -> err.in0]\n", "scenario", 3, "(err.in0 is plugged to ref.output)"),
    ("remove:\n  plugs: [k.gain]\n", "scenario", 3, "no plug 'k.gain'"),
    ("remove:\n  set: [k.input]\n", "scenario", 3, "k.input is not set by the files this one extends"),
    ("remove:\n  record: [k.input]\n", "scenario", 3, "k.input is not recorded"),
    ("remove:\n  entity: [k]\n", "scenario", 3, "unknown key 'entity' (allowed: entities, plugs, set, record)"),
    ("record: [k.input, dev.q]\n", "scenario", 2, "dev.q is already recorded (BASE:14 [record.0])"),
    ("record: [nope.output]\n", "scenario", 2, "recorded signal 'nope.output'"),
    ("plugs:\n  - ref.output -> err.in1\n  - dev.v -> err.in1\n", "scenario", 4, "err.in1 is already plugged by this"),
    ("set: {err.in1: [0.0, 0.0]}\nplugs:\n  - dev.v -> err.in1\n", "scenario", 4, "err.in1 is already set by this"),
    ("set: {k.gain: 1.0}\noverrides: {k.gain: 2.0}\n", "scenario", 3, "k.gain is already set by this file"),
    ("entities:\n  ref: {type: KinematicDevice, params: {size: 2}}\n", "scenario", 3,
     "ref (KinematicDevice) has no signal 'output'"),
    ("entities:\n  ref: {type: Constant, params: {value: [1.0, 2.0, 3.0]}}\n", "scenario", 3,
     "(from BASE:8 [plugs.0])"),
]


@pytest.mark.parametrize(("text", "blamed", "line", "fragment"), COMPOSITION_ERRORS)
def test_errors_of_a_composed_file_name_the_file_line_and_key_that_made_them(text, blamed, line, fragment, tmp_path):
    path = scenario(tmp_path, text)
    with pytest.raises(dg.GraphFileError) as info:
        dg.load(path)
    assert info.value.file == str(tmp_path / f"{blamed}.yaml")
    assert info.value.line == line, str(info.value)
    assert fragment.replace("BASE", str(tmp_path / "base.yaml")) in str(info.value)


BASE_ERRORS = [
    # (a mistake in the base, its line, message fragment): the scenario is right, the base is blamed
    (COMPOSED_BASE.replace("dev.q -> err.in1", "dev.qq -> err.in1"), 9, "has no signal 'qq'"),
    (COMPOSED_BASE.replace("k.gain: 2.0", "k.gain: two"), 13, "k.gain"),
    (COMPOSED_BASE.replace("size: 2}}\n  ref", "size: 2, q0: [1]}}\n  ref"), 3, "dev"),
    (COMPOSED_BASE.replace("record: [dev.q,", "record: [dev.qq,"), 14, "recorded signal 'dev.qq'"),
    ("dt: 0.01\nremove: {entities: [k]}\nentities: {}\n", 2, "'remove' is for a file that extends another"),
]


@pytest.mark.parametrize(("base", "line", "fragment"), BASE_ERRORS)
def test_a_mistake_of_the_base_names_the_base_when_a_scenario_is_loaded(base, line, fragment, tmp_path):
    path = scenario(tmp_path, "entities:\n  extra: {type: Constant, params: {value: 1.0}}\n", base)
    with pytest.raises(dg.GraphFileError) as info:
        dg.load(path)
    assert (info.value.file, info.value.line) == (str(tmp_path / "base.yaml"), line), str(info.value)
    assert fragment in str(info.value)


def test_a_bad_robot_is_blamed_on_the_file_that_names_it(tmp_path):
    path = scenario(tmp_path, "name: x\nrobot: tals\n", "robot: talos\nentities:\n  device: {type: MujocoDevice}\n")
    with pytest.raises(dg.GraphFileError,
                       match=r"model 'tals' \(parameter 'model'\): unknown robot; did you mean 'talos'") as info:
        dg.load(path)
    assert (info.value.file, info.value.line, info.value.key) == (str(path), 3, "robot")


def test_a_bad_command_line_setting_is_blamed_on_the_command_line(tmp_path):
    path = scenario(tmp_path, "set: {k.gain: 3.0}\n")
    for overrides, fragment in (({"k.gain": "abc"}, "expected a scalar float"), ({"nope.x": 1}, "no entity 'nope'"),
                                ({"k.size": 0}, "must be within")):
        with pytest.raises(dg.GraphFileError, match=fragment) as info:
            dg.load(path, overrides)
        assert (info.value.file, info.value.line) == ("<command line>", None)
        assert info.value.key == f"--set {next(iter(overrides))}"


# -- the repository's graph files ---------------------------------------------------------------

def shared_run(a: list[str], b: list[str]) -> int:
    """The longest run of consecutive lines that ``a`` and ``b`` share."""
    best, previous = 0, [0] * (len(b) + 1)
    for x in a:
        current = [0] * (len(b) + 1)
        for j, y in enumerate(b, start=1):
            if x == y:
                current[j] = previous[j - 1] + 1
                best = max(best, current[j])
        previous = current
    return best


def code_lines(path: Path) -> list[str]:
    """The file's lines without comments, blank lines and indentation."""
    lines = (line.split(" #")[0].strip() for line in path.read_text().splitlines())
    return [line for line in lines if line and not line.startswith("#")]


def test_shared_run_counts_consecutive_identical_lines():
    assert shared_run(list("abcdxyz"), list("qbcdxq")) == 4 and shared_run(list("ab"), list("cd")) == 0


def test_no_two_graph_files_share_more_than_ten_consecutive_lines():
    files = sorted(p for p in (ROOT / "graphs").rglob("*") if p.suffix in (".yaml", ".py"))
    assert len(files) >= 8
    for i, a in enumerate(files):
        for b in files[i + 1:]:
            run = shared_run(code_lines(a), code_lines(b))
            assert run <= 10, f"{a.name} and {b.name} share {run} consecutive lines: compose them from a base"


def chain(path: Path, seen: set[Path] | None = None) -> list[dict]:
    """The plain data of a file and of every file it extends, each once."""
    import yaml

    seen = set() if seen is None else seen
    seen.add(path.resolve())
    data = yaml.safe_load(path.read_text())
    extends = data.get("extends", [])
    out = [data]
    for name in [extends] if isinstance(extends, str) else extends:
        if (path.parent / name).resolve() not in seen:
            out += chain(path.parent / name, seen)
    return out


@pytest.mark.parametrize("path", GRAPH_FILES, ids=lambda p: str(p.relative_to(ROOT / "graphs")))
def test_every_graph_file_names_its_robot_once(path):
    files = chain(path)
    for data in files:
        assert not any("model" in (spec.get("params") or {}) for spec in data.get("entities", {}).values())
        assert not any(key.endswith(".model") for key in {**data.get("set", {}), **data.get("overrides", {})})
    robots = [data["robot"] for data in files if "robot" in data]
    models = {e.given_params["model"] for e in dg.load(path) if isinstance(e.given_params.get("model"), str)}
    assert len(robots) == len(models) <= 1 and set(robots) == models


@pytest.mark.parametrize("path", sorted((ROOT / "graphs").glob("*.py")), ids=lambda p: p.name)
def test_every_graph_script_names_its_robot_once(path):
    text = path.read_text()
    assert re.findall(r"\bmodel=[\"']", text) == []  # every entity takes the one constant
    assert len(re.findall(r"^ROBOT = [\"'][\w-]+[\"']", text, flags=re.MULTILINE)) == 1


SELF_CONTAINED = "3af9cc3"
"""The last commit whose graph files each described a whole graph (before composition)."""


def graph_summary(graph: dg.Graph, folder: Path) -> dict:
    """What makes a graph: each entity's type and parameters (paths from ``folder``), the plugs,
    the constants and the recorded signals, orders aside."""
    from dgraph.files import to_plain

    def value(entity, key, v):
        if type(entity)._param_decls[key].kind == "path" and v is not None:
            return os.path.relpath(v, folder)
        return sorted(v) if (entity.type_name, key) == ("Recorder", "signals") else to_plain(v, key)

    return {"entities": {e.name: (e.type_name, {k: value(e, k, v) for k, v in e.params.items()}) for e in graph},
            "plugs": set(graph.plugs()),
            "set": {i.full_name: to_plain(i.value, "") for e in graph for i in e.inputs.values() if i.is_set}}


CHANGED_PLUGS = {  # (source, target) then -> now
    # the ZMP estimator reads the ankle wrenches that the estimator's sensor guard trusts (issue 12)
    ("device.ft_left_ankle", "zmp.ft_left_ankle"): ("estimator.checked_ft_left_ankle", "zmp.ft_left_ankle"),
    ("device.ft_right_ankle", "zmp.ft_right_ankle"): ("estimator.checked_ft_right_ankle", "zmp.ft_right_ankle"),
}


@pytest.mark.parametrize("name", ["pd_double_integrator", "talos_standing", "talos_sway", "talos_push_tank",
                                  "talos_push_no_tank", "talos_tsid_position", "talos_ik_position"])
def test_the_composed_graphs_are_the_graphs_the_self_contained_files_described(name, tmp_path):
    """The composition changed how the files are written, not the graphs: each builds what its
    self-contained version at SELF_CONTAINED built, but for the changes made on purpose since
    (:data:`CHANGED_PLUGS`). A later change that means to change a graph says so there."""
    import shutil
    import subprocess

    try:
        old = subprocess.run(["git", "show", f"{SELF_CONTAINED}:graphs/{name}.yaml"], cwd=ROOT, check=True,
                             capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip(f"needs the git history ({SELF_CONTAINED})")
    shutil.copytree(ROOT / "graphs" / "data", tmp_path / "data")
    write(tmp_path, f"{name}.yaml", old)
    if name == "talos_push_no_tank":  # it extended the tank graph of its time
        write(tmp_path, "talos_push_tank.yaml", subprocess.run(
            ["git", "show", f"{SELF_CONTAINED}:graphs/talos_push_tank.yaml"], cwd=ROOT, check=True,
            capture_output=True, text=True).stdout)
    before = graph_summary(dg.load(tmp_path / f"{name}.yaml"), tmp_path)
    before["plugs"] = {CHANGED_PLUGS.get(plug, plug) for plug in before["plugs"]}
    assert graph_summary(dg.load(ROOT / "graphs" / f"{name}.yaml"), ROOT / "graphs") == before


def test_the_readme_shows_the_sway_scenario_as_shipped():
    import yaml

    blocks = re.findall(r"```yaml\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    scenario = next(block for block in blocks if "extends:" in block)
    assert yaml.safe_load(scenario) == yaml.safe_load((ROOT / "graphs" / "talos_sway.yaml").read_text())


# -- a loader that cannot hang (issue 12) ------------------------------------------------------

TRAJECTORY = "name: t\nentities:\n  ref: {{type: TrajectoryFile, params: {{path: {path}}}}}\n"


def refused(call, *args, within: float = 3.0) -> dg.GraphFileError:
    """The GraphFileError of ``call(*args)``, which must come within ``within`` seconds (these
    take milliseconds; the margin is for a loaded machine, what is tested is that nothing hangs)."""
    start = time.perf_counter()
    with pytest.raises(dg.GraphFileError) as info:
        call(*args)
    assert time.perf_counter() - start < within, str(info.value)
    return info.value


def located(error: dg.GraphFileError, file: Path | str, line: int | None, key: str | None) -> None:
    assert (error.file, error.line, error.key) == (str(file), line, key), str(error)


def unix_socket(path: Path) -> socket.socket:
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(path))
    return sock


@pytest.mark.timeout(20)
def test_a_symlink_loop_in_extends_is_located_at_the_extends_line(tmp_path):
    (tmp_path / "self.yaml").symlink_to("self.yaml")
    (tmp_path / "c.yaml").symlink_to("d.yaml")
    (tmp_path / "d.yaml").symlink_to("c.yaml")
    for target in ("self.yaml", "c.yaml"):
        derived = write(tmp_path, "derived.yaml", f"name: x\nextends: {target}\n")
        error = refused(dg.load, derived)
        located(error, derived, 2, "extends")
        assert f"cannot extend {target!r}" in str(error) and "symbolic links" in str(error)
    error = refused(dg.load, tmp_path / "c.yaml")  # the file itself a loop
    located(error, tmp_path / "c.yaml", None, None)
    write(tmp_path, "good.yaml", GOOD)
    assert loads("extends: good.yaml\n", str(tmp_path / "c.yaml")).name == "small"  # text named by a loop


@pytest.mark.timeout(20)
@pytest.mark.parametrize("kind", ["fifo", "/dev/zero", "directory", "socket"])
def test_a_data_file_that_is_not_a_regular_file_is_refused_unread(kind, tmp_path):
    target = {"fifo": tmp_path / "data.csv", "/dev/zero": Path("/dev/zero"), "directory": tmp_path,
              "socket": tmp_path / "data.npz"}[kind]
    if kind == "fifo":
        os.mkfifo(target)
    sock = unix_socket(target) if kind == "socket" else None
    try:
        path = write(tmp_path, "graph.yaml", TRAJECTORY.format(path=target))
        error = refused(dg.load, path)
        located(error, path, 3, "entities.ref.params.path")
        assert "not a regular file" in str(error)
        error = refused(dg.files.check, path)
        located(error, path, 3, "entities.ref.params.path")
        derived = write(tmp_path, "derived.yaml", f"extends: {path.name}\nset: {{ref.path: {target}}}\n")
        located(refused(dg.load, derived), derived, 2, "set.ref.path")
    finally:
        if sock is not None:
            sock.close()


@pytest.mark.timeout(20)
@pytest.mark.parametrize("kind", ["fifo", "/dev/zero", "directory", "socket"])
def test_a_graph_file_that_is_not_a_regular_file_is_refused_unread(kind, tmp_path):
    target = {"fifo": tmp_path / "base.yaml", "/dev/zero": Path("/dev/zero"), "directory": tmp_path / "d.yaml",
              "socket": tmp_path / "base.yaml"}[kind]
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "directory":
        target.mkdir()
    sock = unix_socket(target) if kind == "socket" else None
    try:
        located(refused(dg.load, target), target, None, None)
        if kind != "/dev/zero":  # extends reads only .yaml files
            derived = write(tmp_path, "derived.yaml", f"extends: {target.name}\n")
            error = refused(dg.load, derived)
            located(error, derived, 1, "extends")
            assert "not a regular file" in str(error)
    finally:
        if sock is not None:
            sock.close()


@pytest.mark.timeout(20)
def test_a_graph_file_swapped_for_a_fifo_after_its_check_is_not_waited_for(tmp_path, monkeypatch):
    """The race: the path is a regular file when looked at, a FIFO when opened. It is opened
    without blocking and looked at again."""
    from dgraph.files import source

    regular, fifo = write(tmp_path, "regular.yaml", GOOD), tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    real_stat = os.stat
    monkeypatch.setattr(source.os, "stat", lambda p, *a, **k: real_stat(regular if str(p) == str(fifo) else p))
    error = refused(dg.load, fifo)
    assert "not a regular file" in str(error)


@pytest.mark.timeout(20)
def test_a_file_of_size_0_is_not_read(tmp_path):
    """/proc files say size 0 and may never end (/proc/kmsg blocks once read to its end)."""
    empty = write(tmp_path, "empty.csv", "")
    for target in (empty, Path("/proc/self/environ")):
        path = write(tmp_path, "graph.yaml", TRAJECTORY.format(path=target))
        error = refused(dg.load, path)
        located(error, path, 3, "entities.ref.params.path")
        assert "it is empty (size 0" in str(error)
    (tmp_path / "proc.yaml").symlink_to("/proc/self/environ")
    located(refused(dg.load, tmp_path / "proc.yaml"), tmp_path / "proc.yaml", 1, None)  # "the file is empty"


def test_files_larger_than_the_limits_are_refused_naming_the_limit(tmp_path):
    from dgraph.files import MAX_BYTES, MAX_DATA_BYTES

    big = tmp_path / "big.yaml"
    big.write_text(GOOD + "#" * MAX_BYTES)
    error = refused(dg.load, big)
    assert f"larger than {MAX_BYTES} bytes" in str(error) and error.file == str(big)
    data = tmp_path / "big.csv"
    with data.open("wb") as f:
        f.truncate(MAX_DATA_BYTES + 1)  # sparse: no disk used
    path = write(tmp_path, "graph.yaml", TRAJECTORY.format(path="big.csv"))
    error = refused(dg.load, path)
    located(error, path, 3, "entities.ref.params.path")
    assert f"larger than {MAX_DATA_BYTES} bytes" in str(error)


def test_a_nul_byte_in_a_path_is_located(tmp_path):
    derived = write(tmp_path, "derived.yaml", 'name: x\nextends: "base\\0.yaml"\n')
    error = refused(dg.load, derived)
    located(error, derived, 2, "extends")
    assert "NUL" in str(error)
    path = write(tmp_path, "graph.yaml", TRAJECTORY.format(path='"data\\0.csv"'))
    error = refused(dg.load, path)
    located(error, path, 3, "entities.ref.params.path")
    assert "NUL" in str(error)
    error = refused(dg.load, str(tmp_path / "a\0.yaml"))
    assert error.file == str(tmp_path / "a\0.yaml") and "NUL" in str(error)


DEEP = [
    # (text, line of the refusal)
    ("a: " + "[" * 3000 + "]" * 3000 + "\n", 1),
    ("a: " + "{a: " * 3000 + "1" + "}" * 3000 + "\n", 1),
    ("".join(" " * i + "k:\n" for i in range(500)) + " " * 500 + "v\n", 65),
    ("".join(" " * i + "-\n" for i in range(500)), 65),
    ("".join(" " * i + "k:\n" for i in range(1400)) + " " * 1400 + "v\n", None),  # line: libyaml's or 65
    ("entities:\n  g: {type: Gain, params: {size: 2, gain: " + "[" * 70 + "]" * 70 + "}}\n", 2),
]


@pytest.mark.parametrize("loader", ["libyaml", "python"])
@pytest.mark.parametrize(("text", "line"), DEEP,
                         ids=["flow", "flow-mappings", "block", "block-sequences", "block-1400", "param"])
def test_pathological_nesting_is_refused_quickly_with_its_line(text, line, loader, monkeypatch):
    from dgraph.files import MAX_DEPTH, source

    if loader == "python":
        monkeypatch.setattr(source, "_SAFE_LOADER", source.PythonLoader)
    error = refused(loads, text, within=1.0)
    assert f"nested more than {MAX_DEPTH} deep" in str(error) and len(error.key or "") < 40, str(error)
    assert error.line == line or (line is None and error.line is not None), str(error)


def test_nesting_up_to_the_limit_is_read():
    from dgraph.files import MAX_DEPTH

    def nested(depth: int) -> str:  # set (2) and lists inside, to ``depth`` levels
        return "entities: {}\nset: {a.b: " + "[" * (depth - 2) + "]" * (depth - 2) + "}\n"

    value = dg.files.parse(nested(MAX_DEPTH))["set"]["a.b"]
    for _ in range(MAX_DEPTH - 3):
        value = value[0]
    assert value == []
    assert "nested more than" in str(refused(dg.files.parse, nested(MAX_DEPTH + 1)))


@pytest.mark.parametrize("loader", ["libyaml", "python"])
@pytest.mark.parametrize("item", ["1", "a", "!!str a", "[]"])
def test_a_file_of_too_many_values_is_refused_as_it_is_composed(item, loader, monkeypatch):
    from dgraph.files import source

    monkeypatch.setattr(source, "MAX_NODES", 1000)
    if loader == "python":
        monkeypatch.setattr(source, "_SAFE_LOADER", source.PythonLoader)
    text = "entities: {}\nname: [" + f"{item}, " * 1010 + "]\n"
    error = refused(loads, text)
    assert "more than 1000 values" in str(error) and error.line in (None, 2)
    assert len(dg.files.parse("entities: {}\nset: {a.b: [" + f"{item}, " * 900 + "]}\n")["set"]["a.b"]) == 900


def test_check_locates_what_the_library_refuses_as_load_does(tmp_path, monkeypatch):
    """A refusal without a place (here a GraphError, and a foreign ValueError, from a constant
    that the graph refuses) is located at the file by check too, its cause chained."""
    from dgraph.files import build

    path = write(tmp_path, "graph.yaml", GOOD)
    for error in (dg.GraphError("refused"), ValueError("odd")):
        def refuse(*args, error=error):
            raise error

        monkeypatch.setattr(build, "_check_records", refuse)
        for call in (dg.load, dg.files.check):
            raised = refused(call, path)
            assert raised.file == str(path) and raised.__cause__ is error, str(raised)


def test_a_foreign_exception_of_a_constructor_is_chained_and_an_interrupt_is_not_caught(monkeypatch):
    from dgraph.files import build

    class Exploding(dg.Entity):
        def configure(self):
            raise self.error

    monkeypatch.setattr(build, "get_type", lambda name: Exploding)
    Exploding.error = ZeroDivisionError("boom")
    error = refused(loads, "name: x\nentities:\n  e: {type: Exploding}\n")
    assert error.line == 3 and "could not be built: ZeroDivisionError: boom" in str(error)
    assert error.__cause__ is Exploding.error
    Exploding.error = KeyboardInterrupt()
    with pytest.raises(KeyboardInterrupt):
        loads("name: x\nentities:\n  e: {type: Exploding}\n")


@pytest.mark.parametrize("loader", ["libyaml", "python"])
def test_numbers_with_an_exponent_are_read_as_yaml_1_2_reads_them(loader, monkeypatch):
    """``1e3``, ``2.5e1``, ``-1E-2``, ``.5e1`` (no dot or no sign in the exponent) are floats, as
    YAML 1.2 reads them; PyYAML's YAML 1.1 resolver made them strings. ``1e3x`` stays a string."""
    from dgraph.files import source

    if loader == "python":
        monkeypatch.setattr(source, "_SAFE_LOADER", source.PythonLoader)
    g = loads("name: x\nentities:\n  s: {type: Sinusoid, params: {amplitude: 1.0, frequency: .5e1, ramp: 2.5e1}}\n"
              "  k: {type: Gain}\nset: {k.gain: 1e3, k.input: -1E-2}\n")
    assert g["s"].params["ramp"] == 25.0 and g["s"].params["frequency"] == 5.0
    assert g["k.gain"].value == 1000.0 and g["k.input"].value == -0.01
    data = dg.files.parse("entities: {}\nset: {a.b: [1e3, 2.5E+1, 1e3x, e3, 1.e2, 12]}\n")
    assert data["set"]["a.b"] == [1000.0, 25.0, "1e3x", "e3", 100.0, 12]
    assert [type(v) for v in data["set"]["a.b"]] == [float, float, str, str, float, int]


@pytest.mark.parametrize("loader", ["libyaml", "python"])
def test_a_yaml_syntax_error_is_one_line_with_its_file_line_and_column(loader, tmp_path, monkeypatch):
    """A mis-indented key, an unclosed bracket, ``a: b: c``: the file, the line (1-based) and the
    column where the parser stopped, PyYAML's (or libyaml's) problem and the construct it was in."""
    from dgraph.files import source

    if loader == "python":
        monkeypatch.setattr(source, "_SAFE_LOADER", source.PythonLoader)
    cases = [
        ("name: x\nentities:\n  a: {type: Gain}\n   b: {type: Gain}\n", 4, 4,
         "in a block mapping started at line 3, column 3 (check the indentation)"),
        ("name: x\nentities:\n  a: {type: Gain}\nplugs: [a.output -> a.input\n", 5, 1,
         "in a flow sequence started at line 4, column 8"),
        ("entities: {}\nname: a: b\n", 2, 8, "mapping values are not allowed"),
    ]
    for text, line, column, fragment in cases:
        path = write(tmp_path, "bad.yaml", text)
        error = refused(dg.load, path)
        message = str(error)
        assert (error.file, error.line) == (str(path), line), message
        assert message.startswith(f"{path}:{line}: invalid YAML at column {column}: "), message
        assert fragment in message and "\n" not in message, message


def test_set_options_are_read_by_the_files_loader_and_their_errors_name_the_option(tmp_path):
    """``--set`` texts read with the graph files' loader (``1e3`` a float, ``[1, 2]`` a list); a text
    that is not YAML, a mapping, no value or a value the graph refuses: an error naming the
    option (``--set k.gain``) and the text, without the line of a document it was wrapped in."""
    from dgraph.files import COMMAND_LINE, command_line_settings

    path = write(tmp_path, "graph.yaml", GOOD)
    g = dg.load(path, command_line_settings(["k.gain=1e3", "dev.q0=[1, 2]"]))
    assert g["k.gain"].value == 1000.0 and list(g["dev.q"].value) == [1.0, 2.0]
    for item, fragment in [("k.gain=[1,", "'[1,': invalid YAML at its end"),
                           ("k.gain={a: 1", "'{a: 1': invalid YAML at its end: "),
                           ("k.gain=\"x", "'\"x': invalid YAML at column 3"),
                           ("k.gain=a: b", "'a: b': expected a scalar or a list, got a mapping"),
                           ("k.gain=", "missing value"), ("k.gain= ", "missing value")]:
        error = refused(command_line_settings, [item])
        assert (error.file, error.line, error.key) == (COMMAND_LINE, None, "--set k.gain"), str(error)
        assert str(error).startswith(f"{COMMAND_LINE} [--set k.gain]: {fragment}"), str(error)
        assert "line" not in str(error).removeprefix(COMMAND_LINE) and "\n" not in str(error), str(error)
    for overrides in (command_line_settings(["k.gain=abc"]), {"k.gain": "[1,"}):
        error = refused(dg.load, path, overrides)
        located(error, COMMAND_LINE, None, "--set k.gain")
        assert "expected a scalar float" in str(error)
    assert "expected entity.name=value" in str(refused(command_line_settings, ["k=1"]))


DID_YOU_MEAN_BASE = """\
name: x
entities:
  com: {type: Sinusoid, params: {amplitude: 1.0, frequency: 1.0}}
  k: {type: Gain}
"""


@pytest.mark.parametrize(("text", "line", "key", "fragment"), [
    (DID_YOU_MEAN_BASE + "plugs: [comm.output -> k.input]\n", 5, "plugs.0",
     "no entity named 'comm' in the graph; did you mean 'com'?"),
    (DID_YOU_MEAN_BASE + "plugs: [com.output -> kk.input]\n", 5, "plugs.0",
     "no entity named 'kk' in the graph; did you mean 'k'?"),
    (DID_YOU_MEAN_BASE + "plugs: [com.outptu -> k.input]\n", 5, "plugs.0",
     "com (Sinusoid) has no signal 'outptu'; it has: output, velocity, acceleration; did you mean 'output'?"),
    (DID_YOU_MEAN_BASE + "record: [com.velocty]\n", 5, "record.0", "has no signal 'velocty'; it has: output, velocity, "
     "acceleration; did you mean 'velocity'?"),
    (DID_YOU_MEAN_BASE + "set: {k.gian: 2.0}\n", 5, "set.k.gian", "has no signal 'gian'; it has: input, gain, output; "
     "did you mean 'gain'?"),
    (DID_YOU_MEAN_BASE + "set: {com.phse: 1.0}\n", 5, "set.com.phse", "did you mean 'phase'?"),
    (DID_YOU_MEAN_BASE.replace("frequency: 1.0", "frequency: 1.0, phse: 0.0"), 3, "entities.com.params.phse",
     "com (Sinusoid): unknown parameter(s) phse; known: amplitude, frequency, phase, offset, ramp, dt; "
     "did you mean 'phase'?"),
])
def test_an_unknown_entity_signal_or_parameter_suggests_the_closest_name(text, line, key, fragment):
    """An unknown entity in a plug, an unknown signal of a known entity (plug, record, set) and an
    unknown parameter: located at their key, the closest name suggested; none when none is close."""
    error = refused(loads, text)
    located(error, "<string>", line, key)
    assert fragment in str(error), str(error)
    far = refused(loads, DID_YOU_MEAN_BASE + "plugs: [com.zzz -> k.input]\n")
    assert "did you mean" not in str(far) and "has no signal 'zzz'" in str(far)
