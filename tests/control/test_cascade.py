"""LexicographicCascade: strict priority on random stacks, against independent references."""

from __future__ import annotations

import daqp
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from dgraph.control import NOT_FINITE, SOLVED, RowBlock
from dgraph.control.cascade import LexicographicCascade


def keyed(key, A, b, C, lower, upper):
    """A level named ``key`` (the cascade keeps a ProxQP workspace per key)."""
    return RowBlock(A, b, C, lower, upper, key=key)


def random_level(rng, key, n, m_e, m_i, *, dependent=False, conflicting=False, around_zero=False):
    """Random rows; ``dependent`` repeats a combination of rows, ``conflicting`` adds a pair of
    inequalities no x satisfies (the level is infeasible on its own), ``around_zero``: x = 0
    satisfies the inequalities (a feasible level)."""
    A = rng.normal(size=(m_e, n))
    b = 2.0 * rng.normal(size=m_e)
    if dependent and m_e >= 2:
        A[-1] = A[0] - 0.5 * A[1]
    C = rng.normal(size=(m_i, n))
    centre = np.zeros(m_i) if around_zero else rng.normal(size=m_i)
    lower = centre - np.abs(rng.normal(size=m_i))
    upper = centre + np.abs(rng.normal(size=m_i))
    one_sided = rng.random(m_i) < 0.3
    upper[one_sided] = np.inf
    if conflicting and m_i:
        row = rng.normal(size=(1, n))
        C = np.vstack([C, row, -row])
        lower = np.r_[lower, 1.0, 1.0]  # row x >= 1 and row x <= -1
        upper = np.r_[upper, np.inf, np.inf]
    return keyed(key, A, b, C, lower, upper)


@st.composite
def stacks(draw):
    n = draw(st.integers(2, 7))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    levels = []
    for k in range(draw(st.integers(1, 4))):
        m_e = draw(st.integers(0, n + 1))
        m_i = draw(st.integers(0 if m_e else 1, 4))
        levels.append(random_level(rng, k, n, m_e, m_i, dependent=draw(st.booleans()),
                                   conflicting=draw(st.booleans()) and k > 0, around_zero=k == 0))
    return levels, n


def numerical_ranks_are_clear(levels):
    """No matrix of the problem is nearly singular (a singular value between 1e-12 and 1e-5 of the
    largest): there, the rank depends on a tolerance and the two solvers may rightly disagree."""
    matrices, stacked = [], []
    for level in levels:
        stacked.append(level.equality_matrix)
        matrices += [level.equality_matrix, np.vstack(stacked),
                     np.vstack([level.equality_matrix, level.inequality_matrix])]
    for matrix in matrices:
        if matrix.size:
            sigma = np.linalg.svd(matrix, compute_uv=False)
            ratio = sigma / max(sigma[0], 1e-300)
            if ((ratio > 1e-12) & (ratio < 1e-5)).any():
                return False
    return True


def kkt_refined(H, f, A, lower, upper, multipliers, y):
    """daqp's answer solved again exactly on its active set (the KKT system by numpy's lstsq),
    kept if feasible: the proximal iterations stop up to 1e-6 away from the optimum."""
    active = np.abs(multipliers) > 1e-12
    bounds = np.where(multipliers > 0, upper, lower)[active]
    rows = A[active]
    kkt = np.block([[H, rows.T], [rows, np.zeros((len(rows), len(rows)))]])
    refined = np.linalg.lstsq(kkt, np.r_[-f, bounds], rcond=None)[0][:len(f)]
    values = A @ refined
    feasible = (values >= lower - 1e-9).all() and (values <= upper + 1e-9).all()
    better = 0.5 * refined @ H @ refined + f @ refined <= 0.5 * y @ H @ y + f @ y + 1e-12
    return refined if feasible and better else y


