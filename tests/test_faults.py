"""Faults: staged while a tick is computed, kept when it commits, counted once per tick."""

from __future__ import annotations

import pytest

import dgraph as dg
from dgraph import faults
from dgraph.faults import Fault, FaultLog
from tests.conftest import Follower, Ticker


def test_a_reported_fault_is_staged_until_its_tick_commits():
    log = FaultLog()
    log.report(3, "est.q[2]", "NaN", "replaced by its prediction", "nan")
    assert log.staged(3) == [Fault(3, "est.q[2]", "NaN", "replaced by its prediction", "nan")]
    assert log.staged(4) == [] and log.faults == [] and log.degraded_ticks == 0 and not log.counts
    log.commit(3)
    assert log.faults == [Fault(3, "est.q[2]", "NaN", "replaced by its prediction", "nan")]
    assert log.degraded_ticks == 1 and log.counts == {("est.q[2]", "NaN"): 1}
    assert log.staged(3) == []  # kept, no longer staged
    log.commit(4)  # a tick without fault is not degraded
    assert log.degraded_ticks == 1 and len(log.faults) == 1


def test_begin_forgets_the_faults_staged_for_another_tick_and_keeps_its_own():
    log = FaultLog()
    log.report(5, "a.y", "NaN", "zero")       # a tick that failed and was not retried
    log.report(6, "a.y", "inf", "zero")       # already reported for the coming tick (an after hook)
    log.begin(6)
    assert log.staged(5) == [] and [f.cause for f in log.staged(6)] == ["inf"]
    log.commit(6)
    assert [(f.tick, f.cause) for f in log.faults] == [(6, "inf")] and log.degraded_ticks == 1


def test_commit_keeps_only_the_committed_ticks_faults():
    log = FaultLog()
    log.report(1, "a.y", "NaN", "zero")
    log.report(2, "a.y", "NaN", "zero")
    log.commit(2)
    assert [f.tick for f in log.faults] == [2] and log.staged(1) == []


def test_the_same_fault_reported_twice_at_one_tick_is_kept_once():
    log = FaultLog()
    for _ in range(3):  # a computation run again after a failed attempt
        log.report(7, "a.y", "NaN", "zero", "nan")
    log.report(7, "a.y", "NaN", "zero", "other detail")  # not the same fault
    log.report(7, "b.y", "NaN", "zero", "nan")
    assert len(log.staged(7)) == 3
    log.commit(7)
    assert len(log.faults) == 3 and log.degraded_ticks == 1
    assert log.counts == {("a.y", "NaN"): 2, ("b.y", "NaN"): 1}
    log.report(8, "a.y", "NaN", "zero", "nan")  # the same fault at another tick is another one
    log.commit(8)
    assert len(log.faults) == 4 and log.degraded_ticks == 2 and log.counts["a.y", "NaN"] == 3


def test_counts_and_degraded_ticks_over_several_ticks():
    log = FaultLog()
    for t in range(10):
        log.begin(t)
        if t % 2 == 0:
            log.report(t, "est.encoder_position[3]", "NaN", "replaced by its prediction")
        if t % 5 == 0:
            log.report(t, "est.imu_orientation", "jump", "replaced by its prediction")
        log.commit(t)
    assert log.degraded_ticks == 6  # 0, 2, 4, 5, 6, 8
    assert log.counts == {("est.encoder_position[3]", "NaN"): 5, ("est.imu_orientation", "jump"): 2}
    assert [f.tick for f in log.faults] == [0, 0, 2, 4, 5, 6, 8]


def test_only_the_first_kept_faults_are_stored_but_every_one_is_counted(monkeypatch):
    monkeypatch.setattr(faults, "KEPT_FAULTS", 5)
    log = FaultLog()
    for t in range(4):
        log.report(t, "a.y", "NaN", "zero")
        log.report(t, "b.y", "inf", "zero")
        log.commit(t)
    assert len(log.faults) == 5
    assert [(f.tick, f.signal) for f in log.faults] == [(0, "a.y"), (0, "b.y"), (1, "a.y"), (1, "b.y"), (2, "a.y")]
    assert log.degraded_ticks == 4 and log.counts == {("a.y", "NaN"): 4, ("b.y", "inf"): 4}
    assert sum(log.counts.values()) == 8


def test_a_sensor_dead_for_a_minute_at_1_khz_leaves_a_bounded_log_that_counts_every_fault():
    """With the default cap (not patched): 60,000 faults keep at most KEPT_FAULTS, the first ones,
    and the counts, the degraded ticks and the summary still see all of them."""
    log = FaultLog()
    for t in range(60_000):
        log.report(t, "est.encoder_position[3]", "NaN", "replaced by its prediction")
        log.commit(t)
    assert len(log.faults) == faults.KEPT_FAULTS < 60_000
    assert log.faults[-1].tick == faults.KEPT_FAULTS - 1
    assert log.degraded_ticks == 60_000 and log.summary() == "60000 x est.encoder_position[3]: NaN"


def test_summary_lists_the_most_frequent_kinds_first_and_counts_the_rest():
    log = FaultLog()
    assert log.summary() == ""
    for t in range(6):
        log.report(t, "a.y", "NaN", "zero")
        if t < 3:
            log.report(t, "b.y", "inf", "zero")
        if t < 1:
            log.report(t, "c.y", "jump", "zero")
        log.commit(t)
    assert log.summary() == "6 x a.y: NaN\n3 x b.y: inf\n1 x c.y: jump"
    assert log.summary(limit=1) == "6 x a.y: NaN\n... and 2 other kinds"


