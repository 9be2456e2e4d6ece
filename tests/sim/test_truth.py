"""dgraph_sim.truth: the CoM and frames of recorded configurations."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from dgraph.entities.robot import load_model
from dgraph_sim.truth import true_com_and_frames


def test_each_configuration_gives_pinocchios_com_and_frame_positions():
    model = load_model("talos")
    half_sitting = model.referenceConfigurations["half_sitting"]
    moved = half_sitting.copy()
    moved[:3] += [0.3, -0.2, 0.05]  # the base moved: every point moves with it
    com, frames = true_com_and_frames(np.array([half_sitting, moved]), ["left_sole_link", "right_sole_link"])
    assert com.shape == (2, 3) and frames.shape == (2, 2, 3)
    data = model.createData()
    np.testing.assert_allclose(com[0], pin.centerOfMass(model, data, half_sitting), atol=1e-12)
    np.testing.assert_allclose(com[1] - com[0], [0.3, -0.2, 0.05], atol=1e-12)
    np.testing.assert_allclose(frames[1] - frames[0], [[0.3, -0.2, 0.05]] * 2, atol=1e-12)
    assert frames[0, 0, 1] > 0.05 > -0.05 > frames[0, 1, 1]  # the left sole on the left
