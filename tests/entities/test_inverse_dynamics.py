"""InverseDynamicsSolver: exactness against daqp, dynamics, limits, contacts, failures."""

from __future__ import annotations

import daqp
import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.control import NOT_FINITE, PRIMAL_INFEASIBLE, SOLVED
from dgraph.control.inverse_dynamics import InverseDynamicsQP
from tests.entities.talos_graph import build, half_sitting


def perturbed_state(seed):
    rng = np.random.default_rng(seed)
    q = half_sitting()
    q[7:] += 0.05 * rng.normal(size=32)
    return q, 0.2 * rng.normal(size=38)


def dynamics_residual(graph, t=0):
    """||M a + h - J_c^T f - S^T tau||_inf, with J_c^T f from the contacts' own data."""
    solver, state = graph["solver"], graph["robot"].state(t)
    solution = solver.solution(t)
    generalized = sum(c.jacobian.T @ (c.force_generator @ f) for c, f in zip(solution.contacts, solution.forces))
    torque = np.r_[np.zeros(6), solution.tau]
    return np.abs(state.mass_matrix @ solution.acceleration + state.bias_forces - generalized - torque).max()


def exact_solution(graph):
    """The solver's QP at tick 0, torque-limit rows included, solved by daqp (dual active set,
    exact to machine precision); and its workspace."""
    qp = graph["solver"]._qp
    ws = next(iter(qp._workspaces.values()))
    ws.rows.write_torque_bounds(graph["robot"].state(0).bias_forces)  # written by the solver only when needed
    n_eq = len(ws.b)
    A = np.vstack([ws.A, ws.C])
    upper = np.r_[ws.b, ws.upper]
    lower = np.r_[ws.b, ws.lower]
    sense = np.r_[np.full(n_eq, 5), np.zeros(len(ws.upper))].astype(np.int32)  # 5: equality
    x, _, exitflag, _ = daqp.solve(ws.H, ws.g, A, upper, lower, sense)
    assert exitflag == 1
    return x, ws


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_solution_matches_an_exact_solver_and_satisfies_the_dynamics(seed):
    """The formulation is exact: at a tight tolerance ProxQP's answer is daqp's (the full QP,
    torque-limit rows included, although the solver needs them only when one binds)."""
    q, v = perturbed_state(seed)
    graph = build(q, v, eps_abs=1e-9)
    solver = graph["solver"]
    solution = solver.solution(0)
    assert solution.status == SOLVED and not solution.torque_limited
    x, _ = exact_solution(graph)
    assert np.abs(np.r_[solution.acceleration, np.concatenate(solution.forces)] - x).max() < 1e-4
    assert dynamics_residual(graph) < 1e-6


@pytest.mark.parametrize("seed", range(6))
def test_the_default_tolerance_moves_the_torques_by_less_than_a_millinewton_metre(seed):
    """eps_abs = 1e-6, from a cold start (a new set of contacts): accelerations to 1e-5, torques
    to 1e-3 N m of the exact optimum (measured: at most 6e-7 and 6e-6 over these seeds; the
    issue asks for 1e-2 N m), the dynamics to 1e-6."""
    q, v = perturbed_state(seed)
    graph = build(q, v)
    solver = graph["solver"]
    solution = solver.solution(0)
    x, workspace = exact_solution(graph)
    exact_tau = workspace.torque_rows @ x + graph["robot"].state(0).bias_forces[6:]
    assert solver.eps_abs == 1e-6 and solution.status == SOLVED
    assert np.abs(solution.acceleration - x[:38]).max() < 1e-5
    assert np.abs(solution.tau - exact_tau).max() < 1e-3
    assert dynamics_residual(graph) < 1e-6


