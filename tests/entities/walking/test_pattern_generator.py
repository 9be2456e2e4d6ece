"""ZmpPatternGenerator: re-plan ticks, closed loop on an exact LIPM, a kick, failures, feedback, outputs."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import dgraph as dg
from dgraph.control.status import PRIMAL_INFEASIBLE, SOLVED
from dgraph.entities.stabilizers.lipm import GRAVITY
from dgraph.entities.walking.footsteps import FootstepPlan, straight_walk, yaw_placement
from dgraph.entities.walking.lipm_mpc import LipmMpc
from dgraph.entities.walking.pattern_generator import SupportPolygons, ZmpPatternGenerator

DT = 0.001
HEIGHT = 0.87
LEFT, RIGHT = yaw_placement([0.0, 0.085, 0.0]), yaw_placement([0.0, -0.085, 0.0])
OMEGA = math.sqrt(GRAVITY / HEIGHT)
ROUNDING = 1e-9
"""m: ProxQP's answer to one problem varies in its last bits with where its data lies in memory
(two fresh solvers of one problem: 7e-13 on the jerks), so two runs agree to this, not bit for bit."""
REFERENCES = ("com_position", "com_velocity", "com_acceleration", "zmp", "zmp_velocity", "dcm", "dcm_velocity")


def generator(plan: FootstepPlan, com: np.ndarray | None = None, **params) -> tuple[dg.Graph, ZmpPatternGenerator]:
    """A pattern generator on ``plan`` in a graph of its own, the estimate set to ``com`` at rest."""
    graph = dg.Graph(dt=DT)
    pattern = graph.add(ZmpPatternGenerator("pattern", **params))
    pattern.plan.set(plan)
    measure(pattern, np.array([0.0, 0.0, HEIGHT]) if com is None else com, np.zeros(3))
    return graph, pattern


def measure(pattern: ZmpPatternGenerator, position: np.ndarray, velocity: np.ndarray) -> None:
    pattern.estimated_com_position.set(position)
    pattern.estimated_com_velocity.set(velocity)


def lipm_step(position: np.ndarray, velocity: np.ndarray, zmp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One tick of ``c_ddot = omega^2 (c - z)``, ``z`` held over the tick: the exact solution."""
    cosh, sinh = math.cosh(OMEGA * DT), math.sinh(OMEGA * DT)
    offset = position[:2] - zmp[:2]
    new_position, new_velocity = position.copy(), velocity.copy()
    new_position[:2] = zmp[:2] + offset * cosh + velocity[:2] * sinh / OMEGA
    new_velocity[:2] = offset * OMEGA * sinh + velocity[:2] * cosh
    return new_position, new_velocity


def closed_loop(plan: FootstepPlan, seconds: float, kick: tuple[float, np.ndarray] | None = None) -> dict:
    """The generator fed by an exact LIPM whose ZMP is the generator's output, for ``seconds``;
    ``kick = (time, dv)`` adds ``dv`` to the CoM velocity at ``time``. Returns the measured CoM
    and DCM, the planned DCM and the statuses, per tick."""
    position, velocity = np.array([-0.005, 0.0, HEIGHT]), np.zeros(3)  # over the initial midpoint
    graph, pattern = generator(plan, position)
    record = {"com": [], "dcm": [], "planned_dcm": [], "status": []}
    for t in range(round(seconds / DT)):
        if kick is not None and t == round(kick[0] / DT):
            velocity = velocity + kick[1]
        measure(pattern, position, velocity)
        zmp = pattern.zmp(t)
        record["com"].append(position[:2])
        record["dcm"].append(position[:2] + velocity[:2] / OMEGA)
        record["planned_dcm"].append(pattern.dcm(t)[:2])
        record["status"].append(pattern.status(t))
        graph.step()
        position, velocity = lipm_step(position, velocity, zmp)
    record = {key: np.array(value) for key, value in record.items()}
    record["faults"] = graph.fault_log.degraded_ticks
    return record


def short_walk() -> FootstepPlan:
    """Four 20 cm steps and the closing one: 6.96 s."""
    return straight_walk(LEFT, RIGHT, steps=4)


@pytest.fixture(scope="module")
def walked() -> dict:
    return closed_loop(short_walk(), 10.0)


