"""Scenario 2 of thesis Ch. 6: TALOS pushes a wall standing (graphs/talos_wall_push.yaml).

bench/wall_push.py's runs and failure criteria. With the energy tank, 20 N is held (force error under
10 % in steady state, no slip, no fall, the feet's CoP inside their soles). Without the tank, on the
staircase 20 N then 80 N: 80 N is beyond what it holds (bench/wall_push.py measured the plain QP
failing at 70 N: CoP at the heels, a foot unloaded): the QP's CoP bound and a friction pyramid
saturate and the failure criteria trip. 5 s simulated.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import wall_push  # noqa: E402

WEIGHT = 885.6  # N: TALOS's m g (bench/wall_push.py statics)


@pytest.fixture(scope="module")
def tank(tmp_path_factory):
    return wall_push.run_staircase("talos_wall_push", [20.0], 1.0, WEIGHT, tmp_path_factory.mktemp("tank"))


@pytest.fixture(scope="module")
def no_tank(tmp_path_factory):
    return wall_push.run_staircase("talos_wall_push_no_tank", [20.0, 80.0], 1.0, WEIGHT,
                                   tmp_path_factory.mktemp("no_tank"), ignore=("slip",))


@pytest.mark.parametrize("name", ["tank", "no_tank"])
def test_20_n_is_held(name, request):
    _, results = request.getfixturevalue(name)
    held = results[0]
    assert held["level"] == 20.0
    assert held["failures"] == []
    assert held["error"] < 0.10
    assert held["slip_mm"] < 2.0 and not held["fallen"]
    assert held["cop_margin_mm"] > 5.0 and held["qp_cop_margin_mm"] > 5.0


def test_80_n_saturates_the_feet_and_trips_the_criteria(no_tank):
    _, results = no_tank
    assert len(results) == 2
    beyond = results[1]
    assert beyond["level"] == 80.0
    assert beyond["qp_cop_margin_mm"] < 1.0        # the QP's CoP (corner forces >= 0) bound binds
    assert beyond["qp_friction"] > 0.99            # and a foot's friction pyramid
    assert {"CoP at edge", "foot unloaded"} <= set(beyond["failures"])
