"""MujocoDevice: TALOS standing and falling, sensors, wrenches, divergence, resume, rendering."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph_sim.device import MujocoDevice

G = 9.81


def standing_graph(**params):
    """Position mode at half-sitting with the gravity torque g(q0) as feed-forward (kp 3000, kd 60,
    grippers 100 and 1)."""
    g = dg.Graph(dt=0.001, name="standing")
    dev = g.add(MujocoDevice("sim", control_mode="position", **params))
    model = dev.sim.pin_model
    q0 = dev.q.value.copy()
    dev.control.set(q0[7:])
    dev.feedforward_torque.set(pin.rnea(model, model.createData(), q0, np.zeros(model.nv), np.zeros(model.nv))[6:])
    return g, dev


@pytest.fixture(scope="module")
def stood():
    """Two seconds of standing, with the base position of every tick."""
    g, dev = standing_graph()
    base = []
    dev.after.add(lambda t: base.append(dev.q.value[:3]))
    g.run(duration=2.0)
    return g, dev, np.array(base)


def mass(dev, body):
    m = dev.mj_model
    return float(m.body_subtreemass[m.body(body).id])


def site_rotation(dev, site):
    return dev.data.site_xmat[dev.mj_model.site(site).id].reshape(3, 3)


def test_position_mode_with_gravity_feedforward_stands_two_seconds(stood):
    g, dev, base = stood
    q0 = dev.sim.q0
    assert g.t == 2000 and len(base) == 2000
    assert np.abs(base[:, 2] - q0[2]).max() < 0.01
    assert np.abs(base[:, :2] - q0[:2]).max() < 0.03  # a slow sway over the compliant ankles
    assert not dev.fallen.value and dev.sim_time.value == pytest.approx(2.0)
    assert np.abs(dev.encoder_velocity.value).max() < 0.1  # no chattering joint (grippers: low gains)
    assert np.abs(dev.encoder_position.value - q0[7:]).max() < 0.03  # PD error under load (knees)


def test_imu_matches_the_pinocchio_imu_frame(stood):
    _, dev, _ = stood
    model = dev.sim.pin_model
    data = model.createData()
    q, v = dev.q.value, dev.v.value
    pin.forwardKinematics(model, data, q, v)
    frame = model.getFrameId("imu_link")
    pin.updateFramePlacements(model, data)
    x, y, z, w = dev.imu_orientation.value
    np.testing.assert_allclose(pin.Quaternion(w, x, y, z).toRotationMatrix(), data.oMf[frame].rotation, atol=1e-9)
    omega = pin.getFrameVelocity(model, data, frame, pin.LOCAL).angular
    np.testing.assert_allclose(dev.imu_angular_velocity.value, omega, atol=1e-9)
    # standing still, the accelerometer reads +g along the world's up axis, in the IMU frame
    up = data.oMf[frame].rotation.T @ np.array([0.0, 0.0, G])
    np.testing.assert_allclose(dev.imu_linear_acceleration.value, up, atol=1.0)  # sway: < 1 m/s²
    np.testing.assert_array_equal(dev.encoder_position.value, q[7:])
    np.testing.assert_array_equal(dev.encoder_velocity.value, v[6:])


def test_force_torque_sensors_carry_the_weight(stood):
    _, dev, _ = stood
    total = mass(dev, "base_link")
    feet = mass(dev, "leg_left_6_link") + mass(dev, "leg_right_6_link")
    ankles = [site_rotation(dev, f"ft_{side}_ankle") @ getattr(dev, f"ft_{side}_ankle").value[:3]
              for side in ("left", "right")]
    assert sum(f[2] for f in ankles) == pytest.approx((total - feet) * G, rel=0.02)
    for side, force in zip(("left", "right"), ankles, strict=True):
        assert force[2] > 0.35 * total * G, side  # each foot carries about half, pushing the leg up
        assert getattr(dev, f"ft_{side}_ankle").value[2] > 0.35 * total * G  # sensor z is about up
    contact = dev.contact_force_total.value
    assert contact[2] == pytest.approx(total * G, rel=0.02)
    assert np.abs(contact[:2]).max() < 0.05 * total * G
    for side in ("left", "right"):  # a hanging hand pulls the arm down with its weight
        hand = site_rotation(dev, f"ft_{side}_wrist") @ getattr(dev, f"ft_{side}_wrist").value[:3]
        weight = mass(dev, f"wrist_{side}_ft_link") * G
        assert hand[2] == pytest.approx(-weight, rel=0.05) and np.abs(hand[:2]).max() < 0.1 * weight


def test_joint_torque_is_the_clipped_pd_law(stood):
    g, dev, _ = stood
    t = g.t
    q_j, v_j = dev.encoder_position(t), dev.encoder_velocity(t)
    kp, kd = np.full(32, 3000.0), np.full(32, 60.0)
    kp[[21, 29]], kd[[21, 29]] = 100.0, 1.0  # grippers
    expected = dev.feedforward_torque(t) + kp * (dev.control(t) - q_j) - kd * v_j
    g.step()
    limits = dev.mj_model.actuator_ctrlrange[dev.joint_map.actuated_index, 1]
    np.testing.assert_allclose(dev.joint_torque.value, np.clip(expected, -limits, limits), atol=1e-9)


def test_torque_mode_clips_to_the_effort_limits():
    g = dg.Graph(dt=0.001)
    dev = g.add(MujocoDevice("sim"))
    limits = dev.sim.pin_model.effortLimit[6:]
    dev.control.set(np.full(32, 1e4))
    g.step()
    np.testing.assert_array_equal(dev.joint_torque.value, limits)
    assert limits[3] == 300.0  # leg_left_4 (knee), as in the URDF
    dev.control.set(np.full(32, -1e4))
    g.step()
    np.testing.assert_array_equal(dev.joint_torque.value, -limits)


def test_zero_torque_falls_and_stop_on_fall_names_the_tick():
    g = dg.Graph(dt=0.001)
    dev = g.add(MujocoDevice("sim"))
    dev.control.set(np.zeros(32))
    fell_at = []
    dev.after.add(lambda t: fell_at.append(t) if dev.fallen.value and not fell_at else None)
    g.run(duration=1.5)
    assert dev.fallen.value and 100 < fell_at[0] < 1000
    assert 0.0 < dev.q.value[2] < 0.4  # lying on the floor (all collision meshes touch it)

    g2 = dg.Graph(dt=0.001)
    dev2 = g2.add(MujocoDevice("sim", stop_on_fall=True))
    dev2.control.set(np.zeros(32))
    with pytest.raises(dg.DGraphError, match=rf"sim: the robot fell during tick {fell_at[0] - 1} ") as err:
        g2.run(duration=1.5)
    assert err.value.entity == "sim" and g2.t == fell_at[0] - 1 and not dev2.fallen.value
    with pytest.raises(dg.DGraphError, match=rf"tick {fell_at[0] - 1} "):  # resuming replays the same step
        g2.step()


def test_an_external_wrench_pushes_the_base():
    pushed_graph, pushed = standing_graph(wrench_bodies=["base_link"])
    still_graph, still = standing_graph()
    push = np.array([60.0, 0.0, 0.0])
    pushed.wrench_base_link.set([*push, 0.0, 0.0, 0.0])
    contact = []
    pushed.after.add(lambda t: contact.append(pushed.contact_force_total.value))
    pushed_graph.run(duration=0.5)
    still_graph.run(duration=0.5)
    assert pushed.q.value[0] - still.q.value[0] > 0.01
    # Newton for the whole robot over the run: sum of dt (contact + push + weight) = m v_com
    # (contact_force_total excludes the applied wrench; it starts at rest)
    model = pushed.sim.pin_model
    data = model.createData()
    pin.centerOfMass(model, data, pushed.q.value, pushed.v.value)
    mass = pin.computeTotalMass(model)
    impulse = 0.001 * (np.sum(contact, axis=0) + 500 * (push + np.array([0.0, 0.0, -mass * G])))
    np.testing.assert_allclose(impulse, mass * data.vcom[0], atol=1e-4)  # N s (measured 1e-6), vs 30 N s pushed
    assert np.mean(contact, axis=0)[0] < -40.0  # the floor holds the robot back


def test_divergence_raises_and_keeps_the_state():
    g = dg.Graph(dt=0.001)
    dev = g.add(MujocoDevice("sim", wrench_bodies=["base_link", "arm_left_7_link"]))
    assert "wrench_arm_left_7_link" in dev.inputs
    dev.control.set(np.zeros(32))
    g.run(ticks=5)
    q = dev.q.value.copy()
    dev.wrench_base_link.set([1e12, 0.0, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(dg.DGraphError, match=r"sim: MuJoCo simulation diverged at tick 5: BADQACC") as err:
        g.step()
    assert err.value.entity == "sim" and g.t == 5
    np.testing.assert_array_equal(dev.q.value, q)
    dev.wrench_base_link.set(np.zeros(6))  # the failed step is undone: the run goes on
    g.step()
    assert np.isfinite(dev.q.value).all() and abs(dev.q.value[2] - q[2]) < 1e-3
    dev.wrench_arm_left_7_link.set([np.inf, 0.0, 0.0, 0.0, 0.0, 0.0])  # a disturbance, not a command: raises
    with pytest.raises(dg.DGraphError, match="sim: non-finite wrench_arm_left_7_link at tick 6"):
        g.step()
    assert g.t == 6 and dev.control_fault.value == 0


def test_a_diverged_state_is_named_by_mujocos_own_checks_even_without_its_reset():
    """The device's check reads MuJoCo's bad qpos/qvel/qacc warnings (``mj_step1`` starts by checking
    the new qpos and qvel); with MuJoCo's reset off, the state stays diverged and is named too."""
    g = dg.Graph(dt=0.001)
    dev = g.add(MujocoDevice("sim", wrench_bodies=["base_link"]))
    dev.control.set(np.zeros(32))
    dev.mj_model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
    g.run(ticks=3)
    dev.wrench_base_link.set([1e300, 0.0, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(dg.DGraphError, match=r"diverged at tick 3: BADQPOS .*BADQACC .*non-finite qpos/qvel"):
        g.step()
    assert g.t == 3


def test_a_failed_tick_with_another_wrench_resumes_as_if_it_never_ran():
    """The state saved before a step leaves out the applied forces: the resumed tick rewrites the
    wrench of the failed one."""
    runs = []
    for fail in (False, True):
        g, dev = standing_graph(wrench_bodies=["base_link", "arm_left_7_link"])
        dev.wrench_base_link.set([0.0, 40.0, 0.0, 0.0, 0.0, 5.0])
        g.run(ticks=100)
        if fail:
            g.add(FailOnce("fail", at=100))
            dev.wrench_arm_left_7_link.set([0.0, 0.0, 300.0, 0.0, 0.0, 0.0])
            with pytest.raises(RuntimeError, match="boom"):
                g.step()
        dev.wrench_arm_left_7_link.set(np.zeros(6))
        g.run(ticks=100)
        runs.append({name: np.array(s.value) for name, s in dev.outputs.items()})
    for name, value in runs[0].items():
        np.testing.assert_array_equal(runs[1][name], value, err_msg=name)


class Commands(dg.Entity):
    """A test source: row ``t`` of ``rows`` (NaN allowed: the graph's value checks are off), or
    with ``reuse`` that row copied into one buffer handed out at every tick."""

    rows = dg.Param(kind="object")
    reuse = dg.Param(False, kind="bool")

    def configure(self):
        self._buffer = np.zeros(32)

    @dg.output(shape=(32,), depends=("t",))
    def value(self, t):
        row = self.rows[min(t, len(self.rows) - 1)]
        if self.reuse:
            self._buffer[:] = row
            return self._buffer
        return row


def play(rows, mode="torque", port="control", ticks=None, fail_at=None, reuse=False, **inputs):
    """Run a device fed ``rows`` on ``port`` (other inputs constant); per tick: q, v, ctrl, control_fault."""
    g = dg.Graph(dt=0.001)
    g.check_values = False  # let NaN through to the device, as an unchecked upstream entity would
    dev = g.add(MujocoDevice("sim", control_mode=mode))
    g.add(Commands("commands", rows=np.asarray(rows, dtype=float), reuse=reuse))
    g.plug("commands.value", f"sim.{port}")
    for name, value in inputs.items():
        dev.signal(name).set(value)
    if fail_at is not None:
        g.add(FailOnce("fail", at=fail_at))
    seen = {"q": [], "v": [], "ctrl": [], "qpos": [], "fault": []}

    def record(t):
        for key, value in (("q", dev.q.value), ("v", dev.v.value), ("ctrl", dev.data.ctrl.copy()),
                           ("qpos", dev.data.qpos.copy()), ("fault", dev.control_fault.value)):
            seen[key].append(value)

    dev.after.add(record)
    ticks = len(rows) if ticks is None else ticks
    if fail_at is not None:
        with pytest.raises(RuntimeError, match="boom"):
            g.run(ticks=ticks)
        assert g.t == fail_at and dev.control_fault.time <= fail_at
    g.run(ticks=ticks - g.t)
    return {key: np.array(value) for key, value in seen.items()}


def test_a_non_finite_torque_is_replaced_by_the_last_valid_one_and_counted():
    rng = np.random.default_rng(1)
    valid = rng.normal(0.0, 20.0, (40, 32))
    rows = valid.copy()
    rows[10] = np.nan                          # one bad tick
    rows[20:23] = np.inf                       # three in a row
    rows[30, 5] = np.nan                       # a single bad joint is a bad command
    held = valid.copy()
    held[10], held[20:23], held[30] = valid[9], valid[19], valid[29]
    faulty, reference = play(rows), play(held)
    expected = np.zeros(40, dtype=int)
    expected[[10, 20, 21, 22, 30]] = [1, 1, 2, 3, 1]  # stamped t + 1: row k is the state after tick k
    assert faulty["fault"].tolist() == expected.tolist()
    np.testing.assert_array_equal(faulty["q"], reference["q"])  # exactly the held command was applied
    np.testing.assert_array_equal(faulty["v"], reference["v"])
    assert np.isfinite(faulty["ctrl"]).all() and np.isfinite(faulty["qpos"]).all()  # MuJoCo never saw one


def test_without_any_valid_torque_yet_the_fallback_is_zero():
    rows = np.zeros((30, 32))
    rows[:5] = np.nan
    rows[5:] = 30.0
    faulty, reference = play(rows), play(np.where(np.isnan(rows), 0.0, rows))
    assert faulty["fault"][:6].tolist() == [1, 2, 3, 4, 5, 0]
    np.testing.assert_array_equal(faulty["q"], reference["q"])


def test_the_command_held_is_a_copy_when_its_producer_reuses_its_buffer():
    rows = np.random.default_rng(2).normal(0.0, 20.0, (20, 32))
    rows[8:12] = np.nan  # written into the buffer that held the last valid command
    fresh, reused = play(rows), play(rows, reuse=True)
    assert reused["fault"].tolist() == fresh["fault"].tolist() == [0] * 8 + [1, 2, 3, 4] + [0] * 8
    np.testing.assert_array_equal(reused["q"], fresh["q"])
    assert np.isfinite(reused["ctrl"]).all()


def test_position_mode_holds_the_last_valid_target_velocity_and_feedforward():
    _, dev = standing_graph()
    q_j, gravity = dev.q.value[7:].copy(), dev.feedforward_torque.value.copy()
    targets = q_j + 0.02 * np.sin(np.arange(30)[:, None] * 0.3 + np.arange(32))
    feedforward = np.tile(gravity, (30, 1)) + np.arange(30)[:, None]  # changes every tick
    feedforward[12] = np.nan                   # the target is fine, the torque is not: the triple is held
    feedforward_held = feedforward.copy()
    feedforward_held[12] = feedforward[11]
    faulty = play(feedforward, mode="position", port="feedforward_torque", control=targets[0])
    reference = play(feedforward_held, mode="position", port="feedforward_torque", control=targets[0])
    assert faulty["fault"].tolist() == [0] * 12 + [1] + [0] * 17
    np.testing.assert_array_equal(faulty["q"], reference["q"])  # the PD of tick 12 is on the state at 12
    # a bad target: the last valid (target, velocity reference, feed-forward), the PD on the current state
    rows = targets.copy()
    rows[12:15] = np.inf
    held = targets.copy()
    held[12:15] = targets[11]
    faulty = play(rows, mode="position", feedforward_torque=gravity)
    reference = play(held, mode="position", feedforward_torque=gravity)
    assert faulty["fault"][11:16].tolist() == [0, 1, 2, 3, 0]
    np.testing.assert_array_equal(faulty["q"], reference["q"])
    assert np.isfinite(faulty["ctrl"]).all() and np.isfinite(faulty["qpos"]).all()


def test_position_mode_without_any_valid_target_holds_the_joints_where_they_were():
    q_j = MujocoDevice("probe", control_mode="position").q.value[7:]
    rows = np.full((20, 32), np.nan)
    faulty = play(rows, mode="position", feedforward_torque=np.zeros(32))
    reference = play(np.tile(q_j, (20, 1)), mode="position", feedforward_torque=np.zeros(32))
    assert faulty["fault"].tolist() == list(range(1, 21))
    np.testing.assert_array_equal(faulty["q"], reference["q"])  # target q_j(0) latched, no feed-forward


def test_the_command_held_is_the_last_one_applied_not_one_of_a_failed_tick():
    runs = []
    for fail in (False, True):
        g = dg.Graph(dt=0.001)
        dev = g.add(MujocoDevice("sim"))
        dev.control.set(np.full(32, 10.0))
        g.run(ticks=10)
        if fail:
            g.add(FailOnce("fail", at=10))
            dev.control.set(np.full(32, -40.0))  # valid, but its step is undone by the failure
            with pytest.raises(RuntimeError, match="boom"):
                g.step()
        dev.control.set(np.full(32, np.inf))
        g.step()
        assert dev.control_fault.value == 1
        runs.append(dev.q.value)
    np.testing.assert_array_equal(runs[1], runs[0])  # both held 10 N m, the torque applied at tick 9


def test_a_failed_tick_during_a_fault_resumes_identically():
    rows = np.full((40, 32), 10.0)
    rows[15:25] = np.nan
    straight, resumed = play(rows), play(rows, fail_at=20)  # the observer fails at tick 20, mid-fault
    assert straight["fault"][19:26].tolist() == [5, 6, 7, 8, 9, 10, 0]
    for key in ("q", "v", "fault"):
        np.testing.assert_array_equal(resumed[key], straight[key], err_msg=key)


class FailOnce(dg.Entity):
    """An observer failing once at a given tick (after the device stepped MuJoCo)."""

    observes = True
    at = dg.Param(0, kind="int")

    def setup(self):
        self.failed = False

    def observe(self, t):
        if t == self.at and not self.failed:
            self.failed = True
            raise RuntimeError("boom")


def test_resume_after_a_failed_tick_is_identical():
    runs = []
    for fail in (False, True):
        g, dev = standing_graph(wrench_bodies=["base_link"])
        dev.wrench_base_link.set([0.0, 40.0, 0.0, 0.0, 0.0, 5.0])  # some motion
        if fail:
            g.add(FailOnce("fail", at=150))
            with pytest.raises(RuntimeError, match="boom"):
                g.run(ticks=300)
            assert g.t == 150 and dev.q.time == 150
            g.run(ticks=150)
        else:
            g.run(ticks=300)
        runs.append({name: np.array(s.value) for name, s in dev.outputs.items()})
    assert np.abs(runs[0]["v"]).max() > 0.01
    for name, value in runs[0].items():
        np.testing.assert_array_equal(runs[1][name], value, err_msg=name)


def test_parameters_are_checked():
    with pytest.raises(dg.ParamError, match="wrench body 'nose' is not in the model"):
        MujocoDevice("sim", wrench_bodies=["nose"])
    with pytest.raises(dg.ParamError, match="'kp' must be a finite scalar or 32 values"):
        MujocoDevice("sim", kp=[1.0, 2.0])
    with pytest.raises(dg.ParamError, match="q0 needs 39"):
        MujocoDevice("sim", q0=np.zeros(7))
    for gain in ("kp", "kd"):  # a negative stiffness or damping would push the joints away
        with pytest.raises(dg.ParamError, match=rf"sim: parameter '{gain}' must be within \[0.0, None\]"):
            MujocoDevice("sim", control_mode="position", **{gain: [-1.0] + [1.0] * 31})
    assert dg.get_type("MujocoDevice") is MujocoDevice  # through the dgraph.entities entry point


def render_or_skip(dev, width, height):
    import mujoco

    try:
        return dev.render(width, height)
    except mujoco.FatalError as exc:  # only a machine without an OpenGL/EGL platform skips; anything else fails
        if "OpenGL" not in str(exc) and "EGL" not in str(exc):
            raise
        pytest.skip(f"offscreen rendering unavailable (MUJOCO_GL=egl): {exc}")


def test_render_snapshot_and_video(tmp_path):
    with dg.Graph(dt=0.001) as g:
        dev = g.add(MujocoDevice("sim", video_path=str(tmp_path / "fall.gif"), video_fps=100.0, video_size=[32, 24]))
        image = render_or_skip(dev, 64, 48)
        assert image.shape == (48, 64, 3) and image.dtype == np.uint8
        assert image.std() > 10.0  # robot, floor and sky, not a uniform image
        assert dev.snapshot(str(tmp_path / "s.png"), 64, 48) == str(tmp_path / "s.png")
        dev.control.set(np.zeros(32))
        g.run(ticks=25)  # frames after ticks 1, 11, 21
    from PIL import Image

    assert Image.open(tmp_path / "s.png").size == (64, 48)
    video = Image.open(tmp_path / "fall.gif")
    assert video.n_frames == 3 and video.size == (32, 24)


def test_an_unknown_video_format_is_refused_at_construction():  # more in test_video.py
    with pytest.raises(dg.ParamError, match=r"device: video_path: 'out/run.avi' has an unknown video extension"):
        MujocoDevice("device", video_path="out/run.avi")


def test_position_mode_inputs_exist_only_in_position_mode():
    torque = MujocoDevice("device")
    assert "feedforward_torque" not in torque.inputs and "velocity_reference" not in torque.inputs
    with pytest.raises(dg.DGraphError, match="has no signal 'feedforward_torque'"):
        torque.signal("feedforward_torque")
    assert "feedforward_torque" in MujocoDevice("device", control_mode="position").inputs


class _Counted:
    """``mujoco.mj_rnePostConstraint``, counting its calls."""

    def __init__(self, function):
        self.function, self.calls = function, 0

    def __call__(self, m, d):
        self.calls += 1
        return self.function(m, d)


def test_an_arm_without_any_sensor_measures_its_contact_force(monkeypatch):
    """The Panda (a URDF arm: no sensor at all) presses its drill tool on the wall: MuJoCo fills
    cfrc_ext only for an acceleration-stage sensor, so the device computes it itself each step."""
    from pathlib import Path

    from dgraph.entities.references.drilling import RAMP

    counted = _Counted(mujoco.mj_rnePostConstraint)
    monkeypatch.setattr(mujoco, "mj_rnePostConstraint", counted)
    graph = dg.load(str(Path(__file__).resolve().parents[2] / "graphs" / "panda_drill.yaml"), {"recorder.rerun": "off"})
    with graph:
        assert graph["device"].mj_model.nsensor == 0
        graph.run(duration=1.2, progress=False)
        data = graph["recorder"].data()
    assert counted.calls == 1 + 1200  # the reset, then every step
    force = data["device.contact_force_total"]
    assert (data["sequence.phase"] == RAMP).any()  # the approach ended on the measured force (>= 3 N)
    pressing = -force[:, 0] > 5.0
    assert pressing.sum() > 100
    # the wall pushes back along -x, its friction (mu 0.5, a pyramid) within the cone
    assert (np.abs(force[pressing, 1:]) <= 0.5 * -force[pressing, 0:1] + 1e-3).all()


def test_talos_has_acceleration_stage_sensors_and_no_extra_call(monkeypatch):
    counted = _Counted(mujoco.mj_rnePostConstraint)
    monkeypatch.setattr(mujoco, "mj_rnePostConstraint", counted)
    g, dev = standing_graph()
    g.run(duration=0.05)
    assert not dev._rne_post_constraint and counted.calls == 0
    assert dev.contact_force_total.value[2] > 0.9 * mass(dev, "base_link") * G  # MuJoCo's own, for the F/T sensors


def test_contact_solver_options_reach_the_model_and_the_defaults_stay_mujocos():
    g = dg.Graph(dt=0.001)
    default = g.add(MujocoDevice("default"))
    tuned = g.add(MujocoDevice("tuned", contact_solver={"cone": "elliptic", "impratio": 10.0,
                                                        "noslip_iterations": 3}))
    assert default.mj_model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL
    assert default.mj_model.opt.impratio == 1.0 and default.mj_model.opt.noslip_iterations == 0
    assert tuned.mj_model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert tuned.mj_model.opt.impratio == 10.0 and tuned.mj_model.opt.noslip_iterations == 3
    assert default.sim.mj_model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL  # the cached model is not touched


@pytest.mark.parametrize(("options", "message"), [
    ({"cone": "conical"}, "cone: one of pyramidal, elliptic"),
    ({"impratio": 0.0}, "impratio: a number > 0"),
    ({"noslip_iterations": 1.5}, "noslip_iterations: an integer >= 0"),
    ({"tolerance": 1e-9}, "tolerance: unknown option"),
    (["cone", "elliptic"], "expected a mapping"),
])
def test_a_bad_contact_solver_option_is_a_param_error_naming_it(options, message):
    with pytest.raises(dg.ParamError, match=message) as error:
        dg.Graph(dt=0.001).add(MujocoDevice("sim", contact_solver=options))
    assert "contact_solver" in str(error.value)
