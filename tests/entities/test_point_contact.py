"""PointContact: motion rows by finite differences of the point, friction rows, anchoring, force reference."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.contacts import PointContact
from dgraph.entities.robot import RobotModel, load_model
from dgraph.entities.tasks import ForceTask

PARENT, OFFSET = "gripper_left_base_link", np.array([0.0, 0.0, -0.2])
TOOL = {"left_tool_tip": {"parent": PARENT, "translation": OFFSET.tolist()}}
EPS = 1e-6
H = 1e-4  # step of the second difference (truncation ~H^2, round-off ~1e-16 / H^2)


def random_state(model, seed):
    rng = np.random.default_rng(seed)
    q = pin.randomConfiguration(model, np.r_[-np.ones(3), model.lowerPositionLimit[3:]],
                                np.r_[np.ones(3), model.upperPositionLimit[3:]])
    return q, rng.normal(size=model.nv)


def tip(model, data, q):
    """The tool tip computed without the tool frame: the parent frame's placement applied to the offset."""
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[model.getFrameId(PARENT)].act(OFFSET).copy()


def contact_graph(q, v, **params):
    g = dg.Graph(dt=0.001, name="point_contact_test")
    robot = g.add(RobotModel("robot", tool_frames=TOOL))
    robot.q.set(q)
    robot.v.set(v)
    contact = g.add(PointContact("tool", frame="left_tool_tip", **params))
    g.plug("robot.state", "tool.robot")
    return g, robot, contact


@pytest.fixture(scope="module")
def model():
    return load_model("talos")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jacobian_and_drift_are_finite_differences_of_the_point(model, seed):
    q, v = random_state(model, seed)
    _, _, contact = contact_graph(q, v)
    data = model.createData()
    p = lambda dq: tip(model, data, pin.integrate(model, q, dq))  # noqa: E731
    rows = contact.contact(0)
    assert rows.jacobian.shape == (3, model.nv)
    jacobian = np.column_stack([(p(EPS * e) - p(-EPS * e)) / (2 * EPS) for e in np.eye(model.nv)])
    np.testing.assert_allclose(rows.jacobian, jacobian, atol=1e-6)
    # along q(s) = q + s v (constant v: a = 0) the point's acceleration is J_dot v; kp = kd = 0: rhs = -J_dot v
    drift = (p(H * v) - 2 * p(0 * v) + p(-H * v)) / H**2
    assert np.abs(drift).max() > 0.1  # a real test: the drift is not ~0 at a random state
    np.testing.assert_allclose(-rows.motion_rhs, drift, atol=2e-4 * max(1.0, np.abs(drift).max()))
    np.testing.assert_allclose(contact.position(0), p(0 * v), atol=1e-12)


def test_motion_rhs_is_the_pd_law_towards_the_anchor(model):
    q, v = random_state(model, 4)
    g, robot, contact = contact_graph(q, v)
    kp, kd = np.array([30.0, 40.0, 50.0]), 7.0
    contact.kp.set(kp)
    contact.kd.set(kd)
    g.step()  # anchored at p(q)
    anchor = contact.anchor.value.copy()
    _, v2 = random_state(model, 5)
    q2 = pin.integrate(model, q, 0.02 * v2)  # a nearby configuration, moving
    robot.q.set(q2)
    robot.v.set(v2)
    data = model.createData()
    p = lambda dq: tip(model, data, pin.integrate(model, q2, dq))  # noqa: E731
    velocity = (p(EPS * v2) - p(-EPS * v2)) / (2 * EPS)
    drift = (p(H * v2) - 2 * p(0 * v2) + p(-H * v2)) / H**2
    rows = contact.contact(g.t)
    error = p(0 * v2) - anchor
    assert np.linalg.norm(error) > 1e-3
    np.testing.assert_allclose(contact.error(g.t), error, atol=1e-12)
    np.testing.assert_allclose(rows.motion_rhs, -kp * error - kd * velocity - drift, atol=1e-3)


def test_friction_rows_accept_forces_in_the_pyramid_and_refuse_the_others():
    normal = np.array([0.3, -0.2, 1.0])
    mu, fmin, fmax = 0.6, 2.0, 80.0
    q = load_model("talos").referenceConfigurations["half_sitting"]
    _, _, contact = contact_graph(q, np.zeros(38), normal=normal.tolist(), mu=mu, min_normal_force=fmin,
                                  max_normal_force=fmax)
    rows = contact.contact(0)
    n = normal / np.linalg.norm(normal)
    feasible = lambda f: bool(np.all(rows.friction_matrix @ f <= rows.friction_upper + 1e-9)  # noqa: E731
                              and np.all(rows.friction_matrix @ f >= rows.friction_lower - 1e-9))
    np.testing.assert_allclose(rows.friction_matrix[-1], n)  # the normal force row uses the unit normal
    assert feasible(10.0 * n) and feasible(fmin * n) and feasible(fmax * n)
    assert not feasible(0.99 * fmin * n) and not feasible(1.01 * fmax * n) and not feasible(-10.0 * n)
    rng = np.random.default_rng(0)
    for _ in range(50):
        tangent = np.cross(n, rng.normal(size=3))
        tangent /= np.linalg.norm(tangent)
        # inside the pyramid's inscribed cone (radius mu / sqrt 2): feasible; outside Coulomb's cone: not
        assert feasible(20.0 * n + 0.99 * mu / np.sqrt(2) * 20.0 * tangent)
        assert not feasible(20.0 * n + 1.01 * mu * 20.0 * tangent)
    assert rows.n_forces == 3
    f = np.array([1.0, -2.0, 30.0])
    np.testing.assert_array_equal(rows.world_wrench(f), [*f, 0.0, 0.0, 0.0])


