"""RobotModel and RobotState: dynamics terms, and every Jacobian and drift by finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.robot import RobotModel, RobotState, load_model
from dgraph.entities.robot.robot_state import LOCAL, WORLD, DataFields

EPS = 1e-6


@pytest.fixture(scope="module")
def model():
    return load_model("talos")


def random_state(model, seed):
    rng = np.random.default_rng(seed)
    q = pin.randomConfiguration(model, np.r_[-np.ones(3), model.lowerPositionLimit[3:]],
                                np.r_[np.ones(3), model.upperPositionLimit[3:]])
    return q, rng.normal(size=model.nv)


def robot_at(model, seed, frames=()):
    """A RobotModel (with ``frames`` as outputs) in a graph, at the random state of ``seed``."""
    robot = dg.Graph(dt=0.001).add(RobotModel("robot", frames=list(frames)))
    q, v = random_state(model, seed)
    robot.q.set(q)
    robot.v.set(v)
    return robot, q, v


def state_at(model, q, v):
    return RobotState(model, DataFields(model.createData()), q, v)


def central(f, model, q, direction):
    """(f(q + eps d) - f(q - eps d)) / 2 eps on the configuration manifold."""
    return (f(pin.integrate(model, q, EPS * direction)) - f(pin.integrate(model, q, -EPS * direction))) / (2 * EPS)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_mass_matrix_and_bias_forces_match_pinocchio(model, seed):
    q, v = random_state(model, seed)
    state = state_at(model, q, v)
    data = model.createData()
    pin.crba(model, data, q)
    upper = np.triu(data.M)
    assert np.allclose(state.mass_matrix, upper + np.triu(upper, 1).T, atol=1e-10)
    np.testing.assert_array_equal(state.mass_matrix, state.mass_matrix.T)  # copied as its transpose
    assert np.allclose(state.bias_forces, pin.rnea(model, data, q, v, np.zeros(model.nv)), atol=1e-9)


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("frame", ["left_sole_link", "arm_right_7_link"])
def test_world_frame_jacobian_and_drift_by_finite_differences(model, seed, frame):
    q, v = random_state(model, seed)
    state = state_at(model, q, v)
    fid = model.getFrameId(frame)
    jacobian = state.frame_jacobian(fid, WORLD)
    reference = state.frame_placement(fid)

    def pose_vector(qq):  # translation and rotation vector relative to the reference rotation
        placement = state_at(model, qq, v).frame_placement(fid)
        return np.concatenate([placement.translation, pin.log3(placement.rotation @ reference.rotation.T)])

    for i in range(0, model.nv, 5):
        e = np.zeros(model.nv)
        e[i] = 1.0
        assert np.allclose(central(pose_vector, model, q, e), jacobian[:, i], atol=1e-6), i
    velocity = lambda qq: state_at(model, qq, v).frame_jacobian(fid, WORLD) @ v  # noqa: E731
    assert np.allclose(central(velocity, model, q, v), state.frame_drift(fid, WORLD), atol=1e-5)
    assert np.allclose(state.frame_velocity(fid, WORLD), jacobian @ v, atol=1e-12)


def test_local_frame_jacobian_and_drift_by_finite_differences(model):
    q, v = random_state(model, 3)
    state = state_at(model, q, v)
    fid = model.getFrameId("right_sole_link")
    jacobian = state.frame_jacobian(fid, LOCAL)
    placement = state.frame_placement(fid)
    twist = lambda qq: pin.log6(placement.actInv(state_at(model, qq, v).frame_placement(fid))).vector  # noqa: E731
    for i in range(0, model.nv, 4):
        e = np.zeros(model.nv)
        e[i] = 1.0
        assert np.allclose(central(twist, model, q, e), jacobian[:, i], atol=1e-6), i
    body_twist = lambda qq: state_at(model, qq, v).frame_jacobian(fid, LOCAL) @ v  # noqa: E731
    assert np.allclose(central(body_twist, model, q, v), state.frame_drift(fid, LOCAL), atol=1e-5)


def test_com_and_centroidal_terms_by_finite_differences(model):
    q, v = random_state(model, 4)
    state = state_at(model, q, v)
    com = lambda qq: state_at(model, qq, v).com.position  # noqa: E731
    for i in range(0, model.nv, 3):
        e = np.zeros(model.nv)
        e[i] = 1.0
        assert np.allclose(central(com, model, q, e), state.com.jacobian[:, i], atol=1e-7), i
    assert np.allclose(state.com.velocity, state.com.jacobian @ v, atol=1e-12)
    com_velocity = lambda qq: state_at(model, qq, v).com.jacobian @ v  # noqa: E731
    assert np.allclose(central(com_velocity, model, q, v), state.com.drift, atol=1e-5)
    momentum = lambda qq: state_at(model, qq, v).centroidal_momentum_matrix @ v  # noqa: E731
    assert np.allclose(central(momentum, model, q, v), state.centroidal_drift, atol=1e-4)
    # linear momentum is m * com velocity
    assert np.allclose(state.centroidal_momentum[:3], state.total_mass * state.com.velocity, atol=1e-9)


def test_entity_outputs_share_one_pass_per_tick(model):
    robot, q, _ = robot_at(model, 5, frames=["left_sole_link", "right_sole_link"])
    for name in ("mass_matrix", "bias_forces", "com_position", "com_jacobian", "centroidal_drift",
                 "left_sole_link_jacobian", "right_sole_link_placement", "right_sole_link_drift"):
        robot.signal(name)(0)
    assert robot.state.count == 1
    assert robot.left_sole_link_placement(0).shape == (4, 4)
    assert np.allclose(robot.com_position(0), pin.centerOfMass(model, model.createData(), q))
    robot.q.set(pin.neutral(model))
    robot.com_position(0)
    assert robot.state.count == 2


def test_each_quantity_is_computed_once_per_state_and_matches_pinocchio(model):
    robot, q, v = robot_at(model, 7, frames=["left_sole_link"])
    state, fid = robot.state(0), model.getFrameId("left_sole_link")
    assert state.com is state.com and state.frame(fid) is state.frame(fid, WORLD)
    assert state.frame(fid, LOCAL) is not state.frame(fid, WORLD)
    sole = state.frame(fid)  # the frame outputs hand out the state's arrays, not copies of them
    assert robot.left_sole_link_jacobian(0) is sole.jacobian and robot.left_sole_link_drift(0) is sole.drift
    assert robot.left_sole_link_placement(0) is sole.placement and robot.left_sole_link_velocity(0) is sole.velocity
    data = model.createData()
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    for ref in (WORLD, LOCAL):
        frame = state.frame(fid, ref)
        np.testing.assert_array_equal(frame.jacobian, pin.getFrameJacobian(model, data, fid, ref))
        np.testing.assert_array_equal(frame.velocity, pin.getFrameVelocity(model, data, fid, ref).vector)
        np.testing.assert_array_equal(frame.rotation, data.oMf[fid].rotation)
        np.testing.assert_array_equal(frame.translation, data.oMf[fid].translation)
    local_drift = pin.getFrameAcceleration(model, data, fid, LOCAL).vector
    np.testing.assert_array_equal(state.frame(fid, LOCAL).drift, local_drift)
    np.testing.assert_array_equal(sole.drift, pin.getFrameClassicalAcceleration(model, data, fid, WORLD).vector)
    np.testing.assert_array_equal(state.centroidal_momentum, data.Ag @ v)
    drift = pin.computeCentroidalMomentumTimeVariation(model, data, q, v, np.zeros(model.nv)).vector
    np.testing.assert_allclose(state.centroidal_drift, drift, rtol=1e-12, atol=1e-10)  # dA_G v: the same rate


def test_every_array_a_state_hands_out_is_read_only(model):
    q, v = random_state(model, 3)
    state = state_at(model, q, v)
    fid = model.getFrameId("left_sole_link")
    frame, com = state.frame(fid), state.com
    shared = [state.mass_matrix, state.bias_forces, state.inverse_mass_matrix, state.centroidal_momentum_matrix,
              state.centroidal_momentum, state.centroidal_drift, com.position, com.velocity, com.jacobian, com.drift,
              frame.placement, frame.rotation, frame.translation, frame.velocity, frame.jacobian, frame.drift]
    for array in shared:
        with pytest.raises(ValueError, match="read-only"):
            array[...] = 0.0
    assert state.inverse_mass_matrix is state.inverse_mass_matrix  # computed once, like the others
    assert np.allclose(state.mass_matrix @ state.inverse_mass_matrix, np.eye(model.nv), atol=1e-8)  # untouched


def test_the_mass_matrix_outputs_are_copies_that_outlive_the_pass(model):
    robot, q, v = robot_at(model, 8)
    mass, bias = robot.mass_matrix(0), robot.bias_forces(0)
    state = robot.state(0)
    assert np.shares_memory(state.mass_matrix, state.data.M) and not np.shares_memory(mass, state.data.M)
    np.testing.assert_array_equal(mass, state.mass_matrix)
    np.testing.assert_array_equal(bias, state.bias_forces)
    robot.q.set(pin.neutral(model))
    robot.mass_matrix(0)  # a new pass on the shared data: the values handed out before do not move
    data = model.createData()
    pin.computeAllTerms(model, data, q, v)
    np.testing.assert_array_equal(mass, data.M.T)
    np.testing.assert_array_equal(bias, data.nle)


def test_bad_frame_and_model_are_clear_errors():
    with pytest.raises(dg.ParamError, match="no frame 'nope'"):
        RobotModel("robot", frames=["nope"])
    with pytest.raises(dg.ParamError, match="robot: cannot load robot model 'no_such_robot'"):
        RobotModel("robot", model="no_such_robot")
    from dgraph.entities.devices import KinematicDevice
    from dgraph.entities.estimators import FloatingBaseEstimator

    for entity in (lambda: KinematicDevice("dev", model=3), lambda: FloatingBaseEstimator("est", model=3)):
        with pytest.raises(dg.ParamError, match="model must be a robot name or a pinocchio.Model, got int"):
            entity()


def test_a_state_kept_past_its_pass_raises_instead_of_answering_for_another(model):
    robot, q, _ = robot_at(model, 6)
    old = robot.state(0)
    fid = model.getFrameId("left_sole_link")
    com, placement, sole = old.com, old.frame_placement(fid), old.frame(fid)
    robot.q.set(pin.neutral(model))
    robot.state(0)  # a new pass on the shared data
    reads = (lambda: old.centroidal_drift, lambda: old.frame(fid, LOCAL), lambda: old.frame_placement(fid),
             lambda: old.mass_matrix, lambda: old.bias_forces)  # views of the data: they would answer for the new pass
    for read in reads:
        with pytest.raises(dg.DGraphError, match="read after its Pinocchio data was reused"):
            read()
    assert old.com is com and old.frame(fid) is sole  # what it computed before is still its own
    com = com.position
    assert np.allclose(com, pin.centerOfMass(model, model.createData(), q))
    assert np.array_equal(sole.placement, placement.homogeneous)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    assert np.allclose(placement.homogeneous, data.oMf[model.getFrameId("left_sole_link")].homogeneous)


def test_inverse_mass_matrix_inverts_the_mass_matrix_and_leaves_the_drifts():
    g = dg.Graph()
    robot = g.add(RobotModel("robot"))
    rng = np.random.default_rng(11)
    model = robot.pin_model
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    robot.q.set(q)
    robot.v.set(rng.normal(size=model.nv))
    state = robot.state(0)
    inverse = state.inverse_mass_matrix
    assert np.abs(inverse @ state.mass_matrix - np.eye(model.nv)).max() < 1e-9
    # terms computed after the inverse: the same as a fresh pass's
    fresh = RobotState(model, DataFields(model.createData()), state.q, state.v)
    np.testing.assert_array_equal(state.centroidal_drift, fresh.centroidal_drift)
    for name in ("position", "velocity", "jacobian", "drift"):
        np.testing.assert_array_equal(getattr(state.com, name), getattr(fresh.com, name))
    np.testing.assert_array_equal(state.frame(3, LOCAL).drift, fresh.frame(3, LOCAL).drift)


def test_the_field_views_made_once_per_data_follow_every_pass_on_it(model):
    """A RobotModel's states share the views of its data's fields (made once): after passes on other
    states they still give what a state on a fresh data gives, bit for bit."""
    robot, _, _ = robot_at(model, 9)
    for seed in (10, 11, 12):
        q, v = random_state(model, seed)
        robot.q.set(q)
        robot.v.set(v)
        state, fresh = robot.state(0), state_at(model, q, v)
        assert state.fields is robot.state(0).fields
        for name in ("mass_matrix", "bias_forces", "centroidal_momentum_matrix", "centroidal_momentum",
                     "centroidal_drift"):
            np.testing.assert_array_equal(getattr(state, name), getattr(fresh, name))
        for name in ("position", "velocity", "jacobian", "drift"):
            np.testing.assert_array_equal(getattr(state.com, name), getattr(fresh.com, name))
        data = model.createData()
        pin.computeAllTerms(model, data, q, v)
        np.testing.assert_array_equal(state.mass_matrix, data.M.T)
        np.testing.assert_array_equal(state.com.jacobian, data.Jcom)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_coriolis_matrix_gives_the_bias_forces_and_leaves_the_other_terms(model, seed):
    """``C v + g = h`` and ``M_dot = C + C^T`` (finite differences along v); Pinocchio's call rewrites
    the data's A_G, so every term read after it must still be a fresh pass's."""
    q, v = random_state(model, seed)
    state = state_at(model, q, v)
    coriolis = state.coriolis_matrix
    gravity = pin.computeGeneralizedGravity(model, model.createData(), q)
    np.testing.assert_allclose(coriolis @ v + gravity, state.bias_forces, atol=1e-9)
    step = 1e-6
    masses = [state_at(model, pin.integrate(model, q, s * step * v), v).mass_matrix.copy() for s in (-1, 1)]
    np.testing.assert_allclose(coriolis + coriolis.T, (masses[1] - masses[0]) / (2 * step), atol=1e-5)
    fresh = state_at(model, q, v)
    np.testing.assert_array_equal(state.centroidal_momentum_matrix, fresh.centroidal_momentum_matrix)
    np.testing.assert_array_equal(state.centroidal_momentum, fresh.centroidal_momentum)
    np.testing.assert_array_equal(state.centroidal_drift, fresh.centroidal_drift)
    np.testing.assert_array_equal(state.frame(3).drift, fresh.frame(3).drift)