def reference_cascade(levels, n):
    """A brute-force sequential solve in the full space with daqp (an exact active-set solver):
    level k over (x, s) with the equalities of the levels above fixed at their optimal residuals
    (an orthonormal basis of their row space, from an SVD) and their inequalities shifted by their
    optimal slack (Saab et al. Eq. 2.59 as written). Returns the final x."""
    fixed_rows, kept = [], []
    x = np.zeros(n)
    for level in levels:
        A, b, C, lo, up = (level.equality_matrix, level.equality_vector, level.inequality_matrix, level.lower,
                           level.upper)
        m_i = len(lo)
        H = np.zeros((n + m_i, n + m_i))
        H[:n, :n] = 2 * A.T @ A
        H[n:, n:] = 2 * np.eye(m_i)
        f = np.r_[-2 * A.T @ b, np.zeros(m_i)]
        rows, upper, lower, sense = [], [], [], []
        if fixed_rows:
            stacked = np.vstack(fixed_rows)
            _, sigma, vt = np.linalg.svd(stacked)
            rank = int(np.sum(sigma > 1e-9 * max(1.0, sigma[0])))
            basis = vt[:rank]
            targets = basis @ x  # x is the reference optimum of the levels above
            for row, target in zip(basis, targets):
                rows.append(np.r_[row, np.zeros(m_i)])
                upper.append(target)
                lower.append(target)
                sense.append(5)
        for Ck, lk, uk, sk in kept:
            for row, l_, u_, s_ in zip(Ck, lk, uk, sk):
                rows.append(np.r_[row, np.zeros(m_i)])
                upper.append(min(u_ + s_, 1e20))
                lower.append(max(l_ + s_, -1e20))
                sense.append(0)
        for i in range(m_i):
            rows.append(np.r_[C[i], -np.eye(m_i)[i]])
            upper.append(min(up[i], 1e20))
            lower.append(max(lo[i], -1e20))
            sense.append(0)
        A_all = np.array(rows).reshape(len(rows), n + m_i)
        y, _, exitflag, info = daqp.solve(H, f, A_all, np.array(upper, float), np.array(lower, float),
                                       np.array(sense, dtype=np.int32), eps_prox=1e-4, primal_tol=1e-10,
                                       iter_limit=100000)
        assume(exitflag == 1)  # the reference failing (degenerate pivots) says nothing about the cascade
        x = kkt_refined(H, f, A_all, np.array(lower), np.array(upper), info["lam"], y)[:n]
        values = C @ x
        slack = values - np.clip(values, lo, up)
        kept.append((C, lo, up, np.where(np.abs(slack) < 1e-6, 0.0, slack)))  # daqp's rounding is not a slack
        if len(b):
            fixed_rows.append(A)
    return x


SETTINGS = settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.filter_too_much,
                                                                             HealthCheck.too_slow])


@SETTINGS
@given(stacks())
def test_a_lower_level_never_degrades_a_higher_one(problem):
    levels, n = problem
    full = LexicographicCascade().solve(levels, n)
    assert full.status == SOLVED
    for k in range(len(levels)):
        alone = LexicographicCascade().solve(levels[:k + 1], n)
        assert alone.status == SOLVED
        assert abs(full.residuals[k] - alone.residuals[k]) <= 1e-6 * (1 + alone.residuals[k])


@SETTINGS
@given(stacks())
def test_residuals_match_a_sequential_daqp_reference(problem):
    levels, n = problem
    assume(numerical_ranks_are_clear(levels))
    reference = reference_cascade(levels, n)
    for closed_form in (True, False):
        solution = LexicographicCascade(closed_form=closed_form).solve(levels, n)
        assert solution.status == SOLVED
        assert_lexicographically_no_worse(levels, solution.x, reference)


def residual_vector(level, x):
    """``(A x - b, s)``: unique at a level's optimum (the cost is strictly convex in it)."""
    values = level.inequality_matrix @ x
    return np.r_[level.equality_matrix @ x - level.equality_vector, values - np.clip(values, level.lower, level.upper)]


