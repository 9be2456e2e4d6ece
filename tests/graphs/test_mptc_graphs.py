"""TALOS under the Modular Passive Tracking Controller in MuJoCo, the estimator in the loop (issue
15's acceptance): graphs/talos_mptc_standing.yaml stands 10 s, graphs/talos_walk_20cm_mptc.yaml
walks the 20 cm plan of the ID solver's walk without a fall and ends where planned. Ground truth
comes from the simulator's configuration ``device.q``."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def standing(walks):
    return walks("talos_mptc_standing")


@pytest.fixture(scope="module")
def walk(walks):
    return walks("talos_walk_20cm_mptc")


def test_mptc_stands_ten_seconds_holding_its_com(standing):
    graph, data, com, _ = standing
    assert graph.t * graph.dt == pytest.approx(10.0)
    assert not data["device.fallen"].any()
    assert (data["solver.status"] == 0).all()
    reference = data["com_reference.output"]
    assert np.abs(com - reference).max() < 0.01  # true CoM within 1 cm of its reference throughout
    assert np.abs(data["solver.task_storage"]).max() < 1.0  # J: the tasks stay near their references


def test_mptc_walks_the_20cm_plan_and_ends_where_planned(walk):
    graph, data, com, soles = walk
    assert not data["device.fallen"].any()
    assert (data["solver.status"] == 0).all()
    final = graph["footsteps"].plan(0).final_midpoint()
    assert final[0] == pytest.approx(1.2, abs=0.02)
    assert np.linalg.norm(soles[-1].mean(axis=0)[:2] - final[:2]) < 0.05
    assert np.abs(com[:, :2] - data["pattern.com_position"][:, :2]).max() < 0.03  # true CoM vs plan


def test_the_passivity_signals_are_consistent_on_the_walk(walk):
    _, data, _, _ = walk
    storage = data["solver.task_storage"]
    assert (storage >= -1e-9).all()  # V_k is a sum of quadratic forms with M_k, K_k positive definite
    np.testing.assert_allclose(data["solver.weighted_storage"], storage.sum(axis=1), rtol=1e-9, atol=1e-9)  # psi 1
    assert np.isfinite(data["solver.residual_power"]).all()
    # the bounds and the rigid feet do act during the walk: the weighting's identity is then not exact
    assert np.abs(data["solver.residual_power"]).max() > 1e-6