def test_anchor_on_activation_forget_on_deactivation_staged_only_on_change(model):
    q = model.referenceConfigurations["half_sitting"].copy()
    g, robot, contact = contact_graph(q, np.zeros(model.nv))
    p0 = contact.position(0).copy()
    assert contact.anchor.value is None
    np.testing.assert_array_equal(contact.error(0), np.zeros(3))  # no anchor yet: the point itself
    g.run(ticks=3)
    np.testing.assert_array_equal(contact.anchor.value, p0)
    assert contact.anchor.time == 1  # anchored at the first tick, not re-staged while it holds
    moved = q.copy()
    moved[0] += 0.01  # the whole robot 1 cm along x
    robot.q.set(moved)
    g.run(ticks=2)
    assert contact.anchor.time == 1
    np.testing.assert_allclose(contact.error(g.t), [0.01, 0.0, 0.0], atol=1e-12)
    contact.deactivate()
    assert not contact.contact(g.t).active
    g.step()
    assert contact.anchor.value is None and contact.anchor.time == 6
    g.run(ticks=2)
    assert contact.anchor.time == 6
    np.testing.assert_array_equal(contact.error(g.t), np.zeros(3))
    contact.activate()
    assert contact.contact(g.t).active
    g.step()
    np.testing.assert_allclose(contact.anchor.value, p0 + np.array([0.01, 0.0, 0.0]), atol=1e-12)  # re-anchored here
    assert contact.anchor.time == 9


def test_force_reference_flows_into_the_constraint(model):
    q = model.referenceConfigurations["half_sitting"]
    g, _, contact = contact_graph(q, np.zeros(model.nv), force_weight=10.0)
    rows = contact.contact(0)
    assert rows.force_reference is None  # unplugged and unset: a plain contact, not a force task
    assert rows.force_weight == 10.0
    contact.force_reference.set([0.0, 0.0, 3.0])
    np.testing.assert_array_equal(contact.contact(0).force_reference, [0.0, 0.0, 3.0])
    task = g.add(ForceTask("force_task"))
    task.reference.set([0.0, 0.0, 12.0])
    task.measured.set([0.0, 0.0, 10.0])
    task.p_gain.set(0.5)
    g.plug("force_task.force", "tool.force_reference")
    np.testing.assert_allclose(contact.contact(g.t).force_reference, [0.0, 0.0, 13.0])
    task.reference.set([1.0, 2.0, 3.0])
    task.measured.set([1.0, 2.0, 3.0])
    np.testing.assert_allclose(contact.contact(g.t).force_reference, [1.0, 2.0, 3.0])


@pytest.mark.parametrize(("params", "fragment"), [
    ({"normal": [0.0, 0.0, 0.0]}, "normal must be a non-zero 3-vector"),
    ({"normal": [0.0, 1.0]}, "normal must be a non-zero 3-vector"),
    ({"min_normal_force": 10.0, "max_normal_force": 5.0}, "max_normal_force < min_normal_force"),
])
def test_bad_parameters_name_the_entity(params, fragment):
    with pytest.raises(dg.ParamError, match=fragment) as info:
        PointContact("tool", frame="left_tool_tip", **params)
    assert info.value.entity == "tool" and str(info.value).startswith("tool:")


def test_a_frame_missing_from_the_model_is_reported(model):
    g = dg.Graph(dt=0.001)
    robot = g.add(RobotModel("robot"))  # no tool frame
    robot.q.set(model.referenceConfigurations["half_sitting"])
    robot.v.set(np.zeros(model.nv))
    g.add(PointContact("tool", frame="left_tool_tip"))
    g.plug("robot.state", "tool.robot")
    assert any("has no frame 'left_tool_tip'" in p for p in g.problems())
    with pytest.raises(dg.ParamError, match="tool: the robot model has no frame 'left_tool_tip'"):
        g["tool"].contact(0)


def test_the_gains_are_checked_where_they_are_set():
    tool = PointContact("tool", frame="left_tool_tip")
    tool.kp.set([1.0, 2.0, 3.0])
    with pytest.raises(dg.SpecError, match=r"tool\.kp: expected a scalar or 3 values, one per axis \(x y z, world\), "
                                           r"got 6 values"):
        tool.kp.set(np.ones(6))
    with pytest.raises(dg.SpecError, match=r"tool\.kd: must be >= 0, got -1\.0"):
        tool.kd.set(-1.0)
