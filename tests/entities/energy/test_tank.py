"""EnergyTank on TALOS and on a fixed-base arm: the passive QP row, bit-identical disabled mode,
tank bookkeeping, task removal, error paths (thesis Ch. 5, notes §7)."""

import dataclasses
import itertools

import numpy as np
import pytest

import dgraph as dg
from dgraph.control import Passivity
from dgraph.control.proxqp import INFINITY
from dgraph.entities.energy import EnergyTank
from dgraph.entities.energy.power import stiffness, task_power, task_space_inertia
from dgraph.entities.features import JointPosture
from dgraph.entities.robot import RobotModel, load_model
from dgraph.entities.solvers import InverseDynamicsSolver
from dgraph.entities.tasks import Task
from tests.entities.talos_graph import CONTACTS, TASKS, build, half_sitting


def passive_graph(enabled=True, seed=0, **tank_params):
    """The shared TALOS ID graph with a tank and a passive solver (robot state set by hand)."""
    g = build(passive=True)
    g.add(EnergyTank("tank", tasks=list(TASKS), contacts=list(CONTACTS), enabled=enabled, **tank_params))
    g.plug("robot.state", "tank.robot")
    for name in TASKS:
        g.plug(f"{name}.equation", f"tank.{name}")
    for name in CONTACTS:
        g.plug(f"{name}.contact", f"tank.{name}")
    g.plug("tank.passivity", "solver.passivity")
    g.plug("solver.solution", "tank.solution")
    return g


def moving_states(n, seed, speed=0.3):
    """A random walk of (q, v) around half-sitting (joints only move; the base stays)."""
    rng = np.random.default_rng(seed)
    model = load_model("talos")
    q, v = half_sitting(), np.zeros(model.nv)
    for _ in range(n):
        v[6:] = 0.9 * v[6:] + speed * rng.normal(size=model.nv - 6) * 0.3
        q = q.copy()
        q[7:] += 0.001 * v[6:]
        yield q, v.copy()


def run(g, states, read=()):
    """Step the graph through the states, reading ``read`` (signal names) at every tick."""
    rows = []
    for q, v in states:
        g["robot"].q.set(q)
        g["robot"].v.set(v)
        rows.append({name: g.signal(name)(g.t) for name in read})
        g.step()
    return rows


def test_the_passivity_row_holds_at_every_feasible_tick():
    g = passive_graph()
    rows = run(g, moving_states(150, seed=1), ("tank.power_bound", "tank.delivered_power", "solver.status",
                                               "solver.passivity_relaxed"))
    solved = [r for r in rows if r["solver.status"] == 0 and not r["solver.passivity_relaxed"]]
    assert len(solved) == len(rows)
    assert max(r["tank.power_bound"] - r["tank.delivered_power"] for r in solved) < 1e-6
    assert any(abs(r["tank.delivered_power"]) > 1e-2 for r in rows)  # the state does move


def test_the_row_is_minus_v_dot_tau_when_the_base_rows_hold():
    """Row algebra: -v_j^T tau == -v^T (M a + h - J_c^T T f) with the QP's a, f."""
    g = passive_graph()
    states = list(moving_states(30, seed=2))
    run(g, states[:-1])
    q, v = states[-1]
    g["robot"].q.set(q)
    g["robot"].v.set(v)
    solution, state = g["solver"].solution(g.t), g["robot"].state(g.t)
    generalized = sum(c.jacobian.T @ c.force_generator @ f for c, f in zip(solution.contacts, solution.forces,
                                                                            strict=True))
    full = state.mass_matrix @ solution.acceleration + state.bias_forces - generalized
    assert np.abs(full[:6]).max() < 1e-6
    assert -v[6:] @ solution.tau == pytest.approx(-v @ full, abs=1e-6)


