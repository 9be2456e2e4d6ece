"""SensorFault: a reading passed through, faulty during its window of ticks (no simulator needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import dgraph as dg
from dgraph_sim.faults import KINDS, SensorFault
from tests.conftest import Ticker

DT = 0.01
TICKS = 8
WINDOW = range(3, 6)  # start = 0.03 s, ticks = 3


class Vec(dg.Entity):
    """A reading that moves every tick: [u, 10 + u, 20 + u]."""

    u = dg.Input(shape=())

    @dg.output(shape=(3,), depends=("u",))
    def v(self, t):
        u = self.u(t)
        return np.array([u, 10.0 + u, 20.0 + u])


class Reader(dg.Entity):
    """Pulls its input every tick, as an estimator would, and keeps what it read."""

    has_state = True
    u = dg.Input(shape=None, finite=None)

    def reset(self):
        self.seen = []

    def prepare_state(self, t):
        self.seen.append(np.array(self.u(t), dtype=float))

    def commit_state(self, t_next):
        pass


def run(**params) -> np.ndarray:
    """The readings the reader got at ticks 0..TICKS-1 through a SensorFault with ``params``."""
    g = dg.Graph(dt=DT, name="fault")
    g.add(Ticker("dev"), Vec("vec"), SensorFault("fault", start=0.03, ticks=3, **params), Reader("reader"))
    g.plug("dev.x", "vec.u")
    g.plug("vec.v", "fault.reading")
    g.plug("fault.output", "reader.u")
    g.run(ticks=TICKS)
    return np.array(g["reader"].seen)


TRUE = np.array([[t, 10.0 + t, 20.0 + t] for t in range(TICKS)])


def expected(kind: str, indices: list[int], magnitude: float = 1.0) -> np.ndarray:
    out = TRUE.copy()
    at = indices or [0, 1, 2]
    for t in WINDOW:
        for i in at:
            out[t, i] = {"nan": math.nan, "inf": math.copysign(math.inf, magnitude),
                         "jump": TRUE[t, i] + magnitude, "frozen": TRUE[WINDOW.start, i]}[kind]
    return out


@pytest.mark.parametrize("indices", [[], [1], [0, 2]])
@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_acts_inside_its_window_only_on_the_chosen_elements(kind, indices):
    got = run(kind=kind, indices=indices, magnitude=2.5)
    want = expected(kind, indices, 2.5)
    np.testing.assert_array_equal(got, want)
    outside = [t for t in range(TICKS) if t not in WINDOW]
    np.testing.assert_array_equal(got[outside], TRUE[outside])  # before and after: the reading itself
    assert not np.array_equal(got[list(WINDOW)], TRUE[list(WINDOW)])  # and inside: something else


def test_a_negative_magnitude_gives_minus_inf():
    got = run(kind="inf", indices=[2], magnitude=-1.0)
    assert got[3:6, 2].tolist() == [-math.inf] * 3 and got[2, 2] == 22.0 and got[6, 2] == 26.0
    np.testing.assert_array_equal(got[:, :2], TRUE[:, :2])


def test_frozen_holds_the_value_of_the_windows_first_tick():
    got = run(kind="frozen", indices=[1])
    assert got[:, 1].tolist() == [10.0, 11.0, 12.0, 13.0, 13.0, 13.0, 16.0, 17.0]
    np.testing.assert_array_equal(got[:, [0, 2]], TRUE[:, [0, 2]])


def test_a_window_of_one_tick_and_the_defaults():
    fault = SensorFault("f", kind="jump")
    assert (fault.start, fault.ticks, fault.indices, fault.magnitude) == (0.0, 1, [], 1.0)
    g = dg.Graph(dt=DT)
    g.add(Ticker("dev"), Vec("vec"), SensorFault("fault", kind="jump", start=0.05), Reader("reader"))
    g.plug("dev.x", "vec.u")
    g.plug("vec.v", "fault.reading")
    g.plug("fault.output", "reader.u")
    g.run(ticks=TICKS)
    got = np.array(g["reader"].seen)
    assert got[:, 0].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 6.0, 7.0]


def test_an_unknown_kind_is_refused_and_the_type_is_registered():
    with pytest.raises(dg.ParamError, match="kind"):
        SensorFault("f", kind="stuck")
    assert dg.get_type("SensorFault") is SensorFault


class NanOf(dg.Entity):
    """A plain output (finite by default) that computes NaN once its first element is above 4."""

    reading = dg.Input(shape=(3,))

    @dg.output(shape=(3,), depends=("reading",))
    def output(self, t):
        value = self.reading(t).copy()
        if value[0] > 4.0:
            value[0] = math.nan
        return value


def test_value_checks_let_the_faults_nan_through_but_refuse_a_plain_nan():
    g = dg.Graph(dt=DT, name="checked")
    g.check_values = True
    g.add(Ticker("dev"), Vec("vec"), SensorFault("fault", kind="nan", start=0.03, ticks=3, indices=[0]),
          Reader("reader"))
    g.plug("dev.x", "vec.u")
    g.plug("vec.v", "fault.reading")
    g.plug("fault.output", "reader.u")
    g.run(ticks=TICKS)  # not refused: finite=None
    got = np.array(g["reader"].seen)
    assert np.isnan(got[3:6, 0]).all() and not np.isnan(got[[0, 1, 2, 6, 7]]).any()

    plain = dg.Graph(dt=DT, name="plain")
    plain.check_values = True
    plain.add(Ticker("dev"), Vec("vec"), NanOf("nan_of"), Reader("reader"))
    plain.plug("dev.x", "vec.u")
    plain.plug("vec.v", "nan_of.reading")
    plain.plug("nan_of.output", "reader.u")
    plain.run(ticks=5)  # x = 0..4
    with pytest.raises(dg.SpecError, match=r"nan_of\.output.*NaN"):
        plain.step()
    assert plain.t == 5
