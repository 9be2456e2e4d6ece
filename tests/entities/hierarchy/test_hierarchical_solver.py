"""HierarchicalSolver on TALOS (Table 4.1 stack): reaching, feet, strictness, errors and failures."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from talos_ik import HAND_FRAME, build, half_sitting

import dgraph as dg
from dgraph.control import NOT_FINITE, SOLVED, RowBlock


def frame_position(graph, frame, t):
    state = graph["robot"].state(t)
    return state.frame_placement(state.frame_id(frame)).translation.copy()


def test_the_hand_reaches_a_reachable_target_to_1mm_and_the_feet_do_not_move():
    g = build(hand=True)
    target = frame_position(g, HAND_FRAME, 0) + np.array([0.10, 0.05, 0.10])
    g["hand_feature"].reference_position.set(target)
    feet = {f: frame_position(g, f, 0) for f in ("left_sole_link", "right_sole_link")}
    g.run(ticks=1500)
    t = g.t
    assert g["solver"].status(t) == SOLVED
    assert np.linalg.norm(frame_position(g, HAND_FRAME, t) - target) < 1e-3
    for frame, start in feet.items():
        assert np.abs(frame_position(g, frame, t) - start).max() < 1e-6
    q, model = g["device"].q.value, g["robot"].pin_model
    assert (q[7:] >= model.lowerPositionLimit[7:] - 1e-9).all() and (q[7:] <= model.upperPositionLimit[7:] + 1e-9).all()


def test_lower_levels_do_not_degrade_higher_ones_on_talos():
    """The residuals of the levels above the hand are the same with and without the hand and
    the levels below it, at a perturbed state where every level is active."""
    rng = np.random.default_rng(0)
    q = half_sitting()
    q[7:] += 0.05 * rng.normal(size=32)
    full = build(q, hand=True)
    full["hand_feature"].reference_position.set(frame_position(full, HAND_FRAME, 0) + 0.2)
    with_all = full["solver"].level_residuals(0)
    for removed in ("posture", "waist", "hand"):
        full["solver"].remove(removed)
        fewer = full["solver"].level_residuals(0)
        kept = len(fewer) - 1  # the last entry is the minimum-norm level
        np.testing.assert_allclose(fewer[:kept], with_all[:kept], atol=1e-6, rtol=1e-6)


def test_a_misshaped_task_is_reported_with_the_solver_and_input_names():
    g = build()
    g["solver"].waist.set(RowBlock.equalities(np.zeros((2, 10)), np.zeros(2)))  # 10 columns, not 38
    with pytest.raises(dg.SpecError, match=r"solver\.waist at tick 0: .*nv = 38") as info:
        g["solver"].velocity(0)
    assert (info.value.entity, info.value.signal) == ("solver", "waist")


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
def test_a_non_finite_task_gives_a_status_and_a_zero_velocity_not_an_exception():
    g = build()
    solver, reference = g["solver"], g["com_xy_feature"].reference_position(0)
    g["com_xy"].gain.set(1e308)
    g["com_xy_feature"].reference_position.set(np.array([-1e308, 0.0, 0.9]))  # lambda e overflows: inf
    assert solver.status(0) == NOT_FINITE
    assert (solver.velocity(0) == 0).all()
    g["com_xy"].gain.set(100.0)
    g["com_xy_feature"].reference_position.set(reference)
    assert solver.status(0) == SOLVED  # recovers at once


def test_level_residuals_keep_one_entry_per_stack_level_while_a_level_is_inactive():
    q = half_sitting()
    q[7:] += 0.05 * np.random.default_rng(0).normal(size=32)  # a posture error: the levels below have residuals
    g = build(q)
    tilt = pin.Quaternion(pin.exp3(np.array([0.3, 0.0, 0.0]))).coeffs()
    g["waist_feature"].reference_orientation.set(tilt)  # out of reach of the levels above: a residual
    before = g["solver"].level_residuals(0)
    g["waist"].deactivate()  # the waist is alone on its level
    g.step()
    after = g["solver"].level_residuals(g.t)
    assert len(after) == len(before)
    waist_level = g["solver"].levels().index(["waist"])
    assert before[waist_level] > 1.0 and after[waist_level] == 0.0  # no rows while inactive
    assert (after[waist_level + 1:] > 1.0).all()  # the levels below keep their places