def test_a_disabled_tank_leaves_the_qp_bit_identical():
    plain, passive = build(), passive_graph(enabled=False)
    for q, v in moving_states(40, seed=3):
        for g in (plain, passive):
            g["robot"].q.set(q)
            g["robot"].v.set(v)
        a, b = plain["solver"].solution(plain.t), passive["solver"].solution(passive.t)
        ws_a = next(iter(plain["solver"]._qp._workspaces.values()))
        ws_b = next(iter(passive["solver"]._qp._workspaces.values()))
        for name in ("H", "g", "A", "b", "C", "lower", "upper"):  # the problem, bit for bit
            assert np.array_equal(getattr(ws_a, name), getattr(ws_b, name)), name
        # two ProxQP objects solving the same data differ by ~1e-14 (vectorised sums on differently
        # aligned buffers), so the answers agree to round-off, not bitwise
        assert np.abs(a.tau - b.tau).max() < 1e-10 and a.iterations == b.iterations
        plain.step()
        passive.step()


def test_zero_scale_zeroes_every_task_vector_and_force_reference():
    g = passive_graph()
    q, v = list(moving_states(20, seed=9))[-1]
    g["robot"].q.set(q)
    g["robot"].v.set(v)
    state = g["robot"].state(0)
    tasks = [g[name].equation(0) for name in TASKS]
    contacts = [g[name].contact(0) for name in CONTACTS]
    qp = g["solver"]._qp
    ws = qp.assemble(state.mass_matrix, state.bias_forces, tasks, contacts, Passivity(1.0, -0.3, state.v))
    assert ws.upper[-qp.n_actuated - 1] == INFINITY and np.abs(ws.g).max() > 1e-3
    ws = qp.assemble(state.mass_matrix, state.bias_forces, tasks, contacts, Passivity(0.0, None, state.v))
    assert not ws.g.any()
    # a contact with a force reference (a force task): its reference is scaled too
    # (in the contact's force metric M, when it has one: the gradient is -2 w s M f*)
    k = contacts[0].n_forces
    pushing = dataclasses.replace(contacts[0], name="pushing", force_reference=np.full(k, 5.0))
    metric = np.diag(np.arange(1.0, k + 1.0)) + 0.1
    for contact, gradient in ((pushing, np.full(k, 5.0)), (dataclasses.replace(pushing, force_metric=metric),
                                                            metric @ np.full(k, 5.0))):
        for scale in (1.0, 0.5, 0.0):
            ws = qp.assemble(state.mass_matrix, state.bias_forces, tasks, [contact, contacts[1]],
                             Passivity(scale, None, state.v))
            forces = slice(qp.nv, qp.nv + k)
            np.testing.assert_allclose(ws.g[forces], -2.0 * contact.force_weight * scale * gradient)
            np.testing.assert_allclose(ws.H[forces, forces], 2.0 * contact.force_weight * (
                np.eye(k) if contact.force_metric is None else metric))


def test_tank_bookkeeping_adds_up_and_stays_in_its_bounds():
    g = passive_graph(initial_energy=4.9, band=0.1)
    names = ("tank.energy", "tank.delivered_power", "tank.storage_rate", "tank.alpha", "tank.beta", "tank.gamma",
             "tank.correction")
    rows = run(g, moving_states(200, seed=4, speed=2.0), names)
    energy = rows[0]["tank.energy"]
    for row, after in itertools.pairwise(rows):
        flow = row["tank.delivered_power"] - row["tank.beta"] * row["tank.gamma"] * row["tank.storage_rate"]
        alpha = g["tank"]._overflow(row["tank.energy"], flow)  # the valve of the actual flow
        energy += 0.001 * (1 - alpha) * flow + (after["tank.correction"] - row["tank.correction"])
        assert after["tank.energy"] == pytest.approx(energy, abs=1e-12)
        assert 0.1 <= after["tank.energy"] <= 5.0
    assert max(r["tank.alpha"] for r in rows) > 0.0  # the overflow valve acted near E_max


