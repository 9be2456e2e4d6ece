"""ActuatorModel: the chain's current, saturation, delivered and sensed torque (thesis Eqs. 3.1-3.4)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.actuators import ActuatorModel
from dgraph.entities.actuators.chain import TALOS_ELBOW_R_KM, ChainFileError, load_chain_file

FILE = Path(__file__).parents[3] / "graphs" / "data" / "talos_actuators.yaml"
ELBOWS = ["arm_left_4_joint", "arm_right_4_joint"]


def model(**params):
    g = dg.Graph(dt=0.001)
    return g.add(ActuatorModel("chain", joints=ELBOWS, path=str(FILE), **params))


def test_file_holds_table_3_1_and_the_gap_filler():
    chains = load_chain_file(FILE)
    elbow = chains["arm_left_4_joint"]
    assert chains["arm_right_4_joint"] == elbow
    assert (elbow.I_m, elbow.F_vm, elbow.F_sm, elbow.off_m, elbow.F_vj, elbow.F_sj, elbow.off_j) == \
        (0.45, 5.1, 4.0, 0.86, 0.47, 0.55, -0.27)
    assert elbow.R_Km == pytest.approx(TALOS_ELBOW_R_KM) and TALOS_ELBOW_R_KM * 6.0 == pytest.approx(17.86)
    assert (elbow.K_j, elbow.i_max) == (1.015, 6.0)


def test_current_and_torques_follow_the_chain_equations():
    a = model()
    tau, qd, qdd = np.array([5.0, -6.0]), np.array([0.4, -1.2]), np.array([2.0, -3.0])
    a.tau_desired.set(tau)
    a.q_dot.set(qd)
    a.q_ddot.set(qdd)
    tau_fm = 5.1 * qd + 4.0 * np.sign(qd) + 0.86
    expected = (tau + 0.45 * qdd + tau_fm) / TALOS_ELBOW_R_KM  # hand-written Eq. 3.1 - 3.3
    assert a.current(0) == pytest.approx(expected)
    assert not a.saturated(0).any()
    assert a.joint_torque(0) == pytest.approx(tau)  # unsaturated: delivers what was asked
    assert a.sensor_torque(0) == pytest.approx(tau / 1.015)
    assert a.motor_torque(0) == pytest.approx(TALOS_ELBOW_R_KM * expected)


def test_saturation_limits_the_current_and_the_delivered_torque():
    a = model()
    a.tau_desired.set([30.0, -30.0])
    a.q_dot.set([0.0, 0.0])
    assert a.current(0) == pytest.approx([6.0, -6.0])
    assert a.saturated(0).tolist() == [True, True]
    # at rest sign(0) = 0: only the offset off_m is compensated
    assert a.joint_torque(0) == pytest.approx([17.86 - 0.86, -17.86 - 0.86])


def test_smoothing_is_tanh():
    a = model(smoothing=1000.0)
    a.tau_desired.set([0.0, 0.0])
    a.q_dot.set([1e-3, 0.0])
    assert a.current(0) * TALOS_ELBOW_R_KM == pytest.approx([5.1e-3 + 4.0 * np.tanh(1.0) + 0.86, 0.86])


def test_controller_armature_is_not_compensated_twice():
    # tau_j* from Pinocchio holds 0.1 q_ddot of armature: only I_m - 0.1 = 0.35 is added
    a = model(controller_armature=0.1)
    a.tau_desired.set([2.0, 2.0])
    a.q_dot.set([0.0, 0.0])
    a.q_ddot.set([3.0, -3.0])
    assert a.current(0) * TALOS_ELBOW_R_KM == pytest.approx([2.0 + 0.35 * 3.0 + 0.86, 2.0 - 0.35 * 3.0 + 0.86])
    assert a.joint_torque(0) == pytest.approx([2.0 - 0.1 * 3.0, 2.0 + 0.1 * 3.0])  # the link's part of tau_j*
    per_joint = model(controller_armature=[0.1, 0.45])
    per_joint.tau_desired.set([0.0, 0.0])
    per_joint.q_dot.set([0.0, 0.0])
    per_joint.q_ddot.set([1.0, 1.0])
    assert per_joint.current(0) * TALOS_ELBOW_R_KM == pytest.approx([0.35 + 0.86, 0.86])
    with pytest.raises(dg.ParamError, match="controller_armature"):
        model(controller_armature=[0.1, 0.1, 0.1])


def test_offsets_can_be_left_to_a_plant_without_them():
    a = model(compensate_offsets=False)
    a.tau_desired.set([1.0, -1.0])
    a.q_dot.set([0.5, 0.0])
    assert a.current(0) * TALOS_ELBOW_R_KM == pytest.approx([1.0 + 5.1 * 0.5 + 4.0, -1.0])
    assert a.joint_torque(0) == pytest.approx([1.0, -1.0])
    assert a.motor_friction(np.array([0.0, 0.0])) == pytest.approx([0.0, 0.0])
    assert model().motor_friction(np.array([0.0, 0.0])) == pytest.approx([0.86, 0.86])


def test_q_ddot_defaults_to_zero():
    a = model()
    a.tau_desired.set([1.0, 1.0])
    a.q_dot.set([1.0, 1.0])
    assert a.current(0) == pytest.approx((1.0 + 5.1 + 4.0 + 0.86) / TALOS_ELBOW_R_KM)


@pytest.mark.parametrize(("text", "match"), [
    ("joints: [1, 2", "line 1"),
    ("joints:\n  arm_left_4_joint: {R_Km: 3.0}\n", "arm_left_4_joint.*missing.*i_max"),
    ("joints:\n  arm_left_4_joint: {R_Km: 3.0, i_max: 6.0, Km: 1}\n", "unknown parameter.*Km"),
    ("joints:\n  arm_left_4_joint: {R_Km: -3.0, i_max: 6.0}\n", "R_Km must be positive"),
    ("joints:\n  arm_left_4_joint: {R_Km: !!python/object:os.system x, i_max: 6.0}\n", "not valid YAML"),
    ("other: 1\n", "'joints'"),
    # a joint written twice: YAML would keep the last silently
    ("joints:\n  arm_left_4_joint: {R_Km: 3.0, i_max: 6.0}\n  arm_left_4_joint: {R_Km: 9.0, i_max: 6.0}\n",
     "line 3: duplicate key 'arm_left_4_joint' \\(first at line 2\\)"),
    ("joints:\n  arm_left_4_joint:\n    R_Km: 3.0\n    i_max: 6.0\n    R_Km: 9.0\n", "line 5: duplicate key 'R_Km'"),
])
def test_bad_files_are_located(tmp_path, text, match):
    bad = tmp_path / "chains.yaml"
    bad.write_text(text)
    with pytest.raises(ChainFileError, match=match):
        load_chain_file(bad)
    with pytest.raises(dg.ParamError, match="path"):
        ActuatorModel("chain", joints=["arm_left_4_joint"], path=str(bad))


def test_unknown_joint_is_refused():
    with pytest.raises(dg.ParamError, match="arm_left_3_joint"):
        ActuatorModel("chain", joints=["arm_left_3_joint"], path=str(FILE))


def test_graph_file_loads_it(tmp_path):
    (tmp_path / "chains.yaml").write_text(FILE.read_text())
    graph = tmp_path / "g.yaml"
    graph.write_text("name: chain\ndt: 0.001\nentities:\n  chain: {type: ActuatorModel, params: "
                     "{joints: [arm_left_4_joint], path: chains.yaml}}\nset:\n  chain.tau_desired: [1.0]\n"
                     "  chain.q_dot: [0.0]\n")
    with dg.load(str(graph)) as g:
        assert g.entities["chain"].current(0) == pytest.approx([(1.0 + 0.86) / TALOS_ELBOW_R_KM])