def test_it_replans_at_the_first_tick_and_where_the_plan_time_crosses_a_period(monkeypatch):
    solves = []
    original = LipmMpc.solve

    def counted(self, *args, **kwargs):
        solves.append(kwargs["tick"])
        return original(self, *args, **kwargs)

    monkeypatch.setattr(LipmMpc, "solve", counted)
    for start, expected in ((0.0, list(range(0, 1000, 5))), (0.0023, [0, *range(3, 1000, 5)])):
        solves.clear()
        graph, pattern = generator(dataclasses.replace(short_walk(), start=start))
        replans = set()
        for t in range(1000):
            for name in REFERENCES:  # reading every output does not re-plan again
                getattr(pattern, name)(t)
            replans.add(pattern.com_plan(t).replan_tick)
            graph.step()
        assert solves == expected
        assert sorted(replans) == expected
        assert len(solves) == (200 if start == 0.0 else 201)  # 1 s at 5 ms, and the first tick


def test_the_closed_loop_lipm_follows_the_feet_and_its_dcm_stays_bounded(walked):
    plan = short_walk()
    assert set(walked["status"]) == {SOLVED} and walked["faults"] == 0
    np.testing.assert_allclose(walked["com"][-1], plan.final_midpoint()[:2], atol=0.02)
    # the measured DCM stays on the planned one (re-planned from it every 5 ms) and over the feet
    assert np.abs(walked["dcm"] - walked["planned_dcm"]).max() < 1e-4
    footprints = np.array([step.placement[:2, 3] for step in plan.steps] + [LEFT[:2, 3], RIGHT[:2, 3]])
    assert (walked["dcm"][:, 0] >= footprints[:, 0].min() - plan.sole.back).all()
    assert (walked["dcm"][:, 0] <= footprints[:, 0].max() + plan.sole.front).all()
    assert np.abs(walked["dcm"][:, 1]).max() < 0.09  # the soles' centres are 0.085 m to each side


def test_a_velocity_kick_stays_feasible_and_recovers(walked):
    kicked = closed_loop(short_walk(), 10.0, kick=(2.5, np.array([0.0, 0.1, 0.0])))  # mid single support
    assert set(kicked["status"]) == {SOLVED}
    after = round(2.5 / DT)
    deviation = np.linalg.norm(kicked["com"] - walked["com"], axis=1)
    assert deviation[after + 200] > 0.01  # the kick moved the CoM
    assert deviation[after + 2000:].max() < 0.002  # and within 2 s it is back on the unperturbed walk
    assert np.abs(kicked["dcm"] - kicked["planned_dcm"]).max() < 1e-4
    np.testing.assert_allclose(kicked["com"][-1], short_walk().final_midpoint()[:2], atol=0.02)


