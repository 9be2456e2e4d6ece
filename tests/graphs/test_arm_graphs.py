"""A fixed-base arm in MuJoCo under the inverse-dynamics QP: the Panda of example-robot-data reaches.

``graphs/panda_reach.yaml`` runs 3 s: the tool centre point follows a 2 s minimum-jerk move of
0.29 m (from 0.2 s to 2.2 s) with its orientation held. Ground truth is the simulator's ``q``
through Pinocchio's forward kinematics. The same graph runs once more with the robot given as
the path of the Panda's URDF file (no SRDF: the posture and ``q0`` are set).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.robot import load_robot

ROOT = Path(__file__).resolve().parents[2]
TARGET = np.array([0.45, 0.2, 0.3])
FRAME = "panda_hand_tcp"


def run(tmp: Path, graph_file: Path = ROOT / "graphs" / "panda_reach.yaml") -> tuple[dg.Graph, dict, list[float]]:
    """Run the graph; its recording, and ``||M a + h - tau||_inf`` of the QP's solution every 100 ticks."""
    graph = dg.load(str(graph_file), {"recorder.npz_path": str(tmp / "reach.npz"),
                                      "recorder.rrd_path": str(tmp / "reach.rrd")})
    residuals: list[float] = []

    def dynamics_residual(t: int) -> None:
        if t % 100 == 0:
            state, solution = graph["robot"].state(t), graph["solver"].solution(t)
            residuals.append(float(np.abs(state.mass_matrix @ solution.acceleration + state.bias_forces
                                          - solution.tau).max()))

    graph["device"].before.add(dynamics_residual)
    with graph:
        graph.run(duration=graph.duration, progress=False)
    return graph, graph["recorder"].data(), residuals


def tool_positions(graph: dg.Graph, q: np.ndarray) -> np.ndarray:
    model = graph["robot"].pin_model
    data, frame = model.createData(), model.getFrameId(FRAME)
    out = []
    for qi in q:
        pin.framesForwardKinematics(model, data, qi)
        out.append(data.oMf[frame].translation.copy())
    return np.array(out)


@pytest.fixture(scope="module")
def reach(tmp_path_factory):
    return run(tmp_path_factory.mktemp("panda_reach"))


def test_the_panda_reaches_its_target_within_a_millimetre(reach):
    graph, rec, _ = reach
    assert graph["device"].sim.robot.floating_base is False and graph["device"].nq == 9
    position = tool_positions(graph, rec["device.q"])
    error = np.linalg.norm(position - TARGET, axis=1)
    time = rec["time"]
    assert error[0] > 0.28                                       # it starts 0.29 m away
    assert error[time >= 2.3].max() < 1e-3                       # 0.1 s after the move ends: < 1 mm (0.36 mm)
    tracking = np.linalg.norm(position - rec["hand_position.output"], axis=1)
    assert tracking.max() < 2e-3                                 # the moving reference is tracked (0.45 mm)
    assert np.abs(rec["hand.error"][time >= 2.3, 3:]).max() < 2e-3  # the orientation is held (rad)


def test_torques_stay_within_the_urdf_limits_and_everything_is_finite(reach):
    graph, rec, residuals = reach
    limits = graph["robot"].pin_model.effortLimit
    for key in ("device.joint_torque", "solver.tau"):
        assert np.isfinite(rec[key]).all()
        assert (np.abs(rec[key]) <= limits + 1e-6).all(), key
    for key in ("device.q", "hand.error", "hand_position.output"):
        assert np.isfinite(rec[key]).all(), key
    assert not rec["solver.status"].any()                        # every QP solved
    assert max(residuals) < 1e-6                                 # tau = M a + h: fixed base, no contact
    assert len(rec["fault_tick"]) == 0


def urdf_reach(robot: str, device: str = "") -> str:
    """``panda_reach.yaml`` with ``robot`` a URDF path (no SRDF: the posture and ``q0`` set) and
    ``device`` added to the device's parameters."""
    default = np.array(load_robot("panda").q0)
    text = (ROOT / "graphs" / "panda_reach.yaml").read_text()
    text = text.replace("robot: panda ", f"robot: {robot} ")
    text = text.replace("params: {reference_configuration: default}", "params: {reference_configuration: ''}")
    text = text.replace("control_mode: torque}", f"control_mode: torque, q0: {default.tolist()}{device}}}")
    return text.replace("record: [", f"  posture.reference: {default.tolist()}\nrecord: [")


def test_a_urdf_path_runs_the_same_reach(tmp_path):
    urdf = load_robot("panda").urdf                              # the installed file: nothing is downloaded
    graph_file = tmp_path / "panda_urdf_reach.yaml"
    graph_file.write_text(urdf_reach(urdf))
    graph, rec, _ = run(tmp_path, graph_file)
    assert graph["device"].model == urdf and graph["robot"].model == urdf
    error = np.linalg.norm(tool_positions(graph, rec["device.q"]) - TARGET, axis=1)
    assert error[rec["time"] >= 2.3].max() < 1e-3
    assert not rec["solver.status"].any() and np.isfinite(rec["device.joint_torque"]).all()


def test_a_urdf_next_to_the_graph_file_is_found_from_any_working_directory(tmp_path):
    """``robot: arm.urdf`` and ``package_dirs: [deps]`` are the graph file's, as ``mjcf`` is: checked
    from another folder, saved elsewhere (written relative to the saved file), loaded again."""
    project, elsewhere = tmp_path / "project", tmp_path / "elsewhere"
    project.mkdir(), elsewhere.mkdir()
    urdf = load_robot("panda").urdf
    shutil.copy(urdf, project / "arm.urdf")  # meshes: package://example-robot-data/robots/... under deps
    os.symlink(os.path.realpath(os.path.join(os.path.dirname(urdf), "..", "..", "..", "..")), project / "deps")
    graph_file = project / "arm.yaml"
    graph_file.write_text(urdf_reach("arm.urdf", ", package_dirs: [deps]"))
    checked = subprocess.run([sys.executable, "-m", "dgraph", "check", str(graph_file)], cwd=elsewhere,
                             capture_output=True, text=True, timeout=120)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    graph = dg.load(graph_file)
    assert graph["device"].model == graph["robot"].model == str(project / "arm.urdf")
    assert graph["device"].package_dirs == [str(project / "deps")] and graph["device"].na == 9
    saved = elsewhere / "copy.yaml"
    dg.save(graph, saved)
    written = saved.read_text()
    assert "robot: ../project/arm.urdf" in written and "package_dirs: [../project/deps]" in written
    again = dg.load(saved)
    assert again["device"].model == str(project / "arm.urdf") and again["device"].na == 9
    dg.save(again, project / "copy.yaml")
    assert (project / "copy.yaml").read_text() == written.replace("../project/", "")
