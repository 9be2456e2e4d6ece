"""SensorGuard: bad sensor elements replaced by their prediction and reported, good ones untouched."""

from __future__ import annotations

import math

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.estimators.sensor_guard import MAX_NAMED, Channel, SensorGuard
from dgraph.faults import Fault

DT = 0.01
AXIS = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
TICKS = 40
NAMES = ("pos", "vel", "quat", "wrench")
PREDICTED = "replaced by its prediction"
FILLED = "replaced by a value in range (no earlier reading)"


class Raw(dg.Entity):
    """A raw reading, as a driver would hand it over: anything, NaN included (an input's constant
    may not be NaN, so the readings come from here)."""

    def setup(self):
        self.value = np.zeros(0)

    @dg.output(shape=None, depends=("t",), finite=None)
    def output(self, t):
        return self.value


class Sensors(dg.Entity):
    """The raw readings of a small robot: a position with its rate, an orientation, a wrench
    (``finite=None``: a raw reading may hold NaN and infinities)."""

    pos = dg.Input(shape=(3,), finite=None)
    vel = dg.Input(shape=(3,), finite=None)
    quat = dg.Input(shape=(4,), finite=None)
    wrench = dg.Input(shape=(6,), finite=None)


def trajectory() -> dict[str, np.ndarray]:
    """Good readings, one row per tick: every element moves every tick (nothing is frozen),
    the position integrates its rate exactly as the guard predicts it."""
    t = np.arange(TICKS)[:, None]
    vel = np.array([0.5, -1.0, 2.0]) + np.array([0.01, 0.02, -0.01]) * t
    pos = np.empty((TICKS, 3))
    pos[0] = [0.1, 0.2, -0.3]
    for k in range(1, TICKS):
        pos[k] = pos[k - 1] + DT * vel[k - 1]
    angle = 0.02 * t  # about a tilted axis: every component moves
    quat = np.hstack([np.sin(angle / 2) * AXIS, np.cos(angle / 2)])
    wrench = np.arange(1.0, 7.0) + 0.1 * t
    return {"pos": pos, "vel": vel, "quat": quat, "wrench": wrench}


GOOD = trajectory()


class Rig:
    """A ``Sensors`` entity read through a guard, tick by tick as an estimator does: ``read(t)``
    while the tick is computed, ``commit()`` when it commits."""

    def __init__(self, frozen_ticks: int = 0, vel_growth: float | None = None, wrench_frozen: bool = True):
        self.graph = dg.Graph(dt=DT, name="guard")
        self.graph.cache_enabled = False  # a raw reading changed at the same tick is read again
        self.entity = self.graph.add(Sensors("s"))
        self.raw = {}
        for name in NAMES:
            self.raw[name] = self.graph.add(Raw(f"raw_{name}"))
            self.graph.plug(self.raw[name].output, self.entity.signal(name))
        self.guard = SensorGuard(self.entity, [
            Channel("pos", -1.0, 1.0, 0.05, rate="vel"),
            Channel("vel", -5.0, 5.0, 1.0, growth=vel_growth),
            Channel("quat", -1.01, 1.01, 0.05, quaternion=True),
            Channel("wrench", -100.0, 100.0, frozen=wrench_frozen),  # no jump test
        ], DT, frozen_ticks=frozen_ticks)
        self.log = self.entity.fault_log
        self.t = 0

    def feed(self, **bad: dict[int, float] | np.ndarray) -> dict[str, np.ndarray]:
        """Set the good readings of tick ``t``, with some elements (``{index: value}``) or whole
        readings (an array) replaced; return what was set."""
        readings = {}
        for name in NAMES:
            value = GOOD[name][self.t].copy()
            change = bad.get(name, {})
            if isinstance(change, dict):
                for index, x in change.items():
                    value[index] = x
            else:
                value = np.asarray(change, dtype=float)
            self.raw[name].value = value
            readings[name] = value
        return readings

    def tick(self, commit: bool = True, **bad: dict[int, float] | np.ndarray
             ) -> tuple[dict[str, np.ndarray], list[Fault]]:
        """One tick: the trusted readings and the faults reported."""
        self.feed(**bad)
        self.log.begin(self.t)
        values = {name: value.copy() for name, value in zip(NAMES, self.guard.read(self.t), strict=True)}
        faults = self.log.staged(self.t)
        if commit:
            self.guard.commit()
            self.log.commit(self.t)
            self.t += 1
        return values, faults

    def run(self, ticks: int) -> None:
        for _ in range(ticks):
            _, faults = self.tick()
            assert faults == []


