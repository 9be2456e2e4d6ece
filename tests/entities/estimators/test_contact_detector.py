"""ContactDetector: phases 0 -> 1 -> 2 with force thresholds, dwell times and hysteresis."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.estimators import ContactDetector


def detector_graph(dt=0.001, **params):
    g = dg.Graph(dt=dt, name="detector_test")
    return g, g.add(ContactDetector("detector", **params))


def feed(g, detector, normal_forces, normal=(0.0, 0.0, 1.0)):
    """One tick per force (along ``normal``); the phase after each tick."""
    phases = []
    for f in normal_forces:
        detector.force.set(f * np.asarray(normal, dtype=float))
        g.step()
        phases.append(int(detector.phase.value))
    return phases


def test_contact_is_made_only_after_on_force_held_for_on_time():
    g, d = detector_graph(on_force=5.0, off_force=2.0, on_time=0.01, off_time=0.05)
    assert d.phase.value == 0 and not d.in_contact.value
    assert feed(g, d, [4.99] * 30) == [0] * 30  # just under the threshold: never
    phases = feed(g, d, [5.0] * 12)  # at the threshold from tick 30: 10 ticks of 1 ms
    assert phases == [0] * 9 + [1] * 3
    assert d.in_contact.value and d.phase.time == g.t
    assert g.t == 42


def test_a_short_dip_restarts_the_dwell():
    g, d = detector_graph(on_force=5.0, off_force=2.0, on_time=0.01, off_time=0.05)
    phases = feed(g, d, [8.0] * 9 + [4.0] + [8.0] * 10)
    assert phases == [0] * 19 + [1]  # 9 ticks, dip, then 10 full ticks
    # in contact, forces between the thresholds keep it (hysteresis), and so does a dip shorter than off_time
    assert feed(g, d, [3.0] * 100) == [1] * 100
    assert feed(g, d, [1.0] * 49 + [3.0] + [1.0] * 49) == [1] * 99
    assert feed(g, d, [1.0]) == [2]  # the 50th tick under off_force since the 3 N sample
    assert not d.in_contact.value


def test_contact_is_lost_after_off_force_held_for_off_time_and_lost_is_final():
    g, d = detector_graph(on_force=3.0, off_force=2.0, on_time=0.01, off_time=0.5)
    feed(g, d, [10.0] * 10)
    assert d.phase.value == 1
    phases = feed(g, d, [2.0] * 501)
    assert phases.index(2) == 499  # 500 ticks at the threshold (0.5 s)
    assert feed(g, d, [50.0] * 100 + [0.0] * 100) == [2] * 200  # a new contact needs a new plan
    assert not d.in_contact.value


def test_the_normal_is_normalised_and_only_its_component_counts():
    normal = np.array([0.0, 3.0, 4.0])  # |n| = 5
    g, d = detector_graph(normal=normal.tolist(), on_force=5.0, off_force=2.0, on_time=0.003)
    n = normal / 5.0
    assert feed(g, d, [4.5] * 10, n) == [0] * 10  # 4.5 N along n (22.5 with an unnormalised n)
    side = np.cross(n, [1.0, 0.0, 0.0])
    for _ in range(10):  # a large force across the normal does not make a contact
        d.force.set(100.0 * side + 1.0 * n)
        g.step()
    assert d.phase.value == 0
    assert feed(g, d, [6.0] * 3, n) == [0, 0, 1]


def test_dwell_times_are_whole_ticks_at_a_10_ms_period():
    # 10 ticks of 0.01 s add up to 0.09999999999999999 s: the dwell must not take an 11th tick
    g, d = detector_graph(dt=0.01, on_force=5.0, off_force=2.0, on_time=0.1, off_time=0.1)
    assert feed(g, d, [6.0] * 11) == [0] * 9 + [1] * 2
    assert feed(g, d, [0.0] * 11) == [1] * 9 + [2] * 2


@pytest.mark.parametrize(("params", "fragment"), [
    ({"on_force": 5.0, "off_force": 5.0}, "off_force must be below on_force"),
    ({"on_force": 2.0, "off_force": 3.0}, "off_force must be below on_force"),
    ({"normal": [0.0, 0.0, 0.0]}, "normal must be a non-zero 3-vector"),
])
def test_bad_thresholds_and_normal_name_the_entity(params, fragment):
    with pytest.raises(dg.ParamError, match=fragment) as info:
        ContactDetector("detector", **params)
    assert info.value.entity == "detector"
