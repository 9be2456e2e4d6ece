"""The lifting scenario (issue 17 A.5): TALOS raises its left forearm and holds a load stepped up
to the thesis's 34 kg at 5 cm from the elbow; the elbow's torque goes through TorqueProtection,
the motor torque R K_m i drives MuJoCo's elbow (the chain's armature and friction), ThermalModel
heats on that current. Two runs of graphs/talos_lift_load.yaml (8 s at 1 kHz, about 11 s of wall
time each): as shipped, and with the protection bypassed (``chain.selection: 1``: ActuatorModel, the
same demand i* clipped at i_max); the tests assert on what the Recorder kept.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.actuators.chain import load_chain_file

pytestmark = pytest.mark.sim

ROOT = Path(__file__).resolve().parents[2]
ELBOW = load_chain_file(ROOT / "graphs" / "data" / "talos_actuators.yaml")["arm_left_4_joint"]
I_MAX = ELBOW.i_max  # A, the elbow's limit (6 A)
T_MAX = 100.0  # °C, ThermalModel's default limit
HOLD = slice(7_000, 7_999)  # ticks: the 34 kg hold, after the last step's ramp (6.4-6.6 s) has settled


def run(tmp: Path, **settings: object) -> dict[str, np.ndarray]:
    graph = dg.load(str(ROOT / "graphs" / "talos_lift_load.yaml"),
                    {"recorder.rrd_path": str(tmp / "lift.rrd"), "view.rerun": "off", **settings})
    with graph:
        graph.run(duration=graph.duration, progress=False)
    return graph["recorder"].data()


@pytest.fixture(scope="module")
def lift(tmp_path_factory) -> dict[str, np.ndarray]:
    return run(tmp_path_factory.mktemp("lift_load"))


@pytest.fixture(scope="module")
def bypassed(tmp_path_factory) -> dict[str, np.ndarray]:
    return run(tmp_path_factory.mktemp("lift_load_bypassed"), **{"chain.selection": 1})


def test_the_barrier_not_the_clip_keeps_the_current_under_its_limit(lift):
    """``current`` is clipped to ±i_max, so ``|i| <= i_max`` alone proves nothing: the clip must
    never act (``saturated``) and the current stays 1 % under the limit (5.79 A measured)."""
    current = lift["protection.current"][:, 0]
    assert current.size == 8_000
    assert not lift["protection.saturated"].any()
    assert np.abs(current).max() < 0.99 * I_MAX


def test_the_protection_is_what_limits_the_current_while_the_34_kg_is_held(lift):
    assert np.all(lift["load.position"][HOLD, 0] == 34.0)
    current = np.abs(lift["protection.current"][HOLD, 0])
    demand = np.abs(lift["protection.reference_current"][HOLD, 0])  # i* from the QP's torque, unfiltered
    plateau = current.max()
    assert np.all(current > 0.95 * plateau)  # a plateau: within 5 % for the whole second
    assert np.all(demand > I_MAX)  # the QP asks more than the limit: the protection holds it back
    assert np.all(demand > current + 1.0)


def test_without_the_protection_the_demanded_current_exceeds_the_limit(lift):
    """i* is the current that delivers the QP's torque (what a chain without the filter would draw)."""
    demand = np.abs(lift["protection.reference_current"][:, 0])
    assert demand.max() > 1.2 * I_MAX  # 7.85 A measured at 34 kg
    assert np.count_nonzero(demand > I_MAX) > 1_000


def test_bypassed_the_same_demand_is_clipped_at_the_limit(bypassed):
    """Without the barrier (ActuatorModel: the same i*, the same compensation), the chain's clip
    acts whenever the demand passes i_max, only under the load (2655 ticks measured, none unloaded)."""
    demand = bypassed["bypass_chain.current_desired"][:, 0]
    np.testing.assert_allclose(demand, bypassed["protection.reference_current"][:, 0], rtol=1e-12, atol=1e-12)
    saturated = bypassed["bypass_chain.saturated"][:, 0]
    assert np.count_nonzero(saturated) > 1_000
    assert not saturated[bypassed["load.position"][:, 0] == 0.0].any()
    assert np.abs(bypassed["bypass_chain.current"][:, 0]).max() == I_MAX
    assert not bypassed["device.fallen"].any()


def test_the_delivered_torque_falls_short_of_the_commanded_one_once_limited(lift):
    commanded = lift["elbow_tau.output"][HOLD, 0]
    # what MuJoCo's elbow motor applied over tick t, stamped t + 1: R K_m i(t)
    delivered = lift["device.joint_torque"][HOLD.start + 1:HOLD.stop + 1, 17]
    np.testing.assert_allclose(delivered, ELBOW.R_Km * lift["protection.current"][HOLD, 0], rtol=1e-9)
    assert np.all(np.abs(delivered) < np.abs(commanded))


def test_talos_stays_up_and_every_qp_is_solved(lift):
    assert not lift["device.fallen"].any()
    assert lift["device.q"][:, 2].min() > 0.85  # base height (1.02 m at half-sitting)
    assert (lift["solver.status"] == 0).all()


def test_the_elbow_is_raised_and_held_near_its_reference(lift):
    q = lift["elbow_q.output"][:, 0]
    reference = lift["elbow_reference.position"][:, 0]
    assert reference[-1] == pytest.approx(-1.3)
    assert q[0] == pytest.approx(-0.525, abs=0.01)
    assert np.abs(q[3_000:] - reference[3_000:]).max() < 0.1


def test_the_motor_heats_and_stays_under_its_limit(lift):
    temperature = lift["thermal.temperature"][:, 0]
    assert temperature[0] == pytest.approx(43.0)
    assert temperature[-1] - temperature[0] > 0.1
    assert temperature.max() < T_MAX