@pytest.mark.parametrize("contact_forces", ["wrench", "corners"])
def test_standing_still_forces_carry_the_weight_and_the_cop_is_inside_the_soles(contact_forces):
    graph = build(contact_forces=contact_forces)
    solver = graph["solver"]
    weight = graph["robot"].state(0).total_mass * 9.81
    assert solver.normal_force_total(0) == pytest.approx(weight, rel=1e-4)
    inscribed = 0.3 / np.sqrt(2)
    for contact, forces in zip(solver.solution(0).contacts, solver.solution(0).forces):
        if contact_forces == "corners":
            corners = forces.reshape(4, 3)
            assert (corners[:, 2] >= -1e-6).all()  # unilateral corners: CoP inside the sole
            assert (np.abs(corners[:, :2]) <= inscribed * corners[:, 2:3] + 1e-6).all()
        else:  # the sole's wrench, contact frame: friction and a CoP inside the sole (0.10 front, 0.11 back)
            force, torque = forces[:3], forces[3:]
            assert force[2] > 0 and (np.abs(force[:2]) <= inscribed * force[2] + 1e-6).all()
            cop = np.array([-torque[1], torque[0]]) / force[2]
            assert -0.11 <= cop[0] <= 0.10 and abs(cop[1]) <= 0.069
    assert np.abs(solver.acceleration(0)).max() < 0.1  # holding still: small accelerations
    assert not solver.torque_limited(0)  # far from every limit: one solve, without the limit rows


@pytest.mark.parametrize("seed", range(5))
def test_a_soles_wrench_and_its_corner_forces_give_the_same_optimum(seed):
    """The wrench cone bounds exactly what the corners can exert and the metric is the least
    corner-force norm, so where no corner pyramid binds the two QPs have the same optimum: the
    same accelerations, torques and wrenches, to the solver's tolerance. (Where one binds, the
    corner QP also pays for the forces that move the corners back into their pyramids, the
    wrench QP does not: tau then differs by ~1 N m at these states with 10x the velocity.)"""
    q, v = perturbed_state(seed)
    wrench, corners = (build(q, 0.1 * v, contact_forces=mode, eps_abs=1e-9)["solver"] for mode in ("wrench", "corners"))
    assert wrench.solution(0).status == corners.solution(0).status == SOLVED
    assert len(wrench.solution(0).forces[0]) == 6 and len(corners.solution(0).forces[0]) == 12
    assert not np.abs(next(iter(corners._qp._workspaces.values())).free.latest[2]).max() > 1e-8  # no row binds
    np.testing.assert_allclose(wrench.acceleration(0), corners.acceleration(0), atol=1e-8)
    np.testing.assert_allclose(wrench.tau(0), corners.tau(0), atol=1e-4)
    np.testing.assert_allclose(wrench.contact_wrenches(0), corners.contact_wrenches(0), atol=1e-4)


def test_torque_limits_hold_when_a_task_asks_for_more():
    graph = build()
    graph["posture_task"].kp.set(1e4)  # the unconstrained torques would exceed the limits
    reference = half_sitting()[7:] + 0.5
    graph["posture"].reference.set(reference)
    solver = graph["solver"]
    limits = graph["robot"].pin_model.effortLimit[6:]
    assert solver.status(0) == SOLVED and solver.torque_limited(0)  # solved again with the limits
    assert (np.abs(solver.tau(0)) <= limits + 1e-5).all()
    assert (np.abs(solver.tau(0)) >= limits - 1e-3).any()  # some limit is active
    assert dynamics_residual(graph) < 1e-6


def test_contact_removed_at_run_time_drops_its_forces():
    graph = build()
    solver = graph["solver"]
    graph["left_foot"].deactivate()
    wrenches = solver.contact_wrenches(0)
    assert np.allclose(wrenches[0], 0.0) and wrenches[1, 2] > 0
    assert solver.status(0) == SOLVED
    graph["left_foot"].activate()
    assert solver.contact_wrenches(0)[0, 2] > 100


@pytest.mark.parametrize("scale", [0.0, 0.25, 0.6])
def test_a_scaled_normal_force_bound_caps_the_soles_load(scale):
    """A contact being removed: its normal force stays below ``scale * max_normal_force`` (1000 N),
    the other sole carries the rest of the weight; at 0 the sole carries nothing (its lower
    bound follows the upper one down)."""
    graph = build()
    solver, left = graph["solver"], graph["left_foot"]
    weight = graph["robot"].state(0).total_mass * 9.81
    left.normal_force_scale.set(scale)
    wrenches = solver.contact_wrenches(0)
    assert solver.status(0) == SOLVED
    assert wrenches[0, 2] <= 1000.0 * scale + 1e-2  # within the solver tolerance
    assert wrenches[0, 2] + wrenches[1, 2] == pytest.approx(weight, rel=1e-4)
    if scale == 0.0:
        assert abs(wrenches[0, 2]) < 1e-2
    else:  # free below the cap: the standing QP shares the weight (~500 N a sole)
        assert wrenches[0, 2] == pytest.approx(min(1000.0 * scale, weight / 2), rel=0.1)


