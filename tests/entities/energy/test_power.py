"""Task storage and tank powers (thesis Eqs. 5.5-5.25): the identities of §7 of the Ch. 5 notes."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dgraph.entities.energy.power import (
    TaskBlock,
    stack,
    stiffness,
    task_power,
    task_space_inertia,
    uncontrollable_power,
)


def random_problem(rng, nv=8, rows=(3, 6, 4), gains=None):
    """Random SPD M, a stacked skinny J of full column rank (sum(rows) >= nv), random state."""
    a = rng.normal(size=(nv, nv))
    mass = a @ a.T + nv * np.eye(nv)
    v = rng.normal(size=nv)
    blocks = []
    for i, m in enumerate(rows):
        jacobian = rng.normal(size=(m, nv))
        kp = np.full(m, gains[i] if gains else rng.uniform(1, 100))
        e_dot = rng.normal(size=m)
        blocks.append(TaskBlock(rng.normal(size=m), e_dot, jacobian @ v, rng.normal(size=m), rng.normal(size=m), kp,
                                rng.uniform(0, 20, size=m), jacobian))
    return mass, v, blocks


def pinv_skinny(jacobian):
    return np.linalg.solve(jacobian.T @ jacobian, jacobian.T)  # (J^T J)^-1 J^T, Eq. 5.9


@given(st.integers(0, 10_000))
@settings(max_examples=40, deadline=None)
def test_pseudo_inverse_identities_for_a_stacked_skinny_jacobian(seed):
    rng = np.random.default_rng(seed)
    mass, _, blocks = random_problem(rng)
    jacobian = stack(blocks).jacobian
    j_pinv = pinv_skinny(jacobian)
    inertia = task_space_inertia(jacobian, mass, np.linalg.inv(mass))
    scale = np.abs(inertia).max()
    assert np.allclose(j_pinv @ jacobian, np.eye(mass.shape[0]), atol=1e-9)                      # 5.9
    assert np.allclose(inertia, j_pinv.T @ mass @ j_pinv, atol=1e-9 * scale)                     # 5.10
    assert np.allclose(jacobian.T @ inertia, mass @ j_pinv, atol=1e-9 * np.abs(mass).max())      # 5.14


def test_per_task_inertia_is_the_operational_space_inertia():
    rng = np.random.default_rng(1)
    mass, _, blocks = random_problem(rng)
    jacobian = blocks[0].jacobian  # fat (3 x 8): (J M^-1 J^T)^-1, which differs from J^+T M J^+ (errata E13)
    inertia = task_space_inertia(jacobian, mass, np.linalg.inv(mass))
    assert np.allclose(inertia, np.linalg.inv(jacobian @ np.linalg.solve(mass, jacobian.T)))
    j_pinv = np.linalg.pinv(jacobian)
    assert not np.allclose(inertia, j_pinv.T @ mass @ j_pinv, atol=1e-3)


@given(st.integers(0, 10_000), st.floats(0.0, 1.0), st.booleans())
@settings(max_examples=60, deadline=None)
def test_energy_balance_identity_5_25(seed, scale, equal_gains):
    """-v^T (M a + h - tau_ext) = s (S_dot + B_sigma) - B_phi for a = J^+ s (X_ddot* - J_dot v - Kp E - Kd E_dot)."""
    rng = np.random.default_rng(seed)
    nv = 8
    mass, v, blocks = random_problem(rng, nv, gains=[30.0, 30.0, 30.0] if equal_gains else None)
    block = stack(blocks)
    inertia = task_space_inertia(block.jacobian, mass, np.linalg.inv(mass))
    lam_dot = rng.normal(size=inertia.shape)
    rate = (lam_dot + lam_dot.T) * block.kp  # d(Lambda K_P)/dt for a symmetric Lambda_dot
    bias = rng.normal(size=nv)
    # two contacts (12 corner forces each) and a force task (3D point force)
    contacts = [(rng.normal(size=(6, nv)), rng.normal(size=(6, 12)), rng.normal(size=12)) for _ in range(2)]
    force_jacobian, force_reference = rng.normal(size=(3, nv)), rng.normal(size=3)
    desired = block.reference_acceleration - block.drift - block.kp * block.error - block.kd * block.error_velocity
    a = pinv_skinny(block.jacobian) @ (scale * desired)
    tau_ext = sum(j.T @ t @ f for j, t, f in contacts) + force_jacobian.T @ (scale * force_reference)
    left = -v @ (mass @ a + bias - tau_ext)

    power = task_power(block, inertia, rate)
    controllable = power.controllable_power + (force_jacobian @ v) @ force_reference
    uncontrollable = uncontrollable_power(v, bias, sum((j @ v) @ (t @ f) for j, t, f in contacts))
    right = scale * (power.storage_rate + controllable) - uncontrollable
    assert left == pytest.approx(right, rel=1e-9, abs=1e-9 * (abs(left) + 1.0))


def test_storage_is_nonnegative_with_equal_gains_per_task():
    rng = np.random.default_rng(3)
    for _ in range(200):
        mass, _, blocks = random_problem(rng)
        inverse = np.linalg.inv(mass)
        for block in blocks:  # K_P = k I within each block
            inertia = task_space_inertia(block.jacobian, mass, inverse)
            assert task_power(block, inertia, np.zeros_like(inertia)).storage >= 0.0


def test_unequal_gains_can_make_the_stacked_storage_form_indefinite():
    """sym(Lambda K_P) is indefinite for some unequal gains (errata E4): S >= 0 is not guaranteed."""
    rng = np.random.default_rng(4)
    found = False
    for _ in range(200):
        mass, _, blocks = random_problem(rng, gains=[1.0, 1000.0, 1.0])
        block = stack(blocks)
        p = stiffness(block, task_space_inertia(block.jacobian, mass, np.linalg.inv(mass)))
        if np.linalg.eigvalsh(0.5 * (p + p.T)).min() < -1e-9:
            found = True
            break
    assert found


@pytest.mark.parametrize("gains", [(40.0, 40.0, 40.0), (1.0, 10.0, 100.0)])
def test_storage_rate_matches_the_finite_difference_of_storage(gains):
    """S_dot (with P_dot from the tank's finite difference) is the derivative of S: O(dt), also
    with unequal gains in a task (a posture task's per-joint K_P, errata E4), where ``Lambda K_P``
    is not symmetric and only its symmetric part stores energy."""
    rng = np.random.default_rng(5)
    nv, m = 6, 3
    a = rng.normal(size=(nv, nv))
    mass0 = a @ a.T + nv * np.eye(nv)
    j0, j1 = rng.normal(size=(m, nv)), rng.normal(size=(m, nv))
    e0, e1 = rng.normal(size=m), rng.normal(size=m)
    kp = np.array(gains)

    def at(time):
        jacobian = j0 + time * j1 + 0.3 * np.sin(time) * j1
        mass = mass0 * (1.0 + 0.2 * np.sin(2 * time))
        error, error_rate = e0 * np.cos(time) + e1 * time, -e0 * np.sin(time) + e1
        block = TaskBlock(error, error_rate, np.zeros(m), np.zeros(m), np.zeros(m), kp, np.zeros(m), jacobian)
        return block, task_space_inertia(jacobian, mass, np.linalg.inv(mass))

    errors = []
    for dt in (1e-3, 5e-4):
        t = 0.4
        block_before, inertia_before = at(t - dt)
        block, inertia = at(t)
        block_after, inertia_after = at(t + dt)
        rate = (stiffness(block, inertia) - stiffness(block_before, inertia_before)) / dt
        s_dot = task_power(block, inertia, rate).storage_rate
        s_after = task_power(block_after, inertia_after, rate).storage
        s_now = task_power(block, inertia, rate).storage
        errors.append(abs((s_after - s_now) / dt - s_dot))
    assert errors[1] < 0.7 * errors[0]  # first order in dt
    assert errors[1] < 1e-2 * max(1.0, abs(s_dot))


def test_fixed_base_reduction_keeps_the_balance():
    """N = I, v = q_dot (a fixed-base arm): the same identity, no unactuated rows."""
    rng = np.random.default_rng(6)
    nv = 6
    mass, v, blocks = random_problem(rng, nv, rows=(3, 3, 6), gains=[50.0, 50.0, 50.0])
    block = stack(blocks)
    inertia = task_space_inertia(block.jacobian, mass, np.linalg.inv(mass))
    bias = rng.normal(size=nv)
    a = pinv_skinny(block.jacobian) @ (block.reference_acceleration - block.drift - block.kp * block.error
                                       - block.kd * block.error_velocity)
    tau = mass @ a + bias  # N^T tau with N = I
    power = task_power(block, inertia, np.zeros_like(inertia))
    assert -v @ tau == pytest.approx(power.storage_rate + power.controllable_power - uncontrollable_power(v, bias, 0.0),
                                     rel=1e-9)


def test_rank_deficient_jacobians_fall_back_to_the_pseudo_inverse():
    rng = np.random.default_rng(7)
    mass, _, blocks = random_problem(rng)
    inverse = np.linalg.inv(mass)
    fat = np.vstack([blocks[0].jacobian, blocks[0].jacobian[:1]])  # a repeated row: J M^-1 J^T singular
    inertia = task_space_inertia(fat, mass, inverse)
    product = fat @ inverse @ fat.T
    assert np.allclose(product @ inertia @ product, product, atol=1e-9)  # a generalized inverse
    assert np.allclose(inertia, np.linalg.pinv(product, rcond=1e-9, hermitian=True), atol=1e-8)
    skinny = np.vstack([blocks[1].jacobian, blocks[1].jacobian])[:, :7]  # 12 x 7 of rank 6
    skinny = np.hstack([skinny, skinny[:, :1]])  # rank-deficient columns
    inertia = task_space_inertia(skinny, mass, inverse)
    product = skinny @ inverse @ skinny.T
    assert np.allclose(product @ inertia @ product, product, atol=1e-8)