def good(t: int) -> dict[str, np.ndarray]:
    return {name: GOOD[name][t] for name in NAMES}


def assert_values(values: dict[str, np.ndarray], expected: dict[str, np.ndarray]) -> None:
    for name in NAMES:
        np.testing.assert_array_equal(values[name], expected[name], err_msg=name)


def test_good_readings_pass_through_unchanged_in_fresh_arrays():
    rig = Rig(frozen_ticks=5)
    for t in range(TICKS):
        values, faults = rig.tick()
        assert faults == []
        assert_values(values, good(t))
        assert not np.shares_memory(values["pos"], rig.entity.pos(t))
    assert rig.log.degraded_ticks == 0


BAD_ELEMENTS = [  # channel, index, value at tick 5 (None: the good one plus an offset), cause
    ("vel", 1, math.nan, "NaN"),
    ("vel", 2, math.inf, "inf"),
    ("wrench", 4, -math.inf, "inf"),
    ("wrench", 0, 150.0, "out of range"),
    ("pos", 2, 1.5, "out of range"),
    ("pos", 0, None, "jump"),   # 0.2 from its prediction, max_step 0.05
    ("vel", 0, None, "jump"),   # 3 from its prediction, max_step 1
]


@pytest.mark.parametrize(("name", "index", "value", "cause"), BAD_ELEMENTS)
def test_a_bad_element_is_replaced_by_its_prediction_reported_once_then_trusted_again(name, index, value, cause):
    rig = Rig(frozen_ticks=5)
    rig.run(5)
    if value is None:
        value = GOOD[name][5, index] + {"pos": 0.2, "vel": 3.0}[name]
    values, faults = rig.tick(**{name: {index: value}})
    expected = good(5)
    # the prediction: the last trusted value (tick 4), moved by dt times its rate for the position
    prediction = GOOD[name][4, index] + (DT * GOOD["vel"][4, index] if name == "pos" else 0.0)
    assert values[name][index] == pytest.approx(prediction, abs=1e-15)
    if name == "pos":
        assert values[name][index] == pytest.approx(GOOD["pos"][5, index], abs=1e-15)  # exact kinematics
    values[name][index] = expected[name][index]
    assert_values(values, expected)  # every other element untouched
    assert len(faults) == 1
    fault = faults[0]
    assert (fault.tick, fault.signal, fault.cause, fault.action) == (5, f"s.{name}[{index}]", cause, PREDICTED)
    values, faults = rig.tick()  # the reading comes back: trusted at once
    assert faults == []
    assert_values(values, good(6))
    assert rig.log.degraded_ticks == 1 and rig.log.counts == {(f"s.{name}[{index}]", cause): 1}


def test_the_details_give_the_numbers():
    rig = Rig()
    rig.run(5)
    _, faults = rig.tick(wrench={0: 150.0}, vel={0: GOOD["vel"][5, 0] + 3.0}, pos={1: math.nan})
    causes = {f.signal: f.cause for f in faults}
    assert causes == {"s.pos[1]": "NaN", "s.vel[0]": "jump", "s.wrench[0]": "out of range"}
    details = {f.signal: f.detail for f in faults}  # the numbers end the detail (it may name the source first)
    assert details["s.vel[0]"].endswith(f"{GOOD['vel'][5, 0] + 3.0:.6g}, predicted {GOOD['vel'][4, 0]:.6g} "
                                        "(tolerance 1)")
    assert details["s.wrench[0]"].endswith("150 not in [-100, 100]")
    assert not any(c.isdigit() for c in details["s.pos[1]"].replace("raw_pos", ""))  # NaN: no number to give