def test_a_high_force_weight_scale_unloads_a_new_contact():
    """A contact being created: with its force weight scaled up, the QP shifts load to the other
    sole (the force jump of stack-of-tasks/tsid issue #88 is what the ramp avoids)."""
    graph = build()
    solver, left = graph["solver"], graph["left_foot"]
    even = solver.contact_wrenches(0)[0, 2]
    left.force_weight_scale.set(1e4)
    loaded = solver.contact_wrenches(0)
    assert solver.status(0) == SOLVED
    assert loaded[0, 2] < 0.5 * even and loaded[1, 2] > even
    left.force_weight_scale.set(1.0)
    assert solver.contact_wrenches(0)[0, 2] == pytest.approx(even, rel=1e-6)


def test_anchor_is_taken_at_the_first_tick_and_released_when_inactive():
    graph = build()
    foot = graph["left_foot"]
    graph.step()
    placement = graph["robot"].left_sole_link_placement(0)
    assert np.allclose(foot.anchor(1).homogeneous, placement)
    q = half_sitting()
    q[7:13] += 0.05  # the left leg moves: the anchor stays, the error grows
    graph["robot"].q.set(q)
    graph.step()
    assert np.allclose(foot.anchor(2).homogeneous, placement)
    assert np.linalg.norm(foot.error(2)) > 0.01
    foot.deactivate()
    graph.step()
    assert foot.anchor(3) is None
    foot.activate()
    graph.step()  # re-anchored where the foot is now
    assert np.allclose(foot.anchor(4).homogeneous, graph["robot"].left_sole_link_placement(3))
    assert foot.error(4) == pytest.approx(np.zeros(6), abs=1e-12)


def test_infeasible_problem_gives_a_status_and_the_fallback_torque():
    graph = build()
    state = graph["robot"].state(0)
    qp = InverseDynamicsQP(38, 6, graph["robot"].pin_model.effortLimit[6:])
    contact = graph["left_foot"].contact(0)
    impossible = type(contact)(**{**{f: getattr(contact, f) for f in contact.__dataclass_fields__},
                                  "friction_lower": np.r_[contact.friction_lower[:-1], 500.0],
                                  "friction_upper": np.r_[contact.friction_upper[:-1], 100.0]})
    solution = qp.solve(state.mass_matrix, state.bias_forces, [graph["com_task"].equation(0)], [impossible])
    assert solution.status == PRIMAL_INFEASIBLE
    assert solution.tau is None and not solution.acceleration.any()


@pytest.mark.filterwarnings("ignore:invalid value encountered")
def test_non_finite_task_data_falls_back_to_gravity_compensation():
    q, v = perturbed_state(7)
    graph = build(q, v)
    graph["com"].reference_position.set(np.zeros(3))
    graph["com_task"].kp.set(np.array([np.inf, 0.0, 0.0]))
    solver = graph["solver"]
    assert solver.status(0) == NOT_FINITE
    model = graph["robot"].pin_model
    gravity = pin.computeGeneralizedGravity(model, model.createData(), q)[6:]
    expected = np.clip(gravity - 1.0 * v[6:], -model.effortLimit[6:], model.effortLimit[6:])
    assert np.allclose(solver.tau(0), expected)
    graph["com_task"].kp.set(20.0)  # recovers at once (no warm start from the failure)
    assert solver.status(0) == SOLVED


def test_the_shared_robot_pass_runs_once_per_tick():
    graph = build()
    for _ in range(5):
        graph["robot"].q.set(graph["robot"].q(graph.t) + 1e-4)
        graph["solver"].tau(graph.t)
        graph["solver"].contact_wrenches(graph.t)
    assert graph["robot"].state.count == 5
    assert graph["solver"].solution.count == 5


