"""LexicographicCascade's closed-form active set: a level whose least-squares step violates a
bound (kept from above or its own) is solved without ProxQP, to the same residuals."""

from __future__ import annotations

import numpy as np
from hypothesis import assume, given
from hypothesis import strategies as st
from test_cascade import (
    SETTINGS,
    assert_lexicographically_no_worse,
    keyed,
    numerical_ranks_are_clear,
    reference_cascade,
)

from dgraph.control import SOLVED
from dgraph.control.cascade import LexicographicCascade
from tests.entities.hierarchy.talos_ik import build


def bounds_level(rng, n, on_bound):
    """``l <= x <= u`` on every variable; ``on_bound`` variables have ``u = 0`` or ``l = 0``
    (x = 0 sits on the bound, as a joint on its limit), the others a box around 0."""
    lower, upper = -rng.uniform(0.05, 1.0, n), rng.uniform(0.05, 1.0, n)
    sides = rng.random(n) < 0.5
    upper[on_bound & sides], lower[on_bound & ~sides] = 0.0, 0.0
    return lower, upper


@st.composite
def stacks_under_bounds(draw):
    """Level 0: equalities (contacts) and variable bounds, some active at x = 0; then 1 to 3
    equality levels of random size, the last possibly square (a unique optimum, as a posture)."""
    n = draw(st.integers(3, 8))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    on_bound = rng.random(n) < draw(st.sampled_from([0.2, 0.5, 1.0]))
    lower, upper = bounds_level(rng, n, on_bound)
    m0 = draw(st.integers(0, n // 2))
    contacts = rng.normal(size=(m0, n))
    contacts[:, on_bound] = 0.0  # the bounded variables stay free at level 0: x = 0 is its optimum
    levels = [keyed(0, contacts, np.zeros(m0), np.eye(n), lower, upper)]
    for k in range(1, draw(st.integers(2, 4))):
        m = draw(st.integers(1, n))
        scale = draw(st.sampled_from([1e-3, 1.0, 10.0]))  # small pulls: the bounds need not bind
        levels.append(keyed(k, rng.normal(size=(m, n)), scale * rng.normal(size=m), np.zeros((0, n)), np.zeros(0),
                            np.zeros(0)))
    return levels, n


@SETTINGS
@given(stacks_under_bounds())
def test_the_active_set_matches_proxqp_and_daqp_on_levels_pushing_into_bounds(problem):
    levels, n = problem
    assume(numerical_ranks_are_clear(levels))
    closed = LexicographicCascade().solve(levels, n)
    qp = LexicographicCascade(closed_form=False).solve(levels, n)
    assert closed.status == SOLVED
    assert closed.qp_levels == 0  # below level 0 only kept bounds, feasible at every level's start
    # daqp (an exact active set, refined on its KKT system): level by level the same residuals, or
    # lower at the first level where they differ
    assert_lexicographically_no_worse(levels, closed.x, reference_cascade(levels, n))
    # ProxQP on every level, when it solves, as a looser second opinion: the same residuals to
    # its accuracy, or lower at the first level where they differ. It may cross a bound by 1e-8
    # (seen: 1.2e-8 on a bound at 0), which lower levels with pulls of 10 turn into up to 2e-5 of
    # relative cost; and on some vertices it stops 1e-3 short of a level's optimum, where daqp
    # agrees with the active set.
    if qp.status == SOLVED:
        assert_lexicographically_no_worse(levels, closed.x, qp.x, tolerance=1e-5, cost_tolerance=1e-3)
    assert (closed.x >= levels[0].lower - 1e-9).all() and (closed.x <= levels[0].upper + 1e-9).all()


def test_bounds_active_by_construction_need_no_proxqp():
    """A variable on its bound that a lower level moves slightly (stage 1: the least-squares
    optimum can leave it there) and a square level pulling it out (stage 2: the bound binds,
    its multiplier has the right sign)."""
    n = 4
    top = keyed(0, np.zeros((0, n)), np.zeros(0), np.eye(n), -np.ones(n), np.r_[0.0, 2.0 * np.ones(n - 1)])
    loose = keyed(1, np.array([[1.0, 1.0, 1.0, 0.0]]), np.array([3.0]), np.zeros((0, n)), np.zeros(0), np.zeros(0))
    square = keyed(2, np.eye(n), np.array([2.0, 0.5, -0.5, 0.3]), np.zeros((0, n)), np.zeros(0), np.zeros(0))
    cascade = LexicographicCascade()
    one = cascade.solve([top, loose], n)
    assert one.status == SOLVED and one.qp_levels == 0
    assert one.x[0] <= 1e-12 and one.residuals[1] < 1e-12  # x0 stays on its bound, the level is met
    both = cascade.solve([top, loose, square], n)
    assert both.status == SOLVED and both.qp_levels == 0
    reference = LexicographicCascade(closed_form=False).solve([top, loose, square], n)
    np.testing.assert_allclose(both.residuals, reference.residuals, atol=1e-8)
    np.testing.assert_allclose(both.x, reference.x, atol=1e-6)
    assert both.x[0] == 0.0 or abs(both.x[0]) < 1e-12


def test_talos_with_joint_limits_at_half_sitting_runs_without_proxqp():
    """The grippers sit on their upper limit at half-sitting (bounds 0): every level below the
    limits pushes them past it by 1e-9 to 1e-3 rad/s; the active set keeps them on it, to the
    residuals of the every-level-ProxQP cascade."""
    g = build(limits=True)
    solver, feature = g["solver"], g["com_xy_feature"]
    centre = feature.reference_position(0).copy()
    qp_levels, statuses = [], []

    def control(t):
        feature.reference_position.set(centre + np.array([0.0, 0.05 * np.sin(np.pi * t * g.dt), 0.0]))
        qp_levels.append(solver.qp_levels(t))
        statuses.append(solver.status(t))
        if t % 50 == 25:
            levels = solver.solution(t).levels
            reference = LexicographicCascade(closed_form=False).solve(levels, solver.nv)
            np.testing.assert_allclose(solver.solution(t).residuals, reference.residuals, rtol=1e-6, atol=1e-6)

    g["device"].before.add(control)
    g.run(ticks=300, progress=False)
    assert set(statuses) == {SOLVED}
    assert sum(qp_levels) == 0
    q, model = g["device"].q.value, g["robot"].pin_model
    assert (q[7:] >= model.lowerPositionLimit[7:] - 1e-9).all() and (q[7:] <= model.upperPositionLimit[7:] + 1e-9).all()