class UnreachablePlan(FootstepPlan):
    """A plan whose support polygon is empty from its first single support on."""

    def support_polygon(self, time: float, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        if time < self.phases[1].start:
            return super().support_polygon(time, margin)
        return np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([-1.0, -1.0])  # x <= -1 and x >= 1


def test_an_infeasible_replan_reports_keeps_the_previous_plan_and_raises_nothing():
    walk = straight_walk(LEFT, RIGHT, steps=2, initial_double_support=2.0)
    plan = UnreachablePlan(walk.initial_left, walk.initial_right, walk.steps, 2.0, walk.final_double_support)
    graph, pattern = generator(plan, np.array([-0.005, 0.0, HEIGHT]))
    plans = []
    for t in range(700):
        plans.append((pattern.com_plan(t), pattern.com_position(t).copy()))
        graph.step()
    statuses = [com_plan.status for com_plan, _ in plans]
    first_failure = statuses.index(PRIMAL_INFEASIBLE)
    assert 395 <= first_failure <= 405  # the horizon (1.6 s) reaches the first single support at 2 s
    assert set(statuses[:first_failure]) == {SOLVED} and set(statuses[first_failure:]) == {PRIMAL_INFEASIBLE}
    kept = plans[first_failure - 1][0]
    for t in range(first_failure, 700):
        com_plan, position = plans[t]
        assert com_plan.trajectory is kept.trajectory and com_plan.start_tick == kept.start_tick
        assert com_plan.replan_tick == t - t % 5
        np.testing.assert_array_equal(position[:2], kept.trajectory.sample((t - kept.start_tick) * DT)[0])
    assert graph.fault_log.degraded_ticks == len(range(first_failure, 700, 5))
    assert graph.fault_log.faults[0].signal == "pattern.com_plan"


def test_feedback_blends_the_estimate_into_the_replanned_state():
    graph, pattern = generator(short_walk(), feedback=0.25)
    for t in range(5):
        pattern.zmp(t)
        graph.step()
    previous = pattern.com_plan(4)
    planned = previous.trajectory.sample(5 * DT)
    estimate, estimate_velocity = np.array([0.03, -0.02, HEIGHT]), np.array([0.1, 0.2, 0.0])
    measure(pattern, estimate, estimate_velocity)
    initial = pattern.com_plan(5).trajectory.states[0]
    np.testing.assert_allclose(initial[0], 0.25 * estimate[:2] + 0.75 * planned[0], atol=1e-15)
    np.testing.assert_allclose(initial[1], 0.25 * estimate_velocity[:2] + 0.75 * planned[1], atol=1e-15)
    np.testing.assert_array_equal(initial[2], planned[2])


def test_open_loop_ignores_the_estimate_after_the_first_tick():
    runs = []
    for wrong in (False, True):
        graph, pattern = generator(short_walk(), feedback=0.0)
        positions = []
        for t in range(1500):
            if wrong and t == 1:
                measure(pattern, np.array([0.3, 0.3, 2.0]), np.ones(3))
            positions.append(pattern.com_position(t))
            graph.step()
        runs.append(np.array(positions))
    np.testing.assert_allclose(runs[0], runs[1], rtol=0.0, atol=ROUNDING)
    assert np.abs(runs[0][-1, :2] - runs[0][0, :2]).max() > 0.01  # it moved


def test_outputs_are_the_lipm_relations_and_the_velocities_the_derivatives():
    graph, pattern = generator(short_walk(), feedback=0.0, com_height=0.8)
    values = {name: [] for name in REFERENCES}
    replans = []
    for t in range(1600):
        for name in REFERENCES:
            values[name].append(getattr(pattern, name)(t))
        replans.append(pattern.com_plan(t).replan_tick)
        graph.step()
    v = {name: np.array(rows) for name, rows in values.items()}
    same_plan = np.diff(replans) == 0  # t and t + 1 on one plan (the jerk, so the ZMP velocity, jumps at a re-plan)
    omega = math.sqrt(GRAVITY / 0.8)
    np.testing.assert_allclose(v["zmp"][:, :2], v["com_position"][:, :2] - v["com_acceleration"][:, :2] / omega**2,
                               atol=1e-12)
    np.testing.assert_allclose(v["dcm"][:, :2], v["com_position"][:, :2] + v["com_velocity"][:, :2] / omega,
                               atol=1e-12)
    np.testing.assert_array_equal(v["com_position"][:, 2], 0.8)
    np.testing.assert_array_equal(v["zmp"][:, 2], 0.0)
    for position, velocity in (("com_position", "com_velocity"), ("com_velocity", "com_acceleration"),
                               ("zmp", "zmp_velocity"), ("dcm", "dcm_velocity")):
        difference = (v[position][1:] - v[position][:-1]) / DT  # the trapezoid rule, within each plan
        np.testing.assert_allclose(difference[same_plan], 0.5 * (v[velocity][1:] + v[velocity][:-1])[same_plan],
                                   rtol=0.0, atol=1e-6)
    assert np.abs(v["zmp_velocity"]).max() > 0.2  # the ZMP does move


def test_it_stands_before_the_start_and_after_the_end():
    plan = dataclasses.replace(short_walk(), start=2.0)
    midpoint = 0.5 * (plan.sole.center(LEFT) + plan.sole.center(RIGHT))
    graph, pattern = generator(plan, np.array([*midpoint[:2], HEIGHT]))
    for t in range(round((2.0 + plan.duration + 4.0) / DT)):
        if t < 300:  # more than a horizon before the start
            np.testing.assert_allclose(pattern.com_position(t)[:2], midpoint[:2], atol=1e-6)
            np.testing.assert_allclose(pattern.zmp(t)[:2], midpoint[:2], atol=1e-6)
        measure(pattern, pattern.com_position(t), pattern.com_velocity(t))
        graph.step()
    np.testing.assert_allclose(pattern.com_position(graph.t)[:2], plan.final_midpoint()[:2], atol=1e-3)
    assert np.abs(pattern.com_velocity(graph.t)).max() < 1e-3


def test_the_com_height_is_the_estimate_above_the_soles_unless_given():
    raised = [placement.copy() for placement in (LEFT, RIGHT)]
    for placement in raised:
        placement[2, 3] = 0.1
    plan = straight_walk(*raised, steps=2)
    _, pattern = generator(plan, np.array([0.0, 0.0, 0.95]))
    assert pattern.com_position(0)[2] == pytest.approx(0.95)
    assert pattern.zmp(0)[2] == pytest.approx(0.1)
    assert pattern.com_plan(0).trajectory.omega == pytest.approx(math.sqrt(GRAVITY / 0.85))


def test_the_height_transition_lowers_the_com_by_minimum_jerk_and_leaves_the_horizontal_plan():
    """From the estimate's 0.87 m to com_height 0.75 m in 0.4 s: the CoM and DCM heights are
    0.75 + 0.12 (1 - s(x)), s(x) = 10 x^3 - 15 x^4 + 6 x^5, x = t dt / 0.4, their velocities and
    the CoM acceleration its derivatives; at once (transition 0) the height is 0.75 from tick 0."""
    runs = {}
    for transition in (0.0, 0.4):
        graph, pattern = generator(short_walk(), feedback=0.0, com_height=0.75, height_transition=transition)
        rows = []
        for t in range(600):
            rows.append([getattr(pattern, name)(t) for name in REFERENCES])
            graph.step()
        runs[transition] = np.array(rows)  # (tick, reference, axis)
    at_once, smooth = runs[0.0], runs[0.4]
    np.testing.assert_allclose(smooth[:, :, :2], at_once[:, :, :2], rtol=0.0, atol=ROUNDING)
    np.testing.assert_array_equal(at_once[:, 0, 2], 0.75)
    x = np.minimum(np.arange(600) * DT / 0.4, 1.0)
    expected = 0.75 + 0.12 * (1.0 - (10 * x**3 - 15 * x**4 + 6 * x**5))
    for position, velocity in ((0, 1), (5, 6)):  # the CoM and the DCM
        np.testing.assert_allclose(smooth[:, position, 2], expected, rtol=0.0, atol=1e-12)
        assert smooth[:, velocity, 2].min() == pytest.approx(-1.875 * 0.12 / 0.4)  # at x = 1/2
    assert smooth[0, 0, 2] == pytest.approx(0.87) and (smooth[400:, 0, 2] == 0.75).all()
    for position, derivative, rounding in ((0, 1, 2e-5), (1, 2, 3e-4)):  # the trapezoid rule's dt^2/12 f'''
        difference = np.diff(smooth[:, position, 2]) / DT
        np.testing.assert_allclose(difference, 0.5 * (smooth[1:, derivative, 2] + smooth[:-1, derivative, 2]),
                                   rtol=0.0, atol=rounding)
    assert (smooth[400:, [1, 2, 6], 2] == 0.0).all() and (smooth[:, 3, 2] == 0.0).all()  # the ZMP stays on the ground


def test_support_polygons_are_the_plans_at_every_time():
    plan = short_walk()
    polygons = SupportPolygons(plan, 0.02)
    times = np.concatenate([np.linspace(-1.0, plan.duration + 1.0, 997), [phase.start for phase in plan.phases]])
    edges, offsets = polygons.at(times)
    for time, padded_edges, padded_offsets in zip(times, edges, offsets, strict=True):
        normals, bounds = plan.support_polygon(time, 0.02)
        np.testing.assert_array_equal(padded_edges[:len(bounds)], normals)
        np.testing.assert_array_equal(padded_offsets[:len(bounds)], bounds)
        assert (padded_offsets[len(bounds):] >= 1e19).all()


def test_a_margin_that_leaves_no_polygon_is_a_param_error():
    _, pattern = generator(short_walk(), margin=0.08)
    with pytest.raises(dg.ParamError, match="'margin': margin 0.08 m leaves nothing"):
        pattern.zmp(0)


def test_the_cache_off_gives_the_same_references():
    runs = []
    for cache in (True, False):
        graph, pattern = generator(short_walk())
        graph.cache_enabled = cache
        rows = []
        for t in range(60):
            rows.append(np.concatenate([getattr(pattern, name)(t) for name in REFERENCES]))
            measure(pattern, pattern.com_position(t) + 1e-3, pattern.com_velocity(t))
            graph.step()
        runs.append(np.array(rows))
    np.testing.assert_allclose(runs[0], runs[1], rtol=0.0, atol=ROUNDING)


def test_between_samples_the_20cm_walks_zmp_stays_inside_the_soles():
    """The MPC constrains the ZMP at its 0.1 s samples only; on the thesis's 20 cm walk the ZMP the
    generator outputs at every tick (open loop) still stays inside the support polygon, at least
    1 cm from its edges (the polygons are shrunk by 2 cm at the samples). The 60 cm walk's does not
    (0.115 s double supports moving it 0.6 m: lipm_mpc's docstring, docs/walking.md)."""
    plan = straight_walk(LEFT, RIGHT)
    midpoint = 0.5 * (plan.sole.center(LEFT) + plan.sole.center(RIGHT))
    graph, pattern = generator(plan, np.array([*midpoint[:2], HEIGHT]), feedback=0.0)
    margins = []
    for t in range(round((plan.duration + 0.5) / DT)):
        normals, offsets = plan.support_polygon(t * DT)
        margins.append((offsets - normals @ pattern.zmp(t)[:2]).min())
        graph.step()
    assert min(margins) > 0.01