def test_wrong_inputs_are_named():
    graph = build()
    graph.unplug("solver.com_task")
    with pytest.raises(dg.SpecError, match=r"solver\.com_task: expected a TaskEquation"):
        graph["solver"].com_task.set(np.zeros(3))
    graph.plug("com_task.equation", "solver.com_task")
    bad = graph["com_task"].equation(0)
    graph.unplug("solver.com_task")
    graph["solver"].com_task.set(type(bad)(bad.matrix, bad.vector, -bad.weight))
    with pytest.raises(Exception, match=r"solver\.com_task at tick 0: negative weights"):
        graph["solver"].tau(0)
    graph["solver"].com_task.set(type(bad)(bad.matrix[:2], bad.vector, bad.weight))
    with pytest.raises(Exception, match=r"solver\.com_task at tick 0: 2 rows but a vector of shape \(3,\)"):
        graph["solver"].tau(0)
    with pytest.raises(dg.SpecError, match=r"left_foot\.kp: must be >= 0"):  # refused where it is set
        graph["left_foot"].kp.set(-30.0)


def test_a_real_solver_failure_is_not_sticky():
    graph = build()
    graph["posture_task"].kp.set(1e5)  # absurd: ProxQP declares the problem primal infeasible
    graph["posture"].reference.set(half_sitting()[7:] + 0.5)
    solver = graph["solver"]
    assert solver.status(0) == PRIMAL_INFEASIBLE
    graph["posture_task"].kp.set(1e3)  # reasonable again: solved at once, no warm start from the failure
    assert solver.status(0) == SOLVED
    assert dynamics_residual(graph) < 1e-6

def test_validation_names_a_missing_frame_and_a_model_size_mismatch(tmp_path):
    import dgraph as dg
    from dgraph.entities.contacts import Contact6d
    from dgraph.entities.robot import RobotModel
    from dgraph.entities.solvers import InverseDynamicsSolver

    graph = dg.Graph(dt=0.001)
    graph.add(RobotModel("robot", model="talos_legs"))
    graph.add(Contact6d("foot", frame="left_sole"))
    graph.add(InverseDynamicsSolver("solver", model="talos"))
    graph.plug("robot.state", "foot.robot")
    graph.plug("robot.state", "solver.robot")
    problems = "\n".join(graph.problems())
    assert "foot.robot has no frame 'left_sole'" in problems
    assert "solver: its model has nv = 38 but the robot plugged into solver.robot has nv = 18" in problems
    bad = tmp_path / "bad.yaml"
    bad.write_text("dt: 0.001\nentities:\n  robot: {type: RobotModel}\n"
                   "  foot: {type: Contact6d, params: {frame: left_sole}}\nplugs: [robot.state -> foot.robot]\n")
    with pytest.raises(dg.GraphFileError, match=r"bad.yaml:4 \[entities.foot\].*no frame 'left_sole'"):
        dg.load(str(bad)).validate()


def test_the_assembly_allocates_no_array_in_steady_state():
    """Over 100 ticks of a moving robot, filling the QP allocates at most the small Python objects
    of numpy calls and keys (keyword dictionaries, views, tuples: ~1.4 kB at once), never an
    array of the problem's size (H alone is 31 kB, one task's A^T W A 11.5 kB, a contact's
    J^T T 3.6 kB); a whole solve adds only its answer (x, tau, the forces, the solution object).
    Measured as the peak of traced memory above its level before the call (tracemalloc traces
    numpy's buffers too)."""
    import tracemalloc

    from tests.entities.talos_graph import CONTACTS, TASKS

    graph = build()
    qp = graph["solver"]._qp
    q0 = half_sitting()

    def problem(tick):
        q = q0.copy()
        q[7:] += 1e-3 * np.sin(0.1 * tick + np.arange(32))
        graph["robot"].q.set(q)
        state = graph["robot"].state(tick)
        return (state.mass_matrix, state.bias_forces, [graph[n].equation(tick) for n in TASKS],
                [graph[n].contact(tick) for n in CONTACTS])

    def peak_above(call):
        before = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        call()
        return tracemalloc.get_traced_memory()[1] - before

    for tick in range(3):  # the first ticks make the workspace and the task layout
        qp.solve(*problem(tick), tick)
    tracemalloc.start()
    try:
        assembly, solve = [], []
        for tick in range(3, 103):
            data = problem(tick)
            assembly.append(peak_above(lambda data=data, tick=tick: qp.assemble(*data, tick=tick)))
            solve.append(peak_above(lambda data=data, tick=tick: qp.solve(*data, tick)))
    finally:
        tracemalloc.stop()
    assert max(assembly) < 2048, max(assembly)
    assert max(solve) < 4096, max(solve)