def test_the_overflow_valve_keeps_the_energy_under_its_maximum_without_the_clamp():
    """The QP row bounds the delivered power from below only: a tank that planned to drain may
    fill, so the valve must act on the actual flow (Eq. 5.23), not the planned one."""
    g = passive_graph(initial_energy=4.95, clamp=False)
    rows = run(g, moving_states(300, seed=4, speed=2.0), ("tank.energy", "tank.correction"))
    energies = [r["tank.energy"] for r in rows]
    assert max(energies) <= 5.0 + 1e-9 and rows[-1]["tank.correction"] == 0.0
    assert max(energies) > 4.99  # it did press against E_max


def test_a_disabled_tank_integrates_what_the_plain_qp_delivered():
    g = passive_graph(enabled=False)
    rows = run(g, moving_states(60, seed=10, speed=2.0), ("tank.energy", "tank.delivered_power",
                                                           "tank.storage_rate", "tank.correction"))
    for row, after in itertools.pairwise(rows):
        flow = row["tank.delivered_power"] - row["tank.storage_rate"]  # the QP ran with beta gamma = 1
        overflow = g["tank"]._overflow(row["tank.energy"], flow)  # the same capacity E_max
        expected = row["tank.energy"] + 0.001 * (1.0 - overflow) * flow
        assert after["tank.energy"] == pytest.approx(expected, abs=1e-12)
    assert rows[-1]["tank.correction"] == 0.0
    assert min(r["tank.energy"] for r in rows) < 0.1 or max(r["tank.energy"] for r in rows) > 4.9  # it moved


def test_an_angular_momentum_task_stores_no_energy_but_its_damping_power_counts():
    from dgraph.entities.energy.tank import task_block
    from dgraph.entities.features import AngularMomentum

    g = passive_graph()
    momentum = g.add(AngularMomentum("momentum"))
    task = g.add(Task("momentum_task"))
    task.kp.set(10.0)
    g.plug("robot.state", "momentum.robot")
    g.plug("momentum.feature", "momentum_task.feature")
    q, v = list(moving_states(10, seed=11))[-1]
    g["robot"].q.set(q)
    g["robot"].v.set(v)
    block = task_block(task.equation(0), v)
    assert not block.error.any() and not block.kp.any()
    np.testing.assert_array_equal(block.error_velocity, momentum.error(0))  # k - k*
    np.testing.assert_array_equal(block.kd, np.full(3, 10.0))


def test_rows_with_zero_weight_are_left_out_of_the_storage():
    from dgraph.entities.energy.tank import task_block

    g = passive_graph()
    q, v = list(moving_states(10, seed=12))[-1]
    g["robot"].q.set(q)
    g["robot"].v.set(v)
    g["posture_task"].weight.set(np.r_[np.zeros(12), np.full(20, 0.1)])  # legs out
    block = task_block(g["posture_task"].equation(0), v)
    assert len(block.error) == 20 and block.jacobian.shape == (20, 38)


def test_an_empty_tank_gives_no_nan():
    g = passive_graph(minimum_energy=0.0, initial_energy=0.0, band=0.0)
    rows = run(g, moving_states(30, seed=5), ("tank.energy", "tank.beta", "tank.gamma", "tank.power_bound",
                                              "solver.status"))
    for row in rows:
        assert all(np.isfinite(value) for value in row.values())


