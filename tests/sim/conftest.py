"""Shared fixtures of the simulation tests."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before anything imports mujoco (rendering tests)


def mass_matrices(sim, d, data, q, v):
    """MuJoCo's mass matrix mapped to Pinocchio's velocity coordinates (``T^T M T``), Pinocchio's
    (both halves filled), MuJoCo's own ``M`` and the map ``T``, at ``(q, v)``; ``d`` holds MuJoCo's
    state there after the call (``mj_forward``: its bias forces are up to date)."""
    import mujoco
    import numpy as np
    import pinocchio as pin

    m, jm, model = sim.mj_model, sim.joint_map, sim.pin_model
    jm.qpos_from_q(q, d.qpos)
    jm.qvel_from_v(q, v, d.qvel)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    T = jm.velocity_transform(q)
    M_pin = pin.crba(model, data, q)
    return T.T @ M @ T, np.triu(M_pin) + np.triu(M_pin, 1).T, M, T