def test_beyond_max_named_bad_elements_are_counted_in_one_more_fault():
    rig = Rig()
    rig.run(3)
    values, faults = rig.tick(wrench=np.full(6, math.nan))
    np.testing.assert_array_equal(values["wrench"], GOOD["wrench"][2])
    assert [f.signal for f in faults] == [f"s.wrench[{i}]" for i in range(MAX_NAMED)] + ["s.sensors"]
    assert (faults[-1].cause, faults[-1].detail) == ("more bad elements", f"{6 - MAX_NAMED} more")


def test_a_bad_quaternion_is_one_fault_for_the_whole_reading_replaced_as_a_whole():
    rig = Rig()
    rig.run(5)
    reading = GOOD["quat"][5].copy()
    reading[2] = math.nan
    values, faults = rig.tick(quat=reading)
    np.testing.assert_array_equal(values["quat"], GOOD["quat"][4])
    assert [(f.signal, f.cause, f.action) for f in faults] == [("s.quat", "NaN", PREDICTED)]
    values, faults = rig.tick()
    assert faults == [] and np.array_equal(values["quat"], GOOD["quat"][6])


def test_a_quaternion_jumping_in_some_elements_is_replaced_as_a_whole():
    rig = Rig()
    rig.run(5)
    reading = GOOD["quat"][4] + [0.06, 0.0, 0.0, 0.0]
    reading /= np.linalg.norm(reading)  # a unit quaternion: x moves by about 0.06 > 0.05, y, z and w by less
    deviation = np.abs(reading - GOOD["quat"][4])
    assert deviation[1:].max() < 0.005 and 0.055 < deviation[0] < 0.06
    values, faults = rig.tick(quat=reading)
    np.testing.assert_array_equal(values["quat"], GOOD["quat"][4])  # not a mix of two quaternions
    assert np.linalg.norm(values["quat"]) == pytest.approx(1.0, abs=1e-12)
    assert len(faults) == 1 and (faults[0].signal, faults[0].cause) == ("s.quat", "jump")
    assert f"{reading[0]:.6g}, predicted {GOOD['quat'][4, 0]:.6g} " in faults[0].detail  # named by its worst element


def test_a_quaternion_with_flipped_sign_is_turned_back_without_a_fault():
    rig = Rig()
    rig.run(5)
    values, faults = rig.tick(quat=-GOOD["quat"][5])
    assert faults == []
    np.testing.assert_array_equal(values["quat"], GOOD["quat"][5])
    values, faults = rig.tick(quat=-GOOD["quat"][6])  # still flipped: still turned back
    assert faults == [] and np.array_equal(values["quat"], GOOD["quat"][6])


@pytest.mark.parametrize(("scale", "refused"), [(1.02, True), (0.985, True), (1.005, False), (0.995, False)])
def test_a_quaternion_whose_norm_is_off_by_more_than_one_percent_is_refused(scale, refused):
    rig = Rig()
    rig.run(5)
    values, faults = rig.tick(quat=scale * GOOD["quat"][5])
    if refused:
        np.testing.assert_array_equal(values["quat"], GOOD["quat"][4])
        assert [(f.signal, f.cause) for f in faults] == [("s.quat", "not a unit quaternion")]
    else:
        np.testing.assert_array_equal(values["quat"], scale * GOOD["quat"][5])
        assert faults == []


def test_a_persistent_offset_is_accepted_once_the_growing_bound_passes_it():
    rig = Rig(vel_growth=0.25)
    rig.run(5)
    offset = 1.6  # max_step 1: refused while 1 + 0.25 n < 1.6 + 0.01 (n + 1) (the true rate drifts too)
    trusted = GOOD["vel"][4, 0]
    seen = []
    for n in range(6):
        t = rig.t
        values, faults = rig.tick(vel={0: GOOD["vel"][t, 0] + offset})
        seen.append([(f.signal, f.cause) for f in faults])
        if n < 3:
            assert values["vel"][0] == trusted  # held at its prediction
            assert faults[0].detail.endswith(f"(tolerance {1 + 0.25 * n:.3g})")
        else:
            assert values["vel"][0] == GOOD["vel"][t, 0] + offset  # accepted as a real change
    # n = 3 is the first n with 1 + 0.25 n >= 1.6 + 0.01 (n + 1)
    assert next(n for n in range(6) if 1 + 0.25 * n >= offset + 0.01 * (n + 1)) == 3
    assert seen == [[("s.vel[0]", "jump")]] * 3 + [[]] * 3


