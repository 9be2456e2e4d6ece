"""The LIPM MPC (lipm_mpc.py): condensed predictions, exact sampling, polygons, terminal DCM, failures."""

from __future__ import annotations

import numpy as np
import pytest

from dgraph.control.status import NOT_FINITE, PRIMAL_INFEASIBLE, SOLVED
from dgraph.entities.stabilizers.lipm import GRAVITY
from dgraph.entities.walking.footsteps import straight_walk, turning_walk, yaw_placement
from dgraph.entities.walking.lipm_mpc import (
    CondensedLipm,
    LipmMpc,
    LipmTrajectory,
    pad_polygon,
    padded_polygons,
)

HEIGHT = 0.87
HORIZON = 16
SAMPLING = 0.1
LEFT, RIGHT = yaw_placement([0.0, 0.085, 0.0]), yaw_placement([0.0, -0.085, 0.0])
SOLVER_TOLERANCE = 1e-5  # m: ProxQP's eps_abs is 1e-6


def square(half: float, center: tuple[float, float] = (0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """``|x - cx| <= half``, ``|y - cy| <= half`` as unit-norm half-planes."""
    normals = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
    return normals, half + normals @ np.asarray(center)


def polygons(plan, times: np.ndarray, margin: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
    """The plan's support polygons at ``times``, shrunk by ``margin``, padded."""
    return padded_polygons([plan.support_polygon(time, margin) for time in times])


def receding(plan, period: float, margin: float = 0.02):
    """The MPC re-planned every ``period`` s along ``plan`` from 0.5 s before it to 1.5 s after its
    end, each plan started from the previous one's state (open loop): yields
    ``(result, sample times, (edges, offsets))``."""
    mpc = LipmMpc(HEIGHT)
    state = np.zeros((3, 2))
    state[0] = plan.zmp_reference([-1.0])[0]
    for tick, start in enumerate(np.arange(-0.5, plan.duration + 1.5, period)):
        times = start + SAMPLING * np.arange(1, HORIZON + 1)
        halfplanes = polygons(plan, times, margin)
        result = mpc.solve(state, plan.zmp_reference(times), np.zeros((HORIZON, 2)), halfplanes, tick=tick)
        yield result, times, halfplanes
        state = result.trajectory.sample(period)[:3]


def test_condensed_maps_predict_the_sampled_recursion():
    rng = np.random.default_rng(3)
    initial, jerks = rng.normal(size=(3, 2)), rng.normal(size=(HORIZON, 2))
    model = CondensedLipm(SAMPLING, HORIZON, HEIGHT)
    integrated = LipmTrajectory.from_jerks(initial, jerks, SAMPLING, model.omega)
    zmp = model.zmp_state @ initial + model.zmp_jerk @ jerks
    velocity = model.velocity_state @ initial + model.velocity_jerk @ jerks
    dcm = model.dcm_state @ initial + model.dcm_jerk @ jerks
    np.testing.assert_allclose(zmp, integrated.zmp()[1:], atol=1e-12)
    np.testing.assert_allclose(velocity, integrated.states[1:, 1], atol=1e-12)
    np.testing.assert_allclose(dcm, integrated.dcm()[-1], atol=1e-12)
    np.testing.assert_allclose(LipmMpc(HEIGHT).trajectory(initial, jerks).states, integrated.states, atol=1e-12)


def test_sample_is_the_exact_cubic_between_samples_and_coasts_after_the_horizon():
    rng = np.random.default_rng(4)
    trajectory = LipmTrajectory.from_jerks(rng.normal(size=(3, 2)), rng.normal(size=(4, 2)), SAMPLING, 3.0)
    for k in range(5):
        np.testing.assert_allclose(trajectory.sample(k * SAMPLING)[:3], trajectory.states[k], atol=1e-12)
    step = 1e-6
    for elapsed in (0.013, 0.17, 0.3999, 0.55):  # the last one after the horizon: zero jerk
        before, after = trajectory.sample(elapsed - step), trajectory.sample(elapsed + step)
        derivative = (after[:3] - before[:3]) / (2 * step)
        np.testing.assert_allclose(derivative, trajectory.sample(elapsed)[1:], atol=1e-6)
    np.testing.assert_array_equal(trajectory.sample(0.55)[3], [0.0, 0.0])
    # a fine integration of the constant jerk over the first sample lands on the exact cubic
    state, jerk, dt = trajectory.states[0].copy(), trajectory.jerks[0], 1e-5
    for _ in range(round(0.05 / dt)):
        state = state + dt * np.array([state[1] + dt / 2 * state[2], state[2] + dt / 2 * jerk, jerk])
    np.testing.assert_allclose(state, trajectory.sample(0.05)[:3], atol=1e-8)


def test_a_solved_plan_satisfies_the_cart_table_zmp_to_1e9():
    plan = straight_walk(LEFT, RIGHT)
    results = list(receding(plan, period=0.1))
    assert {result.status for result, _, _ in results} == {SOLVED}
    for result, _, _ in results[::5]:
        trajectory = result.trajectory
        independent = LipmTrajectory.from_jerks(trajectory.states[0], trajectory.jerks, SAMPLING, 1.0)
        zmp = independent.states[:, 0] - HEIGHT / GRAVITY * independent.states[:, 2]
        np.testing.assert_allclose(trajectory.zmp(), zmp, atol=1e-9)


@pytest.mark.parametrize("walk", ["straight", "turning"])
def test_the_zmp_stays_in_the_shrunk_polygons_and_the_final_dcm_in_the_last(walk):
    if walk == "straight":
        plan = straight_walk(LEFT, RIGHT, length=0.6)  # the thesis 60 cm walk: the polygons bind
    else:
        plan = turning_walk(LEFT, RIGHT, steps=6, angle_per_step=0.2, length=0.1)
    worst_zmp = worst_dcm = -np.inf
    tracking = []
    for result, times, (edges, offsets) in receding(plan, period=0.01):
        assert result.status == SOLVED
        zmp = result.trajectory.zmp()[1:]
        worst_zmp = max(worst_zmp, (np.einsum("kmi,ki->km", edges, zmp) - offsets).max())
        worst_dcm = max(worst_dcm, (edges[-1] @ result.trajectory.dcm()[-1] - offsets[-1]).max())
        tracking.append(zmp[0] - plan.zmp_reference(times[:1])[0])
    assert worst_zmp < SOLVER_TOLERANCE
    assert worst_dcm < SOLVER_TOLERANCE
    assert worst_dcm > -1e-4  # the terminal rows bind: without them the horizon's end would leave the feet
    if walk == "straight":
        assert worst_zmp > -1e-4  # 60 cm steps: ZMP rows bind too
    assert np.sqrt(np.mean(np.square(tracking), axis=0)).max() < 0.025
    # the walk ends over the final midpoint
    np.testing.assert_allclose(result.trajectory.states[0, 0], plan.final_midpoint()[:2], atol=1e-3)


def test_the_polygon_rows_of_a_yawed_foot_couple_the_axes():
    mpc = LipmMpc(HEIGHT)
    rotation = np.array([[np.cos(0.4), -np.sin(0.4)], [np.sin(0.4), np.cos(0.4)]])
    normals, offsets = square(0.05)
    edges, offsets = padded_polygons([(normals @ rotation.T, offsets)] * HORIZON)  # a square yawed by 0.4 rad
    result = mpc.solve(np.zeros((3, 2)), np.tile([0.3, 0.3], (HORIZON, 1)), np.zeros((HORIZON, 2)), (edges, offsets))
    assert result.status == SOLVED
    zmp = result.trajectory.zmp()[1:]
    assert (np.einsum("kmi,ki->km", edges, zmp) - offsets).max() < SOLVER_TOLERANCE
    assert (np.einsum("kmi,ki->km", edges, zmp) - offsets).max() > -1e-4  # the reference is outside: rows bind


def test_an_infeasible_problem_reports_its_status_and_the_next_solve_recovers():
    mpc = LipmMpc(HEIGHT)
    apart = (np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([-0.1, -0.1]))  # x <= -0.1 and x >= 0.1
    feasible = padded_polygons([square(0.05)] * HORIZON)
    infeasible = padded_polygons([square(0.05)] * 8 + [apart] * 8)
    zeros = np.zeros((HORIZON, 2))
    first = mpc.solve(np.zeros((3, 2)), zeros, zeros, feasible, tick=0)
    failed = mpc.solve(np.zeros((3, 2)), zeros, zeros, infeasible, tick=1)
    assert (first.status, failed.status, failed.trajectory) == (SOLVED, PRIMAL_INFEASIBLE, None)
    state = np.zeros((3, 2))
    state[1] = 0.1
    recovered = mpc.solve(state, zeros, zeros, feasible, tick=2)
    assert recovered.status == SOLVED
    assert np.abs(recovered.trajectory.dcm()[-1]).max() <= 0.05 + SOLVER_TOLERANCE
    nan_state = np.full((3, 2), np.nan)
    assert mpc.solve(nan_state, zeros, zeros, feasible, tick=3).status == NOT_FINITE


def test_a_shifted_warm_start_reaches_the_cold_solution():
    plan = straight_walk(LEFT, RIGHT)
    warm, cold = LipmMpc(HEIGHT), LipmMpc(HEIGHT)
    state = np.zeros((3, 2))
    zeros = np.zeros((HORIZON, 2))
    for tick, start in enumerate((0.3, 0.5)):  # the second plan starts two samples later
        times = start + SAMPLING * np.arange(1, HORIZON + 1)
        args = (state, plan.zmp_reference(times), zeros, polygons(plan, times))
        result = warm.solve(*args, tick=tick, shift=2 * tick)
        state = result.trajectory.sample(0.2)[:3]
    reference = cold.solve(*args, tick=0)
    np.testing.assert_allclose(result.trajectory.jerks, reference.trajectory.jerks, atol=1e-3)
    np.testing.assert_allclose(result.trajectory.zmp(), reference.trajectory.zmp(), atol=1e-5)


def test_pad_polygon_fills_inactive_rows_and_refuses_too_many_edges():
    edges, offsets = pad_polygon(*square(0.1), max_edges=6)
    assert edges.shape == (6, 2) and np.all(edges[4:] == 0.0) and np.all(offsets[4:] >= 1e19)
    with pytest.raises(ValueError, match="5 edges"):
        pad_polygon(np.ones((5, 2)), np.ones(5), max_edges=4)
