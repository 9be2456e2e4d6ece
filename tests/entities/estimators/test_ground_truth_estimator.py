"""GroundTruthEstimator: a pass-through with the same q / v outputs as a real estimator."""

from __future__ import annotations

import numpy as np
import pytest
from synthetic_talos import DT, Playback, generate

import dgraph as dg
from dgraph.entities.estimators import GroundTruthEstimator


def test_passes_the_true_state_through():
    traj = generate(0.05)
    g = dg.Graph(dt=DT)
    dev = g.add(Playback("sim", trajectory=traj))
    est = g.add(GroundTruthEstimator("est"))
    g.plug(dev.q, est.q_true)
    g.plug(dev.v, est.v_true)
    for i in range(len(traj) - 1):
        assert np.array_equal(est.q(g.t), traj.q[i]) and np.array_equal(est.v(g.t), traj.v[i])
        g.step()
    assert est.q.count == len(traj) - 1
    assert dg.get_type("GroundTruthEstimator") is GroundTruthEstimator


def test_sizes_are_parameters():
    est = GroundTruthEstimator("est", nq=7, nv=6)
    assert est.q.spec.shape == (7,) and est.v_true.spec.shape == (6,)
    est.q_true.set(np.arange(7.0))
    assert np.array_equal(est.q(0), np.arange(7.0))
    with pytest.raises(dg.SpecError):
        est.v_true.set(np.zeros(7))