def test_without_growth_an_offset_is_refused_for_ever_and_a_return_is_trusted_at_once():
    rig = Rig(vel_growth=0.0)
    rig.run(5)
    for _ in range(20):
        values, faults = rig.tick(vel={0: GOOD["vel"][rig.t, 0] + 1.5})
        assert values["vel"][0] == GOOD["vel"][4, 0] and len(faults) == 1
    values, faults = rig.tick()  # within max_step of the held value: trusted again
    assert faults == [] and values["vel"][0] == GOOD["vel"][rig.t - 1, 0]


def test_a_frozen_reading_is_reported_after_frozen_ticks_repeats_and_kept():
    rig = Rig(frozen_ticks=3)
    rig.run(5)
    held = GOOD["wrench"][5, 2]
    reported = {}
    for _ in range(6):  # ticks 5..10: the same bits every tick from tick 5
        values, faults = rig.tick(wrench={2: held})
        assert values["wrench"][2] == held  # nothing better to use: kept
        reported[rig.t - 1] = [(f.signal, f.cause, f.action, f.detail) for f in faults]
    frozen = ("s.wrench[2]", "frozen", "kept (nothing better)")
    assert reported == {5: [], 6: [], 7: [],  # the same as the tick before 1, 2, then 3 times: frozen
                        8: [(*frozen, "the same for 3 ticks")], 9: [(*frozen, "the same for 4 ticks")],
                        10: [(*frozen, "the same for 5 ticks")]}
    values, faults = rig.tick()  # it moves again
    assert faults == [] and values["wrench"][2] == GOOD["wrench"][11, 2]


def test_a_frozen_position_follows_its_prediction():
    """pos[1] moves at about 1 unit/s: over 8 ticks of 0.01 s its rate moves it by about 0.07,
    more than max_step 0.05, so a reading stuck for 8 ticks is frozen."""
    frozen_ticks = 8
    rig = Rig(frozen_ticks=frozen_ticks)
    rig.run(5)
    held = GOOD["pos"][5, 1]
    trusted = {}
    for _ in range(frozen_ticks + 3):  # ticks 5..15: the same bits from tick 5
        values, faults = rig.tick(pos={1: held})
        t = rig.t - 1
        trusted[t] = values["pos"][1]
        if t < 5 + frozen_ticks:
            assert faults == [] and values["pos"][1] == held  # within max_step of its prediction: kept
        else:
            assert [(f.signal, f.cause, f.action) for f in faults] == [("s.pos[1]", "frozen", PREDICTED)]
    for t in range(5 + frozen_ticks, 5 + frozen_ticks + 3):  # the last trusted position moved by dt times its rate
        assert trusted[t] == pytest.approx(trusted[t - 1] + DT * GOOD["vel"][t - 1, 1], abs=1e-15)
        assert trusted[t] != held


def test_frozen_ticks_zero_and_a_channel_without_the_test_never_report_a_frozen_reading():
    for rig in (Rig(frozen_ticks=0), Rig(frozen_ticks=2, wrench_frozen=False)):
        rig.run(2)
        for _ in range(20):
            values, faults = rig.tick(wrench={2: 1.25})
            assert faults == [] and values["wrench"][2] == 1.25
    rig = Rig(frozen_ticks=2)  # the control: the same readings are frozen with the test on
    rig.run(2)
    reported = [rig.tick(wrench={2: 1.25})[1] for _ in range(4)]
    assert [len(faults) for faults in reported] == [0, 0, 1, 1]


def test_a_read_without_commit_changes_nothing_for_the_next_read():
    plain, failing = Rig(frozen_ticks=3), Rig(frozen_ticks=3)
    plain.run(5)
    failing.run(5)
    # a tick whose read saw bad data (and a frozen-looking repeat) fails before commit
    failing.tick(commit=False, vel={0: math.nan}, pos={1: 0.9}, quat=-GOOD["quat"][5])
    failing.log.clear()  # its faults were staged for tick 5: forget them to compare the guards alone
    for _ in range(10):
        (v1, f1), (v2, f2) = plain.tick(), failing.tick()
        assert_values(v2, v1)
        assert f1 == f2 == []
    assert plain.guard._tolerance is plain.guard._step and failing.guard._tolerance is failing.guard._step


