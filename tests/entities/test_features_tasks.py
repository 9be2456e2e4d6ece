"""Features and tasks: errors on SE(3), their rates by finite differences, the task law."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.features import AngularMomentum, CenterOfMass, FramePose, JointPosture
from dgraph.entities.features.feature import feature_rows
from dgraph.entities.operators import Constant
from dgraph.entities.robot import RobotModel, load_model
from dgraph.entities.tasks import Task
from dgraph.files import check

EPS = 1e-6
ROOT = Path(__file__).resolve().parents[2]


def robot_graph(q, v):
    g = dg.Graph(dt=0.001)
    robot = g.add(RobotModel("robot"))
    robot.q.set(q)
    robot.v.set(v)
    return g, robot


def random_state(seed):
    model = load_model("talos")
    rng = np.random.default_rng(seed)
    q = model.referenceConfigurations["half_sitting"].copy()
    q[:3] += rng.normal(scale=0.1, size=3)
    q[3:7] = pin.Quaternion(pin.exp3(rng.normal(scale=0.3, size=3))).coeffs()
    q[7:] += rng.normal(scale=0.2, size=32)
    return model, q, rng.normal(size=model.nv)


def com_task_graph(seed, **task_params):
    """A robot at a random state, a CenterOfMass (reference 0) and a Task on it."""
    _, q, v = random_state(seed)
    g, robot = robot_graph(q, v)
    g.add(CenterOfMass("com")).reference_position.set(np.zeros(3))
    task = g.add(Task("task", **task_params))
    g.plug("robot.state", "com.robot")
    g.plug("com.feature", "task.feature")
    return g, robot, task


def feature_at(make, q, v, setup=lambda f: None):
    g, _ = robot_graph(q, v)
    feature = g.add(make())
    g.plug("robot.state", f"{feature.name}.robot")
    setup(feature)
    return feature.feature(0)


@pytest.mark.parametrize("mask", ["111111", "000111", "001000", "100110"])
def test_frame_pose_error_rate_and_jacobian_by_finite_differences(mask):
    model, q, v = random_state(0)
    fid = model.getFrameId("arm_left_7_link")
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    placement = data.oMf[fid]

    def setup(f):  # reference = current pose, moving with a constant twist (error rate = J v - ref velocity)
        f.reference_position.set(placement.translation)
        f.reference_orientation.set(pin.Quaternion(placement.rotation).coeffs())
        f.reference_velocity.set(np.array([0.1, 0.0, -0.2, 0.0, 0.3, 0.0]))

    make = lambda: FramePose("hand", frame="arm_left_7_link", mask=mask)  # noqa: E731
    value = feature_at(make, q, v, setup)
    rows = [i for i, c in enumerate(mask) if c == "1"]
    assert value.error == pytest.approx(np.zeros(len(rows)), abs=1e-12)
    error = lambda qq: feature_at(make, qq, v, setup).error  # noqa: E731
    rate = (error(pin.integrate(model, q, EPS * v)) - error(pin.integrate(model, q, -EPS * v))) / (2 * EPS)
    reference_velocity = np.array([0.1, 0.0, -0.2, 0.0, 0.3, 0.0])[rows]
    assert np.allclose(rate, value.error_velocity + reference_velocity, atol=1e-6)
    assert np.allclose(value.jacobian @ v - reference_velocity, value.error_velocity, atol=1e-12)


def test_frame_pose_orientation_error_is_the_world_rotation_vector():
    model, q, v = random_state(1)
    data = model.createData()
    fid = model.getFrameId("base_link")
    pin.framesForwardKinematics(model, data, q)
    rotation = data.oMf[fid].rotation
    offset = np.array([0.1, -0.05, 0.2])  # reference = exp(-offset) R: error = offset
    reference = pin.exp3(-offset) @ rotation
    value = feature_at(lambda: FramePose("w", frame="base_link", mask="000111"), q, v,
                       lambda f: f.reference_orientation.set(pin.Quaternion(reference).coeffs()))
    assert np.allclose(value.error, offset, atol=1e-12)


def test_com_posture_and_momentum_features():
    model, q, v = random_state(2)
    com = pin.centerOfMass(model, model.createData(), q)
    value = feature_at(lambda: CenterOfMass("com", mask="011"), q, v,
                       lambda f: f.reference_position.set(com + np.array([0.0, 0.01, -0.02])))
    assert np.allclose(value.error, [-0.01, 0.02]) and value.jacobian.shape == (2, 38)
    posture = feature_at(lambda: JointPosture("p"), q, v)
    assert np.allclose(posture.error, q[7:] - model.referenceConfigurations["half_sitting"][7:])
    assert np.allclose(posture.jacobian @ v, v[6:]) and np.allclose(posture.error_velocity, v[6:])
    momentum = feature_at(lambda: AngularMomentum("am"), q, v)
    data = model.createData()
    pin.computeCentroidalMomentum(model, data, q, v)
    assert np.allclose(momentum.error, data.hg.angular, atol=1e-10)


def test_posture_on_a_subset_of_joints_and_errors():
    _, q, v = random_state(3)
    value = feature_at(lambda: JointPosture("p", joints=["torso_1_joint", "head_2_joint"]), q, v)
    assert value.jacobian.shape == (2, 38) and value.jacobian[0, 6 + 12] == 1.0
    with pytest.raises(dg.ParamError, match="not a one-dof joint"):
        JointPosture("p", joints=["root_joint"])
    with pytest.raises(dg.ParamError, match="no configuration"):
        JointPosture("p", reference_configuration="standing_on_hands")
    with pytest.raises(dg.ParamError, match="mask"):
        FramePose("f", frame="base_link", mask="0000")


def test_task_equation_is_the_pd_law_minus_the_drift():
    _, q, v = random_state(4)
    g, _ = robot_graph(q, v)
    com = g.add(CenterOfMass("com"))
    com.reference_position.set(np.zeros(3))
    com.reference_velocity.set(np.array([0.1, 0.2, 0.3]))
    com.reference_acceleration.set(np.array([1.0, -1.0, 0.5]))
    task = g.add(Task("task"))
    g.plug("robot.state", "com.robot")
    g.plug("com.feature", "task.feature")
    task.kp.set(np.array([10.0, 20.0, 30.0]))
    task.kd.set(5.0)
    task.weight.set(7.0)
    f = com.feature(0)
    equation = task.equation(0)
    desired = f.reference_acceleration - np.array([10.0, 20.0, 30.0]) * f.error - 5.0 * f.error_velocity
    assert np.allclose(task.desired_acceleration(0), desired)
    assert np.allclose(equation.vector, desired - f.drift) and np.allclose(equation.weight, 7.0)
    a = np.linalg.lstsq(f.jacobian, equation.vector, rcond=None)[0]  # the task met exactly: J a + drift = desired
    assert np.allclose(f.jacobian @ a + f.drift, desired)
    assert equation.cost(a) == pytest.approx(0.0, abs=1e-12)


def test_task_gain_errors_and_critical_damping():
    g, _, task = com_task_graph(5, critical_damping=True)
    assert "kd" not in task.inputs
    task.kp.set(16.0)
    f = g["com"].feature(0)
    assert np.allclose(task.desired_acceleration(0), -16.0 * f.error - 8.0 * f.error_velocity)
    with pytest.raises(dg.SpecError, match=r"task\.kp: expected a scalar or 3 values, one per row of its feature "
                                           r"com\.feature, got 4 values"):
        task.kp.set(np.ones(4))  # refused where it is set: a graph file's set names its line
    with pytest.raises(dg.SpecError, match=r"task\.kp: must be >= 0, got -1\.0"):
        task.kp.set(-1.0)
    with pytest.raises(dg.SpecError, match=r"task\.weight: must be >= 0"):
        task.weight.set(np.array([1.0, -1.0, 1.0]))
    assert task.kp.value == 16.0 and task.weight.value == 1.0
    g.add(Constant("four", value=np.ones(4)), Constant("negative", value=-1.0))
    g.plug("four.output", "task.kp")  # what arrives through a plug is checked at each tick
    with pytest.raises(dg.DGraphError, match=r"task\.kp at tick 0: expected a scalar or 3 values"):
        task.equation(0)
    g.plug("negative.output", "task.kp")
    with pytest.raises(dg.DGraphError, match=r"task\.kp must be >= 0 at tick 0"):
        task.equation(0)


@pytest.mark.parametrize("make", [lambda: CenterOfMass("f", mask="101"), lambda: FramePose("f", frame="base_link",
                                  mask="000111"), lambda: JointPosture("f", joints=["torso_1_joint", "torso_2_joint"]),
                                  lambda: AngularMomentum("f")], ids=["com", "frame", "posture", "momentum"])
def test_a_task_knows_the_rows_of_its_feature_before_any_tick(make):
    _, q, v = random_state(10)
    g, _ = robot_graph(q, v)
    feature, task = g.add(make(), Task("task"))
    g.plug("robot.state", "f.robot")
    if "reference_position" in feature.inputs:
        feature.reference_position.set(np.zeros(3))
    assert feature_rows(task.feature) is None  # nothing plugged yet
    task.kd.set(np.ones(7))  # set before the feature is plugged: reported by the graph's check
    g.plug("f.feature", "task.feature")
    rows = feature_rows(task.feature)
    assert feature.feature.count == 0 and rows == len(feature.feature(0).error)
    task.kp.set(np.arange(rows, dtype=float))
    assert g.problems() == [f"task: input kd: expected a scalar or {rows} values, one per row of its feature "
                            "f.feature, got 7 values"]
    task.kd.set(2.0)
    assert g.problems() == []


def test_gains_follow_a_producer_that_reuses_its_buffer():
    class Schedule(dg.Entity):
        """kp grows with time, written into the same array every tick."""

        def configure(self):
            self.buffer = np.zeros(3)

        @dg.output(shape=(3,), depends=("t",))
        def kp(self, t):
            self.buffer[:] = 4.0 * (t + 1) ** 2
            return self.buffer

    g, _, task = com_task_graph(6, critical_damping=True)
    g.add(Schedule("schedule"))
    g.plug("schedule.kp", "task.kp")
    f = g["com"].feature(0)
    for t in (0, 1, 2):  # kp = 4, 16, 36: Kd = 4, 8, 12
        kp = 4.0 * (t + 1) ** 2
        assert np.allclose(task.desired_acceleration(t), -kp * f.error - 2 * np.sqrt(kp) * f.error_velocity)


def test_a_solver_reads_one_output_per_task_and_the_others_follow_from_it():
    _, _, task = com_task_graph(7)
    task.kp.set(np.array([10.0, 20.0, 30.0]))
    task.kd.set(5.0)
    equation = task.equation(0)
    assert task.proportional_gains.count == task.derivative_gains.count == task.desired_acceleration.count == 0
    kp, kd = task.proportional_gains(0), task.derivative_gains(0)  # only the equation was computed, above
    assert kp is equation.kp and kd is equation.kd and np.array_equal(kd, [5.0] * 3)
    np.testing.assert_array_equal(task.desired_acceleration(0), equation.vector + equation.feature.drift)
    assert task.equation(1) is equation  # nothing it depends on changed
    task.kd.set(6.0)
    assert task.derivative_gains(1)[0] == 6.0 and task.equation(1) is not equation


def test_constant_gains_are_converted_once_and_again_when_set():
    _, robot, task = com_task_graph(8, critical_damping=True)
    task.kp.set(np.array([4.0, 9.0, 16.0]))
    first = task.equation(0)
    robot.v.set(2 * robot.v.value)  # the feature changes, the gains do not
    second = task.equation(1)
    assert second is not first and second.kp is first.kp and second.kd is first.kd and second.weight is first.weight
    np.testing.assert_array_equal(second.kd, [4.0, 6.0, 8.0])
    with pytest.raises(ValueError, match="read-only"):
        second.kp[0] = 0.0  # handed out at every tick: nobody may write into it
    task.kp.set(np.array([4.0, 9.0, 16.0]))  # a new constant of the same value: same vectors
    assert task.equation(2).kp is first.kp
    task.kp.set(25.0)
    third = task.equation(3)
    np.testing.assert_array_equal(third.kp, [25.0] * 3)
    np.testing.assert_array_equal(third.kd, [10.0] * 3)


def test_a_contiguous_mask_selects_views_and_the_reference_orientation_follows_its_input():
    model, q, v = random_state(9)
    g, robot = robot_graph(q, v)
    waist = g.add(FramePose("waist", frame="base_link", mask="000111"))
    g.plug("robot.state", "waist.robot")
    value = waist.feature(0)
    world = robot.state(0).frame(model.getFrameId("base_link"))
    assert np.shares_memory(value.jacobian, world.jacobian) and np.array_equal(value.jacobian, world.jacobian[3:])
    np.testing.assert_allclose(value.error, pin.log3(world.rotation), atol=1e-12)  # R* = identity (the default)
    turn = np.array([0.0, 0.0, 0.3])
    waist.reference_orientation.set(pin.Quaternion(pin.exp3(turn)).coeffs())
    np.testing.assert_allclose(waist.feature(0).error, pin.log3(world.rotation @ pin.exp3(turn).T), atol=1e-12)

    class Turning(dg.Entity):
        """A reference orientation turning about z, written into the same array every tick."""

        def configure(self):
            self.buffer = np.zeros(4)

        @dg.output(shape=(4,), depends=("t",))
        def quaternion(self, t):
            self.buffer[:] = pin.Quaternion(pin.exp3(np.array([0.0, 0.0, 0.1 * t]))).coeffs()
            return self.buffer

    g.add(Turning("turning"))
    g.plug("turning.quaternion", "waist.reference_orientation")
    for t in (1, 2):
        expected = pin.log3(world.rotation @ pin.exp3(np.array([0.0, 0.0, 0.1 * t])).T)
        np.testing.assert_allclose(waist.feature(t).error, expected, atol=1e-12)
    posture = g.add(JointPosture("posture"))
    g.plug("robot.state", "posture.robot")
    assert np.shares_memory(posture.feature(0).jacobian, posture.feature(3).jacobian)  # one constant selection
    with pytest.raises(ValueError, match="read-only"):
        posture.feature(3).drift[0] = 1.0


@pytest.mark.parametrize("setting, message", [
    ("posture_task.kp: [1, 2, 3]", "posture_task.kp: expected a scalar or 32 values, one per row of its feature "
                                   "posture.feature, got 3 values"),
    ("com_task.weight: -1.0", "com_task.weight: must be >= 0, got -1.0")])
def test_a_graph_file_setting_a_gain_that_does_not_fit_is_refused_at_its_line(setting, message, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(f"extends: {ROOT / 'graphs' / 'talos_standing.yaml'}\nname: bad\nset:\n  {setting}\n")
    with pytest.raises(dg.GraphFileError) as caught:
        check(path)  # what `dgraph check` runs: it no longer says OK to what `run` refuses at tick 0
    assert str(caught.value) == f"{path}:4 [set.{setting.split(':')[0]}]: {message}"


def test_a_zero_reference_quaternion_is_refused_where_it_is_set():
    waist = FramePose("waist", frame="base_link", mask="000111")
    waist.reference_orientation.set([0.0, 0.0, 0.0, 2.0])  # normalised when used
    with pytest.raises(dg.SpecError, match=r"waist\.reference_orientation: expected a unit quaternion \[x, y, z, w\]"):
        waist.reference_orientation.set(np.zeros(4))


def test_a_robot_graph_of_constants_passes_the_dependency_checks_tick_after_tick():
    """In the dependency-check mode the held robot state is computed again at every tick and
    compared (it declares no time): the cached state stays readable for what is first read later
    (its Pinocchio data's latest pass is the same (q, v)), and nothing is reported."""
    _, q, v = random_state(11)
    g, robot = robot_graph(q, v)
    com, waist, task = g.add(CenterOfMass("com"), FramePose("waist", frame="base_link"), Task("task"))
    com.reference_position.set(np.zeros(3))
    for feature in ("com", "waist"):
        g.plug("robot.state", f"{feature}.robot")
    g.plug("com.feature", "task.feature")
    g.check_dependencies = True
    equation = task.equation(0)
    for t in range(1, 4):
        assert task.equation(t) is equation and robot.state.count == 1
    assert waist.feature(4).error.shape == (6,) and robot.state.time == 0  # a frame first read at tick 4