def assert_lexicographically_no_worse(levels, x, reference, tolerance=1e-7, cost_tolerance=1e-6):
    """Level by level, our residual vector equals the reference's; at the first level where they
    differ, our cost must be the lower (the reference, a proximal daqp, can be off by 1e-5 in x
    after an ill-conditioned level while its cost is off by only 1e-11; below that level the
    two are no longer comparable). A level where the reference's cost is higher than ours ends
    the comparison in our favour: an inexact reference (ProxQP) may give up a little of one
    level, within ``tolerance``, and gain on the next; ``cost_tolerance`` is the relative slack of
    the cost comparison."""
    for k, level in enumerate(levels):
        ours, theirs = residual_vector(level, x), residual_vector(level, reference)
        if theirs @ theirs > (ours @ ours) * (1 + 1e-9) + 1e-12:
            return  # the reference is worse here (an inexact one can trade a level for the next): ours wins
        if np.abs(ours - theirs).max(initial=0.0) > tolerance:
            assert ours @ ours <= (theirs @ theirs) * (1 + cost_tolerance) + 1e-12, (
                f"level {k}: cost {ours @ ours}, the reference reaches {theirs @ theirs}")
            return


@SETTINGS
@given(stacks())
def test_feasible_top_inequalities_hold_whatever_the_levels_below_ask(problem):
    levels, n = problem
    rng = np.random.default_rng(n + len(levels))
    inequalities = random_level(rng, 0, n, 0, 3, around_zero=True)
    top = keyed("top", np.zeros((0, n)), np.zeros(0), inequalities.inequality_matrix, inequalities.lower,
                inequalities.upper)  # inequalities only, and x = 0 satisfies them: feasible
    pulling = keyed("pull", np.eye(n), 1e3 * np.ones(n), np.zeros((0, n)), np.zeros(0), np.zeros(0))
    solution = LexicographicCascade().solve([top, *levels, pulling], n)
    assert solution.status == SOLVED
    values = top.inequality_matrix @ solution.x
    # within 1e-5 against a pull of 1e3 (ProxQP's tolerances are relative to the data, 1e-9)
    assert (values >= top.lower - 1e-5).all() and (values <= top.upper + 1e-5).all()


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 6), st.integers(1, 4), st.integers(0, 2**32 - 1))
def test_equality_stacks_match_null_space_projection(n_levels, rows, seed):
    """Eq. 4.5: v_k = v_{k-1} + (A_k P_{k-1})^+ (b_k - A_k v_{k-1}), P_k = P_{k-1} - (A_k P_{k-1})^+ A_k P_{k-1}."""
    rng = np.random.default_rng(seed)
    n = 8
    levels = [random_level(rng, k, n, rows, 0) for k in range(n_levels)]
    v, P = np.zeros(n), np.eye(n)
    for level in levels:
        AP = level.equality_matrix @ P
        u, sigma, vt = np.linalg.svd(AP, full_matrices=False)
        keep = sigma > 1e-9 * max(1.0, sigma[0])  # absolute below 1: P may be (numerically) zero
        pinv = vt[keep].T @ np.diag(1 / sigma[keep]) @ u[:, keep].T
        v = v + pinv @ (level.equality_vector - level.equality_matrix @ v)
        P = P - pinv @ AP
    solution = LexicographicCascade().solve(levels, n)
    expected = np.array([np.linalg.norm(lv.equality_matrix @ v - lv.equality_vector) for lv in levels])
    np.testing.assert_allclose(solution.residuals, expected, rtol=1e-7, atol=1e-7)
    # with every level equality-only, nothing needs ProxQP
    assert solution.qp_levels == 0


def test_a_level_infeasible_on_its_own_gets_its_least_violation_and_the_rest_goes_on():
    n = 3
    top = keyed(0, np.zeros((0, n)), np.zeros(0), np.array([[1.0, 0, 0], [1.0, 0, 0]]), np.array([1.0, -np.inf]),
                np.array([np.inf, -1.0]))  # x0 >= 1 and x0 <= -1: least violation at x0 = 0
    below = keyed(1, np.array([[1.0, 0, 0], [0, 1.0, 0]]), np.array([5.0, 2.0]), np.zeros((0, n)), np.zeros(0),
                  np.zeros(0))
    solution = LexicographicCascade().solve([top, below], n)
    assert solution.status == SOLVED
    assert solution.x[0] == pytest.approx(0.0, abs=1e-7)  # x0 = 5 would violate the top level more
    assert solution.x[1] == pytest.approx(2.0, abs=1e-7)
    assert solution.residuals[0] == pytest.approx(np.sqrt(2.0), abs=1e-7)