def test_the_first_reading_is_checked_for_range_and_finiteness_only():
    rig = Rig()
    far = {"pos": {0: 0.9}, "vel": {0: -4.5}, "wrench": {5: -99.0}}  # far from anything, but in range
    values, faults = rig.tick(**far)
    assert faults == []
    assert values["pos"][0] == 0.9 and values["vel"][0] == -4.5 and values["wrench"][5] == -99.0


def test_a_bad_first_reading_takes_a_value_in_range():
    rig = Rig()
    values, faults = rig.tick(vel={0: math.nan}, wrench={1: 500.0}, pos={2: -math.inf})
    assert values["vel"][0] == 0.0             # NaN: 0, within [-5, 5]
    assert values["wrench"][1] == 100.0        # the nearest end of its range
    assert values["pos"][2] == 0.0              # an infinity: 0, within [-1, 1] (not a made-up extreme)
    expected = {("s.vel[0]", "NaN"), ("s.wrench[1]", "out of range"), ("s.pos[2]", "inf")}
    assert {(f.signal, f.cause) for f in faults} == expected and {f.action for f in faults} == {FILLED}
    values["vel"][0], values["wrench"][1], values["pos"][2] = GOOD["vel"][0, 0], GOOD["wrench"][0, 1], GOOD["pos"][0, 2]
    assert_values(values, good(0))


@pytest.mark.parametrize("reading", [[0.0, 0.0, 0.0, 0.0], [math.nan] * 4, [0.0, 0.0, 0.0, 2.0]])
def test_a_bad_first_quaternion_is_replaced_by_the_identity(reading):
    rig = Rig()
    values, faults = rig.tick(quat=reading)
    np.testing.assert_array_equal(values["quat"], [0.0, 0.0, 0.0, 1.0])
    assert [(f.signal, f.action) for f in faults] == [("s.quat", FILLED)]


def test_a_rate_must_be_a_guarded_channel_of_the_same_size():
    entity = Rig().entity
    with pytest.raises(dg.ParamError, match="the rate 'quat' of 'pos' is not a guarded input of the same size"):
        SensorGuard(entity, [Channel("pos", rate="quat"), Channel("quat")], DT)
    with pytest.raises(dg.ParamError, match="the rate 'vel' of 'pos'"):
        SensorGuard(entity, [Channel("pos", rate="vel")], DT)


def test_a_one_sided_range_is_checked_at_every_tick():
    entity = Sensors("s")  # constants will do: nothing here is NaN
    guard = SensorGuard(entity, [Channel("vel", 0.0, math.inf), Channel("pos", -math.inf, 1.0)], DT, frozen_ticks=0)
    entity.vel.set([1.0, 2.0, 3.0])
    entity.pos.set([0.5, 0.6, 0.7])
    guard.read(0)
    guard.commit()
    entity.vel.set([-5.0, 2.5, 3.5])  # every element moved: nothing looks frozen
    entity.pos.set([3.0, 0.7, 0.8])
    vel, pos = guard.read(1)
    assert vel.tolist() == [1.0, 2.5, 3.5] and pos.tolist() == [0.5, 0.7, 0.8]
    assert [(f.signal, f.cause) for f in entity.fault_log.staged(1)] == [("s.vel[0]", "out of range"),
                                                                         ("s.pos[0]", "out of range")]


# -- in the floating-base estimator ------------------------------------------------------------