def test_a_fault_reads_as_one_line():
    assert str(Fault(4, "est.q[1]", "out of range", "replaced by its prediction", "3 not in [-1, 1]")) == \
        "tick 4: est.q[1]: out of range (3 not in [-1, 1]); replaced by its prediction"
    assert str(Fault(4, "sim.control", "not finite", "zero torque")) == "tick 4: sim.control: not finite; zero torque"


def test_clear_forgets_everything():
    log = FaultLog()
    log.report(0, "a.y", "NaN", "zero")
    log.commit(0)
    log.report(1, "a.y", "NaN", "zero")
    log.clear()
    assert log.faults == [] and log.degraded_ticks == 0 and not log.counts and log.staged(1) == []
    log.commit(1)  # nothing staged any more
    assert log.degraded_ticks == 0


# -- through the loop ---------------------------------------------------------------------------

class Clamp(dg.Entity):
    """y = min(u, 2): a larger u is clamped and reported as a fault of y."""

    u = dg.Input(shape=())

    def setup(self):
        self.computed = 0

    @dg.output(shape=(), depends=("u",))
    def y(self, t):
        self.computed += 1
        u = self.u(t)
        if u > 2.0:
            self.report_fault(t, "y", "too large", "clamped to 2", f"{u:g}")
            return 2.0
        return u


class Bomb(dg.Entity):
    """A stateful entity that fails its tick while armed."""

    has_state = True

    def setup(self):
        self.armed = False

    def prepare_state(self, t):
        if self.armed:
            raise RuntimeError("boom")


def clamped_graph():
    g = dg.Graph(dt=0.01, name="faults")
    g.add(Ticker("dev"), Clamp("clamp"), Follower("follow"), Bomb("bomb"))  # bomb prepares after follow
    g.plug("dev.x", "clamp.u")
    g.plug("clamp.y", "follow.u")
    return g


def test_a_fault_reported_during_a_tick_is_in_the_graphs_log_after_the_step():
    g = clamped_graph()
    g.run(ticks=3)  # x = 0, 1, 2: nothing clamped
    assert g.fault_log.faults == [] and g.fault_log.degraded_ticks == 0
    g.step()  # x = 3
    assert g.fault_log.faults == [Fault(3, "clamp.y", "too large", "clamped to 2", "3")]
    assert g["follow.s"].value == 2.0
    g.run(ticks=2)
    assert [f.tick for f in g.fault_log.faults] == [3, 4, 5] and g.fault_log.degraded_ticks == 3
    assert g.fault_log.counts == {("clamp.y", "too large"): 3}
    assert g["clamp"].fault_log is g.fault_log


@pytest.mark.parametrize("cache", [True, False])
def test_a_failed_tick_keeps_no_fault_and_its_retry_counts_the_tick_once(cache):
    g = clamped_graph()
    g.cache_enabled = cache
    g.run(ticks=3)
    g["bomb"].armed = True
    with pytest.raises(RuntimeError, match="boom"):
        g.step()  # clamp.y reported its fault at tick 3, then bomb failed the tick
    assert g.t == 3 and g.fault_log.faults == [] and g.fault_log.degraded_ticks == 0
    computed = g["clamp"].computed
    g["bomb"].armed = False
    g.step()
    if not cache:  # computed again at the retry: reported twice, kept once
        assert g["clamp"].computed == computed + 1
    assert g.t == 4 and g.fault_log.degraded_ticks == 1
    assert g.fault_log.faults == [Fault(3, "clamp.y", "too large", "clamped to 2", "3")]
    assert g.fault_log.counts == {("clamp.y", "too large"): 1}


def test_an_entity_outside_a_graph_has_its_own_log():
    a, b = Clamp("a"), Clamp("b")
    assert a.fault_log is a.fault_log and a.fault_log is not b.fault_log
    a.u.set(5.0)
    assert a.y(0) == 2.0
    assert a.fault_log.staged(0) == [Fault(0, "a.y", "too large", "clamped to 2", "5")] and b.fault_log.staged(0) == []
    g = dg.Graph()
    g.add(a)
    assert a.fault_log is g.fault_log and a.fault_log.staged(0) == []


def test_report_fault_names_the_signal_after_its_entity_unless_given_in_full():
    e = Clamp("e")
    e.report_fault(0, "y[2]", "NaN", "zero")
    e.report_fault(0, "other.y", "NaN", "zero")
    e.report_fault(0, "y", "NaN", "zero", "1.5 m")
    assert [f.signal for f in e.fault_log.staged(0)] == ["e.y[2]", "other.y", "e.y"]


def test_a_standalone_device_commits_its_faults_with_its_tick():
    class Noisy(Ticker):
        def prepare_state(self, t):
            if t == 1:
                self.report_fault(t, "x", "frozen", "kept")
            super().prepare_state(t)

    dev = Noisy("dev")
    dev.increment()
    dev.increment()
    dev.increment()
    assert dev.fault_log.faults == [Fault(1, "dev.x", "frozen", "kept")] and dev.fault_log.degraded_ticks == 1