def test_non_finite_or_crossed_rows_give_a_status_not_an_exception():
    n = 2
    good = keyed(0, np.eye(n), np.ones(n), np.zeros((0, n)), np.zeros(0), np.zeros(0))
    nan = keyed(1, np.eye(n), np.array([np.nan, 0.0]), np.zeros((0, n)), np.zeros(0), np.zeros(0))
    crossed = keyed(2, np.zeros((0, n)), np.zeros(0), np.eye(n), np.ones(n), np.zeros(n))
    cascade = LexicographicCascade()
    for bad in (nan, crossed):
        solution = cascade.solve([good, bad], n)
        assert solution.status == NOT_FINITE
        assert (solution.x == 0).all()
    assert cascade.solve([good], n).status == SOLVED


def test_solving_twice_at_a_tick_gives_the_same_answer_bit_for_bit():
    rng = np.random.default_rng(3)
    levels = [random_level(rng, 0, 6, 0, 4, around_zero=True), random_level(rng, 1, 6, 3, 2),
              random_level(rng, 2, 6, 4, 0)]
    cascade = LexicographicCascade(closed_form=False)
    cascade.solve(levels, 6, tick=0)
    first = cascade.solve(levels, 6, tick=1).x.copy()
    again = cascade.solve(levels, 6, tick=1).x
    assert np.array_equal(first, again)


def test_a_level_proxqp_wrongly_calls_infeasible_is_still_solved():
    """A degenerate level (two free variables, three kept rows meeting at the origin) that
    ProxQP 0.8 reports primal infeasible: the cascade asks it for the closest feasible point,
    which is the optimum (found by an adversarial review; daqp's level residual is 10.78)."""
    n = 6
    A0=np.array([[-0.45847334,-0.29589576,-0.14887333,0.31375677,0.67355533,1.06139718],[-0.98809876,-0.017701,0.07812119,-0.5180995,-0.37099684,-1.09371413],[-0.44024792,-0.62895152,-0.09565834,-0.5672239,1.00408671,-0.74250488],[1.21768832,-0.78653762,0.25859744,-1.29306872,-0.18439394,-1.22564644]])
    b0=np.array([1.8171133,-0.9832738,-0.59508729,-0.74868195])
    A1=np.array([[-1.05723628,1.90368377,1.1584588,0.53435617,0.15388934,-0.54400092],[-0.08773643,-0.66425882,-0.80653911,0.54484423,-0.54719447,-0.17393544],[-1.03672747,-0.41049706,0.13471159,0.14521546,0.47701942,-0.20218521],[-1.19353792,-1.23279461,0.90549224,-1.0961047,0.22346741,1.9571205],[-0.24573128,2.46651269,-0.49720689,-0.53984205,0.05691043,-1.84299362]])
    b1=np.array([-3.58501003,-1.01125333,2.3329182,2.02375671,3.58835503])
    none = (np.zeros((0, n)), np.zeros(0), np.zeros(0))
    inequalities = random_level(np.random.default_rng(n + 2), 0, n, 0, 3, around_zero=True)
    top = keyed("top", np.zeros((0, n)), np.zeros(0), inequalities.inequality_matrix, inequalities.lower,
                inequalities.upper)
    for closed_form in (True, False):
        solution = LexicographicCascade(closed_form=closed_form).solve(
            [top, keyed(0, A0, b0, *none), keyed(1, A1, b1, *none)], n)
        assert solution.status == SOLVED
        np.testing.assert_allclose(solution.residuals, [0.0, 0.0, 10.7832426], atol=1e-6)