@pytest.fixture(scope="module")
def standing():
    from dgraph.entities.estimators import FloatingBaseEstimator
    from dgraph.entities.estimators.leg_odometry import standing_configuration

    probe = FloatingBaseEstimator("probe", dt=0.001)
    q = standing_configuration(probe.pin_model, probe.foot_frames)
    return {"imu_orientation": np.array([0.0, 0.0, 0.0, 1.0]), "imu_angular_velocity": np.zeros(3),
            "imu_linear_acceleration": np.array([0.0, 0.0, 9.81]), "encoder_position": q[7:].copy(),
            "encoder_velocity": np.zeros(32), "ft_left_ankle": np.array([0.0, 0.0, 400.0, 0.0, 0.0, 0.0]),
            "ft_right_ankle": np.array([0.0, 0.0, 400.0, 0.0, 0.0, 0.0])}


@pytest.mark.parametrize("check", [False, True])
def test_the_floating_base_estimator_reads_through_its_guard_unless_told_not_to(standing, check):
    from dgraph.entities.estimators import FloatingBaseEstimator
    from dgraph.entities.estimators.floating_base import SENSOR_INPUTS

    g = dg.Graph(dt=0.001)
    est = g.add(FloatingBaseEstimator("est", check_sensors=check))
    readings = {name: value.copy() for name, value in standing.items()}
    readings["encoder_position"][3] = math.nan
    readings["ft_left_ankle"][2] = 1e6  # beyond force_range
    for name, value in readings.items():
        raw = g.add(Raw(f"raw_{name}"))
        raw.value = value
        g.plug(raw.output, est.signal(name))
    got = {name: value.copy() for name, value in zip(SENSOR_INPUTS, est.readings(0), strict=True)}
    faults = g.fault_log.staged(0)
    if not check:
        for name in SENSOR_INPUTS:
            np.testing.assert_array_equal(got[name], readings[name], err_msg=name)  # NaN and all
        assert faults == [] and est._guard is None
    else:
        model = est.pin_model
        lower, upper = model.lowerPositionLimit[7 + 3] - 0.1, model.upperPositionLimit[7 + 3] + 0.1
        assert got["encoder_position"][3] == np.clip(0.0, lower, upper)  # no earlier reading: a value in range
        assert got["ft_left_ankle"][2] == est.force_range
        got["encoder_position"][3], got["ft_left_ankle"][2] = math.nan, 1e6
        for name in SENSOR_INPUTS:
            np.testing.assert_array_equal(got[name], readings[name], err_msg=name)  # the good elements untouched
        assert {(f.signal, f.cause) for f in faults} == {("est.encoder_position[3]", "NaN"),
                                                         ("est.ft_left_ankle[2]", "out of range")}


def test_a_bad_first_element_is_trusted_at_its_first_good_reading_however_far_from_the_fill():
    """Filled at the first tick (no prediction yet), an element is checked for range only until
    it reads good once: the true reading is not refused as a jump from a made-up value."""
    rig = Rig()
    values, _ = rig.tick(pos={0: math.nan})  # filled with 0.0; the truth is 0.1, twice max_step away
    assert values["pos"][0] == 0.0
    values, faults = rig.tick()
    assert faults == [] and values["pos"][0] == GOOD["pos"][1, 0]
    values, faults = rig.tick(pos={0: GOOD["pos"][2, 0] + 0.5})  # from now on, jumps are tested again
    assert [(f.signal, f.cause) for f in faults] == [("s.pos[0]", "jump")]


def test_an_exact_zero_is_never_taken_for_frozen():
    rig = Rig(frozen_ticks=2)
    rig.run(2)
    for _ in range(10):
        values, faults = rig.tick(wrench={3: 0.0})  # an unloaded axis, a joint at rest in a noiseless simulation
        assert faults == [] and values["wrench"][3] == 0.0


def test_a_trusted_reading_handed_out_is_read_only_so_no_reader_can_change_the_next_prediction():
    rig = Rig()
    rig.run(3)
    for bad in ({}, {"vel": {0: math.nan}}):  # the fast path and the checked one
        rig.feed(**bad)
        for value in rig.guard.read(rig.t):
            with pytest.raises(ValueError, match="read-only"):
                value[0] = 1.0
        rig.guard.commit()
        rig.t += 1


def test_a_position_at_rest_repeating_its_value_is_not_frozen():
    """A quantized encoder at rest repeats its reading: with a rate that would move it by less
    than max_step over frozen_ticks ticks, it is not frozen (pos[1] moves by 0.02 over 2 ticks)."""
    rig = Rig(frozen_ticks=2)
    rig.run(5)
    for _ in range(6):
        _, faults = rig.tick(pos={1: GOOD["pos"][5, 1]})
        assert not [f for f in faults if f.cause == "frozen"]