def test_removing_a_task_drops_its_history_and_re_adding_it_starts_without_a_rate_spike():
    g = passive_graph()
    states = list(moving_states(12, seed=6))
    run(g, states[:5])
    assert "posture_task" in g["tank"].previous_stiffness(g.t)
    g["posture_task"].weight.set(0.0)
    run(g, states[5:8])
    assert "posture_task" not in g["tank"].previous_stiffness(g.t)
    g["posture_task"].weight.set(0.1)
    q, v = states[8]
    g["robot"].q.set(q)
    g["robot"].v.set(v)
    tank = g["tank"]
    budget, history = tank.budget(g.t), tank.previous_stiffness(g.t)
    assert "posture_task" in budget.stiffness and "posture_task" not in history
    # S_dot rebuilt by hand: P_dot by finite difference for the tasks with a history, 0 for the
    # re-added posture (no spike from a P that jumped from nothing)
    state = g["robot"].state(g.t)
    expected = 0.0
    for key, block in tank._blocks(v, g.t).items():
        inertia = task_space_inertia(block.jacobian, state.mass_matrix, state.inverse_mass_matrix)
        p = stiffness(block, inertia)
        rate = (p - history[key]) / 0.001 if key in history else np.zeros_like(p)
        expected += task_power(block, inertia, rate).storage_rate
    assert budget.storage_rate == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_stacked_inertia_keeps_the_passivity_row():
    g = passive_graph(inertia="stacked")
    rows = run(g, moving_states(40, seed=7), ("tank.storage", "tank.power_bound", "tank.delivered_power",
                                              "solver.status"))
    assert all(r["solver.status"] == 0 for r in rows)
    assert max(r["tank.power_bound"] - r["tank.delivered_power"] for r in rows) < 1e-6


def test_fixed_base_arm():
    """N = I, v = q_dot (UR5): the same tank and passive row, no unactuated rows."""
    g = dg.Graph(dt=0.001)
    robot = g.add(RobotModel("robot", model="ur5"))
    model = robot.pin_model
    posture = g.add(JointPosture("posture", model="ur5", reference_configuration=""))
    posture.reference.set(np.full(model.nq, 0.3))
    task = g.add(Task("posture_task"))
    task.kp.set(50.0)
    task.kd.set(10.0)
    g.add(InverseDynamicsSolver("solver", model="ur5", tasks=["posture_task"], passive=True))
    tank = g.add(EnergyTank("tank", tasks=["posture_task"]))
    for reader in ("posture", "solver", "tank"):
        g.plug("robot.state", f"{reader}.robot")
    g.plug("posture.feature", "posture_task.feature")
    g.plug("posture_task.equation", "solver.posture_task")
    g.plug("posture_task.equation", "tank.posture_task")
    g.plug("tank.passivity", "solver.passivity")
    g.plug("solver.solution", "tank.solution")
    rng = np.random.default_rng(8)
    relaxed = 0
    for _ in range(50):
        robot.q.set(rng.uniform(-1, 1, model.nq))
        robot.v.set(rng.normal(size=model.nv))
        solution = g["solver"].solution(g.t)
        assert solution.status == 0
        v = robot.v(g.t)
        if solution.passivity_relaxed:  # only when no torque within the limits can meet the bound
            relaxed += 1
            assert tank.power_bound(g.t) > np.abs(v) @ model.effortLimit
            assert solution.iterations < 100  # recognised up front, not by running ProxQP to its limit
        else:
            assert tank.power_bound(g.t) <= -v @ solution.tau + 1e-6
        assert tank.delivered_power(g.t) == pytest.approx(-v @ solution.tau)
        g.step()
    assert relaxed < 5


def test_tank_errors_name_the_entity_and_input():
    with pytest.raises(dg.ParamError, match="tank: minimum_energy"):
        EnergyTank("tank", minimum_energy=5.0, maximum_energy=1.0)
    with pytest.raises(dg.ParamError, match="initial_energy"):
        EnergyTank("tank", initial_energy=9.0)
    with pytest.raises(dg.ParamError, match="power_low must be < 0"):
        EnergyTank("tank", power_low=0.0)
    with pytest.raises(dg.ParamError, match="'robot' cannot name an input"):
        EnergyTank("tank", tasks=["robot"])
    g = passive_graph()
    with pytest.raises(dg.PlugError, match=r"left_foot.contact ContactConstraint into tank.com_task TaskEquation"):
        g.plug("left_foot.contact", "tank.com_task")  # refused at plug time: the old plug stays
    assert g["tank"].com_task.source.full_name == "com_task.equation"
