"""FloatingBaseEstimator against synthetic TALOS sensor data (no simulator needed)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from synthetic_talos import DT, SENSORS, Lift, Playback, Trajectory, generate

import dgraph as dg
from dgraph.entities.estimators import FloatingBaseEstimator
from dgraph.entities.estimators.leg_odometry import RelativeKinematics, _rows, complementary_alpha
from dgraph.entities.robot.rotations import quat_to_matrix

SETTLED = 1000  # ticks: 1 s, about 6 time constants of the 1 Hz complementary filter


@pytest.fixture(scope="module")
def sway() -> Trajectory:
    return generate(2.5)


@pytest.fixture(scope="module")
def lift() -> Trajectory:
    return generate(2.5, lift=Lift())


def run(traj: Trajectory, cache: bool = True, check_dependencies: bool = False, ticks: int | None = None,
        **params: object) -> dict[str, np.ndarray]:
    """Play ``traj`` into an estimator; the estimator outputs at every tick."""
    g = dg.Graph(dt=DT)
    dev = g.add(Playback("sim", trajectory=traj))
    est = g.add(FloatingBaseEstimator("est", q0=traj.q[0], **params))
    for name in SENSORS:
        g.plug(dev.signal(name), est.signal(name))
    g.cache_enabled = cache
    g.check_dependencies = check_dependencies
    rows: dict[str, list] = {k: [] for k in ("q", "v", "contact_left", "contact_right", "base_velocity_world")}
    n = len(traj) if ticks is None else ticks
    for i in range(n):
        for name, row in rows.items():
            row.append(est.signal(name)(g.t))
        if i < n - 1:
            g.step()
    out = {k: np.array(v) for k, v in rows.items()}
    out["anchor_right"] = est.anchor_right.value
    return out


def rotation_error(q_est: np.ndarray, q_true: np.ndarray) -> np.ndarray:
    """Angle (rad) between the estimated and true base orientations, per tick."""
    return np.array([np.linalg.norm(pin.log3(quat_to_matrix(a).T @ quat_to_matrix(b)))
                     for a, b in zip(q_est[:, 3:7], q_true[:, 3:7], strict=True)])


def test_swaying_estimate_matches_the_true_base(sway):
    est = run(sway)
    assert np.abs(est["q"][:, :3] - sway.q[:, :3]).max() < 1e-5          # m (brief: < 1 mm)
    assert rotation_error(est["q"], sway.q).max() < 1e-9                  # rad
    assert np.array_equal(est["q"][:, 7:], sway.q[:, 7:]) and np.array_equal(est["v"][:, 6:], sway.v[:, 6:])
    assert np.abs(est["v"][:, 3:6] - sway.v[:, 3:6]).max() < 1e-9         # rad/s, gyro + torso motion
    assert np.abs(est["v"][:, :3] - sway.v[:, :3]).max() < 1e-3         # m/s (brief: < 1 cm/s)
    # the sway is not trivial: the base moves by centimetres at several cm/s
    assert np.ptp(sway.q[:, :3], axis=0).min() > 0.015 and np.abs(sway.v[:, :3]).max() > 0.05
    # the world-frame output is the rotated base-frame velocity
    r = np.array([quat_to_matrix(q) for q in est["q"][:, 3:7]])
    assert np.allclose(np.einsum("nij,nj->ni", r, est["v"][:, :3]), est["base_velocity_world"], atol=1e-12)
    assert est["contact_left"].all() and est["contact_right"].all()


def test_filter_starts_from_the_kinematics_at_the_first_contact(sway):
    est = run(sway, ticks=300)
    err = np.linalg.norm(est["v"][:, :3] - sway.v[:300, :3], axis=1)
    assert np.linalg.norm(sway.v[0, :3]) > 0.05 and err.max() < 1e-3


def test_lifted_foot_is_ignored_and_reanchored_where_it_lands(lift):
    est = run(lift)
    assert np.abs(est["q"][:, :3] - lift.q[:, :3]).max() < 1e-5
    assert np.abs(est["v"][SETTLED:, :3] - lift.v[SETTLED:, :3]).max() < 1e-3
    assert est["contact_left"].all()
    swing = slice(round(1.2 / DT), round(1.8 / DT) + 1)
    assert not est["contact_right"][swing].any() and est["contact_right"][-1]
    model = FloatingBaseEstimator("probe").pin_model
    data = model.createData()
    soles = []
    for q in (lift.q[0], lift.q[-1]):
        pin.framesForwardKinematics(model, data, q)
        soles.append(data.oMf[model.getFrameId("right_sole_link")].translation.copy())
    assert np.allclose(est["anchor_right"], soles[1], atol=1e-9)
    assert np.allclose(soles[1] - soles[0], [Lift().forward, 0.0, 0.0], atol=1e-9)  # it stepped forward


def test_a_swinging_foot_believed_in_contact_would_corrupt_the_estimate(lift):
    """The previous test can fail: fake a loaded right foot during its swing."""
    sensors = dict(lift.sensors)
    sensors["ft_right_ankle"] = lift.sensors["ft_left_ankle"].copy()
    est = run(Trajectory(lift.q, lift.v, sensors, lift.normal_force))
    assert np.abs(est["q"][:, :3] - lift.q[:, :3]).max() > 0.01


def test_contact_switches_with_hysteresis_on_the_normal_force(lift):
    est = run(lift, contact_force_on=100.0, contact_force_off=50.0)
    expected, contact = [], False
    for f in lift.normal_force[:, 1]:
        contact = f > 100.0 or (contact and f > 50.0)
        expected.append(contact)
    assert np.array_equal(est["contact_right"], expected)
    switches = np.flatnonzero(np.diff(est["contact_right"].astype(int)))
    assert len(switches) == 2
    off, on = switches + 1
    assert lift.normal_force[off, 1] <= 50.0 < lift.normal_force[off - 1, 1]
    assert lift.normal_force[on - 1, 1] <= 100.0 < lift.normal_force[on, 1]


def test_hysteresis_with_constant_inputs(sway):
    g = dg.Graph(dt=DT)
    est = g.add(FloatingBaseEstimator("est", contact_force_on=100.0, contact_force_off=50.0))
    for name in SENSORS:
        est.signal(name).set(sway.sensors[name][0])
    seen = []
    for f in [0, 80, 120, 80, 60, 40, 60, 120, 10, 101]:
        est.ft_left_ankle.set([0, 0, f, 0, 0, 0])  # the soles are flat at tick 0: sensor z is vertical
        seen.append(est.contact_left(g.t))
        g.step()
    assert seen == [False, False, True, True, True, False, False, True, False, True]


def test_caching_off_and_dependency_checks_give_identical_outputs(lift):
    ticks = 2200  # through the lift-off and the touch-down
    on = run(lift, ticks=ticks)
    off = run(lift, cache=False, ticks=ticks)
    checked = run(lift, check_dependencies=True, ticks=ticks)
    for key in ("q", "v", "contact_left", "contact_right", "base_velocity_world"):
        assert np.array_equal(on[key], off[key]), key
        assert np.array_equal(on[key], checked[key]), key


def test_complementary_filter_rejects_encoder_velocity_noise(sway):
    rng = np.random.default_rng(3)
    sensors = dict(sway.sensors)
    sensors["encoder_velocity"] = sway.sensors["encoder_velocity"] + rng.normal(0.0, 0.05, sway.v[:, 6:].shape)
    noisy = Trajectory(sway.q, sway.v, sensors, sway.normal_force)
    fused = run(noisy)
    kinematic = run(noisy, cutoff_frequency=float("inf"))

    def rms(est):
        return np.sqrt(np.mean((est["v"][SETTLED:, :3] - sway.v[SETTLED:, :3]) ** 2))

    assert rms(kinematic) > 0.005          # the noise matters for leg odometry alone
    assert rms(fused) < 0.2 * rms(kinematic)
    assert rms(fused) < 0.003


def test_without_contact_the_base_falls_freely_by_dead_reckoning(sway):
    g = dg.Graph(dt=DT)
    q0 = sway.q[0]
    est = g.add(FloatingBaseEstimator("est", q0=q0))
    for name in SENSORS:
        est.signal(name).set(sway.sensors[name][0])
    est.encoder_velocity.set(np.zeros(32))
    est.imu_angular_velocity.set(np.zeros(3))
    est.imu_linear_acceleration.set(np.zeros(3))  # free fall: no proper acceleration
    est.ft_left_ankle.set(np.zeros(6))
    est.ft_right_ankle.set(np.zeros(6))
    n = 50
    g.run(ticks=n)
    assert not est.contact_left(n) and not est.contact_right(n)
    assert np.allclose(est.base_velocity_world(n), [0.0, 0.0, -9.81 * n * DT])
    assert np.allclose(est.q(n)[:3], q0[:3] - [0.0, 0.0, 9.81 * DT**2 * n * (n - 1) / 2])


@pytest.mark.parametrize(("params", "match"), [
    ({"foot_frames": ["left_soul_link", "right_sole_link"]}, "foot_frames.*no frame 'left_soul_link'.*left_sole_link"),
    ({"imu_frame": "imu"}, "imu_frame.*no frame 'imu'"),
    ({"ft_frames": ["leg_left_6_joint"]}, "two frames"),
    ({"contact_force_on": 40.0, "contact_force_off": 50.0}, "must not exceed"),
    ({"q0": [0.0, 0.0, 1.0]}, r"q0 has shape \(3,\), expected \(39,\)"),
    ({"model": 3}, "robot name or a pinocchio.Model"),
])
def test_bad_parameters_raise_a_param_error_naming_the_entity(params, match):
    with pytest.raises(dg.ParamError, match=match) as info:
        FloatingBaseEstimator("my_estimator", **params)
    assert info.value.entity == "my_estimator" and "my_estimator" in str(info.value)


def test_model_without_free_flyer_is_refused():
    model = pin.buildSampleModelManipulator()
    with pytest.raises(dg.ParamError, match="free flyer"):
        FloatingBaseEstimator("est", model=model)


def test_defaults_and_registry():
    est = FloatingBaseEstimator("est")
    assert est.imu_frame_name == "imu_link"
    assert est.encoder_position.spec.shape == (32,) and est.q.spec.shape == (39,) and est.v.spec.shape == (38,)
    sole_z = est.prediction(0)[5]
    assert 1.0 < sole_z < 1.05  # half-sitting base height with the soles on the floor
    assert dg.get_type("FloatingBaseEstimator") is FloatingBaseEstimator
    assert complementary_alpha(float("inf"), DT) == 0.0
    assert complementary_alpha(1.0, DT) == pytest.approx(1 / (1 + 2 * np.pi * DT))


@pytest.mark.parametrize("frames", [
    ["left_sole_link", "right_sole_link", "imu_link", "leg_left_6_joint", "leg_right_6_joint"],  # the estimator's
    ["left_sole_link", "rgbd_rgb_optical_frame", "gripper_right_fingertip_1_link"],  # offset on every axis; the
    # joints kept are not consecutive in q (gathered)
])
def test_relative_kinematics_is_the_full_models_pass_with_the_base_at_rest(frames, rng):
    model = FloatingBaseEstimator("probe").pin_model
    data = model.createData()
    kin = RelativeKinematics(model, frames)
    kept = {j for f in frames for j in model.supports[model.frames[model.getFrameId(f)].parentJoint]}
    assert kin.model.njoints == len(kept) + len(frames) < model.njoints  # joints moving none of the frames locked
    for _ in range(20):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        q[:7] = [0, 0, 0, 0, 0, 0, 1]
        v = rng.normal(size=model.nv)
        v[:6] = 0.0
        placements, motions = kin.forward(q[7:], v[6:])
        pin.forwardKinematics(model, data, q, v)
        for name, placement, motion in zip(frames, placements, motions, strict=True):
            frame = model.getFrameId(name)
            expected = pin.updateFramePlacement(model, data, frame)
            local = pin.getFrameVelocity(model, data, frame, pin.LOCAL)
            rotation = np.array(placement[:9]).reshape(3, 3).T  # stored column by column
            np.testing.assert_allclose(rotation, expected.rotation, rtol=0, atol=1e-14)
            np.testing.assert_allclose(placement[9:], expected.translation, rtol=0, atol=1e-14)
            np.testing.assert_allclose(motion, local.vector, rtol=0, atol=1e-12)
            # (K): the velocities relative to the base, in B
            aligned = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(rotation @ motion[:3], aligned.linear, rtol=0, atol=1e-12)
            np.testing.assert_allclose(rotation @ motion[3:], aligned.angular, rtol=0, atol=1e-12)
    assert np.abs(v[6:]).max() > 1.0 and np.abs(aligned.linear).max() > 0.1  # not trivially at rest


def test_relative_kinematics_leaves_the_given_model_alone():
    model = FloatingBaseEstimator("probe").pin_model
    frames = [model.names[j] for j in range(2, model.njoints)]  # every joint's frame: nothing is locked
    njoints = model.njoints
    kin = RelativeKinematics(model, frames)
    assert model.njoints == njoints and kin.model.njoints == 2 * njoints - 2


def test_rows_view_consecutive_elements_and_refuse_any_other_layout():
    memory = np.arange(24.0)  # two SE3-like elements: a 3x3 stored column by column, then a 3-vector
    elements = [(memory[12 * i:12 * i + 9].reshape(3, 3, order="F"), memory[12 * i + 9:12 * i + 12]) for i in (0, 1)]
    rows = _rows(elements)
    assert rows.tolist() == memory.reshape(2, 12).tolist() and not rows.flags.writeable
    memory[13] = -1.0  # a view: it follows the memory
    assert rows[1, 1] == -1.0
    with pytest.raises(RuntimeError, match="memory layout"):  # separate allocations
        _rows([(np.zeros((3, 3)), np.zeros(3)), (np.zeros((3, 3)), np.zeros(3))])
    with pytest.raises(RuntimeError, match="memory layout"):  # row by row is not Eigen's order
        _rows([(memory[:9].reshape(3, 3), memory[9:12])])
    with pytest.raises(RuntimeError, match="float64"):
        _rows([(np.zeros(3, dtype=np.float32),)])


def test_graph_file_builds_and_saves_the_estimator(tmp_path, sway):
    path = tmp_path / "estimator.yaml"
    path.write_text(
        "name: estimator\ndt: 0.001\nentities:\n"
        "  est: {type: FloatingBaseEstimator, params: {model: talos, cutoff_frequency: 2.0,\n"
        "        foot_frames: [left_sole_link, right_sole_link], contact_force_on: 120.0}}\n"
        "  truth: {type: GroundTruthEstimator}\n")
    g = dg.load(str(path))
    est = g["est"]
    assert est.cutoff_frequency == 2.0 and est.contact_force_on == 120.0
    dg.save(g, str(tmp_path / "again.yaml"))
    assert dg.load(str(tmp_path / "again.yaml"))["est"].params == est.params