class Driver(dg.Entity):
    """A driver's state, updated (committed) only when a sample arrives."""

    has_state = True
    sample = dg.State(shape=(2,), finite=None)


class Reader(dg.Entity):
    speed = dg.Input(shape=(2,), finite=None)


def test_a_reading_whose_source_stops_updating_is_stale_after_stale_ticks():
    graph = dg.Graph(dt=DT, name="stale")
    driver, reader = graph.add(Driver("driver"), Reader("reader"))
    graph.plug(driver.sample, reader.speed)
    guard = SensorGuard(reader, [Channel("speed", -10.0, 10.0)], DT, frozen_ticks=0, stale_ticks=4)
    reported = {}
    for t in range(14):
        if t < 5:  # samples arrive until tick 4, then the driver stops
            driver.sample.set(np.array([1.0 + t, 2.0]), t)
        graph.fault_log.begin(t)
        values = guard.read(t)
        reported[t] = [(f.signal, f.cause, f.detail) for f in graph.fault_log.staged(t)]
        guard.commit()
        graph.fault_log.commit(t)
        assert values[0].tolist() == [5.0, 2.0] if t >= 4 else [1.0 + t, 2.0]  # kept: nothing better
    assert all(reported[t] == [] for t in range(9))  # 4 ticks without an update are allowed
    assert all(reported[t] == [("reader.speed", "stale", "from driver.sample: last updated at tick 4")]
               for t in range(9, 14))


class Joint(dg.Entity):
    """A joint driver's position and velocity, committed while samples arrive."""

    has_state = True
    position = dg.State(shape=(1,), finite=None)
    velocity = dg.State(shape=(1,), finite=None)


class JointReader(dg.Entity):
    position = dg.Input(shape=(1,), finite=None)
    velocity = dg.Input(shape=(1,), finite=None)


def test_a_stale_position_whose_velocity_is_stale_too_is_held_where_it_was_in_range():
    """A driver that stops sends neither: the position must not integrate its last velocity for
    ever (it would leave its range and then be refused as a jump at every tick)."""
    graph = dg.Graph(dt=DT, name="stopped")
    joint, reader = graph.add(Joint("joint"), JointReader("reader"))
    graph.plug(joint.position, reader.position)
    graph.plug(joint.velocity, reader.velocity)
    guard = SensorGuard(reader, [Channel("position", -1.0, 1.0, 0.05, rate="velocity"),
                                 Channel("velocity", -5.0, 5.0, 1.0)], DT, frozen_ticks=0, stale_ticks=4)
    positions = []
    for t in range(300):
        if t < 5:
            joint.position.set(np.array([0.5 + 0.01 * t]), t)
            joint.velocity.set(np.array([1.0]), t)
        graph.fault_log.begin(t)
        positions.append(guard.read(t)[0][0])
        guard.commit()
        graph.fault_log.commit(t)
    assert max(positions) < 0.62 and positions[-1] == positions[-2]  # held, in range: not 0.54 + 2.95
    late = {(f.signal, f.cause) for f in graph.fault_log.faults if f.tick > 250}
    assert late == {("reader.position", "stale"), ("reader.velocity", "stale")}  # no jump at every tick


def test_a_computed_output_is_never_stale():
    """A constant's output is computed once and keeps its first stamp: not a stale driver."""
    from dgraph.entities.operators import Constant

    graph = dg.Graph(dt=DT, name="computed")
    reader = graph.add(Reader("reader"))
    constant = graph.add(Constant("c", value=[1.0, 2.0]))
    graph.plug(constant.output, reader.speed)
    guard = SensorGuard(reader, [Channel("speed", -10.0, 10.0)], DT, frozen_ticks=0, stale_ticks=2)
    for t in range(20):
        graph.fault_log.begin(t)
        guard.read(t)
        guard.commit()
        graph.fault_log.commit(t)
    assert constant.output.time == 0 and graph.fault_log.faults == []
