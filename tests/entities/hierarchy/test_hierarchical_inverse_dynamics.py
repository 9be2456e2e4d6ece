"""HierarchicalInverseDynamics on TALOS: dynamics and constraints on top, strict priorities below."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.control import NOT_FINITE, SOLVED
from dgraph.entities.hierarchy import HierarchicalInverseDynamics
from tests.entities.talos_graph import CONTACTS, TASKS, build
from tests.entities.test_inverse_dynamics import perturbed_state


def hierarchical(seed=None, tasks=("com_task", "waist_task", "posture_task"), contact_forces="corners"):
    q, v = perturbed_state(seed) if seed is not None else (None, None)
    g = build(q, v, contact_forces=contact_forces)
    g.add(HierarchicalInverseDynamics("hsolver", tasks=list(TASKS), contacts=list(CONTACTS)))
    g.plug("robot.state", "hsolver.robot")
    for name in TASKS:
        g.plug(f"{name}.equation", f"hsolver.{name}")
    for name in CONTACTS:
        g.plug(f"{name}.contact", f"hsolver.{name}")
    solver = g["hsolver"]
    solver.stack.set(tuple((name,) for name in tasks))
    return g, solver


@pytest.mark.parametrize(("seed", "contact_forces"), [(None, "corners"), (0, "corners"), (1, "corners"),
                                                     (None, "wrench"), (0, "wrench")])
def test_dynamics_contacts_friction_and_limits_hold(seed, contact_forces):
    """Also with the soles' wrenches as variables (their regularisation level in the corner-force metric)."""
    g, solver = hierarchical(seed, contact_forces=contact_forces)
    solution = solver.solution(0)
    assert solution.status == SOLVED
    state = g["robot"].state(0)
    generalized = sum(c.jacobian.T @ (c.force_generator @ f) for c, f in zip(solution.contacts, solution.forces))
    torque = np.r_[np.zeros(6), solution.tau]
    assert np.abs(state.mass_matrix @ solution.acceleration + state.bias_forces - generalized - torque).max() < 1e-6
    for contact, forces in zip(solution.contacts, solution.forces):
        assert np.abs(contact.jacobian @ solution.acceleration - contact.motion_rhs).max() < 1e-6
        values = contact.friction_matrix @ forces
        assert (values >= contact.friction_lower - 1e-6).all() and (values <= contact.friction_upper + 1e-6).all()
    assert (np.abs(solution.tau) <= g["robot"].pin_model.effortLimit[6:] + 1e-6).all()


def test_the_com_task_is_not_traded_against_the_posture():
    g, solver = hierarchical(0)
    com = g["com_task"].equation(0)
    strict = np.linalg.norm(com.residual(solver.acceleration(0)))
    solver.remove("posture_task")
    alone = np.linalg.norm(com.residual(solver.acceleration(0)))
    assert strict == pytest.approx(alone, abs=1e-6)
    weighted = np.linalg.norm(com.residual(g["solver"].acceleration(0)))  # the weighted QP trades it
    assert strict < weighted


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
def test_a_non_finite_task_gives_the_fallback_torque_and_a_status():
    g, solver = hierarchical()
    g["com_task"].kp.set(1e308)
    g["com"].reference_position.set(np.array([1e308, 0.0, 0.0]))
    assert solver.status(0) == NOT_FINITE
    state = g["robot"].state(0)
    gravity = pin.computeGeneralizedGravity(state.model, state.model.createData(), state.q)[6:]
    np.testing.assert_allclose(solver.tau(0), np.clip(gravity - solver.fallback_damping * state.v[6:],
                                                      -solver.effort_limit, solver.effort_limit))
    (fault,) = g.fault_log.staged(0)
    assert (fault.signal, fault.cause) == (f"{solver.name}.tau", "solve failed: NOT_FINITE")


def test_there_is_no_passive_mode_to_ignore():
    """No passivity row: no ``passive`` parameter (asking for one is refused, naming it), no
    ``passivity`` input and none of the weighted solver's passivity outputs."""
    with pytest.raises(dg.ParamError, match=r"unknown parameter\(s\) passive"):
        HierarchicalInverseDynamics("hid", passive=True)
    solver = HierarchicalInverseDynamics("hid")
    assert not any(hasattr(solver, name) for name in ("passivity", "passivity_relaxed", "torque_limited"))


def test_a_task_cannot_be_named_after_the_stack_input():
    with pytest.raises(dg.ParamError, match="'stack' cannot name an input"):
        HierarchicalInverseDynamics("hid", tasks=["stack"])