def test_the_cost_is_the_same_whether_a_task_is_steady_or_moving():
    """The posture task hands the same selection matrix and weights every tick: from the second
    tick its part of H is kept, only the moving tasks' rows are multiplied. H and g still equal
    sum_i 2 A_i^T W_i A_i + 2 eps I and -sum_i 2 A_i^T W_i b_i, tick after tick."""
    from tests.entities.talos_graph import CONTACTS, TASKS

    graph = build()
    qp = graph["solver"]._qp
    q0 = half_sitting()
    for tick in range(4):
        q = q0.copy()
        q[7:] += 1e-2 * np.sin(0.3 * tick + np.arange(32))
        graph["robot"].q.set(q)
        state = graph["robot"].state(tick)
        tasks = [graph[n].equation(tick) for n in TASKS]
        ws = qp.assemble(state.mass_matrix, state.bias_forces, tasks, [graph[n].contact(tick) for n in CONTACTS],
                         tick=tick)
        hessian = sum(2.0 * t.matrix.T @ (t.weight[:, None] * t.matrix) for t in tasks) + 2e-6 * np.eye(38)
        gradient = -sum(2.0 * t.matrix.T @ (t.weight * t.vector) for t in tasks)
        np.testing.assert_allclose(ws.H[:38, :38], hessian, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(ws.g[:38], gradient, rtol=1e-12, atol=1e-9)
    assert qp.task_rows(tasks, tick)._is_steady == (False, True, False)  # com, posture, waist


def test_the_finiteness_check_stays_below_openblas_threading():
    """OpenBLAS runs a dot product of more than 10,000 numbers on several threads; on a busy
    2-vCPU machine that stalled 1 tick in 40 of the push scenario for milliseconds. The check of
    the problem's buffer goes in chunks below that size, and still sees a NaN anywhere (corner
    forces: the larger problem)."""
    graph = build()
    solver = graph["solver"]
    assert solver.status(0) == SOLVED
    ws = next(iter(solver._qp._workspaces.values()))
    assert len(ws.data) > 9000 and max(len(chunk) for chunk in ws.chunks) <= 10_000
    assert sum(len(chunk) for chunk in ws.chunks) == len(ws.data)
    ws.data[-1] = np.nan
    assert not solver._qp._finite(ws)


@pytest.mark.parametrize("bad", [np.inf, np.nan])
def test_one_tick_of_non_finite_bias_forces_costs_one_tick(bad):
    """A non-finite h_j (seen only by the torques and their bounds) gives status 4 on its tick,
    and the next finite tick is solved again (nothing non-finite is left in the workspace)."""
    from tests.entities.talos_graph import CONTACTS, TASKS

    graph = build()
    qp = InverseDynamicsQP(38, 6, graph["robot"].pin_model.effortLimit[6:])
    state = graph["robot"].state(0)
    mass, bias = state.mass_matrix.copy(), state.bias_forces.copy()
    tasks = [graph[n].equation(0) for n in TASKS]
    contacts = [graph[n].contact(0) for n in CONTACTS]
    broken = bias.copy()
    broken[10] = bad
    statuses = [qp.solve(mass, h, tasks, contacts, k).status for k, h in enumerate([bias, broken, bias, bias])]
    assert statuses == [SOLVED, NOT_FINITE, SOLVED, SOLVED]


def test_solving_a_tick_again_gives_the_same_answer_bit_for_bit():
    """A graph with its cache off solves a tick once per read: cold (the first tick) or warm,
    every solve of a tick must agree exactly."""
    from tests.entities.talos_graph import CONTACTS, TASKS

    q, v = perturbed_state(3)
    graph = build(q, v)
    qp = InverseDynamicsQP(38, 6, graph["robot"].pin_model.effortLimit[6:])
    state = graph["robot"].state(0)
    problem = (state.mass_matrix.copy(), state.bias_forces.copy(), [graph[n].equation(0) for n in TASKS],
               [graph[n].contact(0) for n in CONTACTS])
    for tick in (0, 1):
        first, again = qp.solve(*problem, tick), qp.solve(*problem, tick)
        assert first.status == again.status == SOLVED and first.iterations == again.iterations
        assert np.array_equal(first.tau, again.tau) and np.array_equal(first.acceleration, again.acceleration)


def test_a_held_solution_passes_the_dependency_checks_time_after_time():
    """In the dependency-check mode a solution nothing changed for is solved again at each tick to
    check that it does not read the time; its solve time (and a warm start) differ between two
    solves of the same data, so it cannot be judged and is left alone: no false alarm, and the
    cache serves the first solve, as without the check."""
    graph = build()
    graph.check_dependencies = True
    solver = graph["solver"]
    first = solver.solution(0)
    for t in range(1, 4):
        assert solver.solution(t) is first and solver.tau(t) is solver.tau(0)


class RawConfiguration(dg.Entity):
    """A configuration as an estimator fed bad data would hand it over (NaN included: a constant may not be NaN)."""

    def setup(self):
        self.value = half_sitting()

    @dg.output(shape=(39,), depends=("t",), finite=None)
    def output(self, t):
        return self.value


def fallback_gravity(model, state_q, state_v, damping=1.0):
    """``g_j(q) - d v_j``, clipped to the torque limits."""
    gravity = pin.computeGeneralizedGravity(model, model.createData(), state_q)[6:]
    return np.clip(gravity - damping * state_v[6:], -model.effortLimit[6:], model.effortLimit[6:])


def test_a_non_finite_state_at_the_first_solve_gives_zero_torque():
    """No state was ever finite, so there is none to compute gravity compensation on: zero
    torque (finite), and the fault says so."""
    graph = build()
    raw = graph.add(RawConfiguration("raw"))
    raw.value = half_sitting()
    raw.value[10] = np.nan
    graph.plug("raw.output", "robot.q")
    solver = graph["solver"]
    assert solver.status(0) == NOT_FINITE
    assert np.array_equal(solver.tau(0), np.zeros(32))
    [fault] = graph.fault_log.staged(0)
    assert (fault.signal, fault.cause) == ("solver.tau", "solve failed: NOT_FINITE")
    assert fault.action == "fallback torque g(q) - d v on zero torque: no finite state yet"


def test_a_failed_solve_on_a_finite_state_falls_back_on_that_state():
    """Tick 0 is solved at half-sitting; tick 1 has another, finite state and a problem ProxQP
    finds primal infeasible: the fallback is computed on the state of tick 1, not on the last
    solved one, and the fault says which."""
    graph = build()
    solver = graph["solver"]
    assert solver.status(0) == SOLVED
    graph.step()
    q, v = perturbed_state(4)
    graph["robot"].q.set(q)
    graph["robot"].v.set(v)
    graph["posture_task"].kp.set(1e5)  # absurd: primal infeasible (test_a_real_solver_failure_is_not_sticky)
    graph["posture"].reference.set(half_sitting()[7:] + 0.5)
    assert solver.status(1) == PRIMAL_INFEASIBLE
    model = graph["robot"].pin_model
    np.testing.assert_allclose(solver.tau(1), fallback_gravity(model, q, v, solver.fallback_damping), rtol=0.0,
                               atol=1e-9)
    assert np.abs(solver.tau(1) - fallback_gravity(model, half_sitting(), np.zeros(38))).max() > 0.1  # not tick 0's
    [fault] = graph.fault_log.staged(1)
    assert fault.action == "fallback torque g(q) - d v on the state at this tick"
