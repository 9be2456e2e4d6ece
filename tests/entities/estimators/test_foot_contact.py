"""FootContactState: the plan's contact flag corrected by the measured normal force (rule table,
dwells, hysteresis, the early contact's force scale, reset)."""

from __future__ import annotations

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.estimators import FootContactState
from dgraph.entities.estimators.foot_contact import ContactThresholds, next_contact_flag

THRESHOLDS = ContactThresholds(touch_force=20.0, release_force=5.0, touch_ticks=3, release_ticks=20,
                               early_touchdown_progress=0.5)


def contact_graph(**params) -> tuple[dg.Graph, FootContactState]:
    graph = dg.Graph(dt=0.001, name="foot_contact_test")
    return graph, graph.add(FootContactState("contact", **params))


def tick(graph: dg.Graph, contact: FootContactState, force: float, planned: bool = True, progress: float = 0.0,
         normal=(0.0, 0.0, 1.0)) -> FootContactState:
    """Set the inputs of one tick (a normal force along ``normal``, the plan's flag, the swing's
    progress), read the flag, then step: returns the entity, its outputs read at the tick."""
    contact.planned.set(planned)
    contact.swing_progress.set(progress)
    contact.force.set(force * np.asarray(normal, dtype=float))
    contact.active(graph.t)
    contact.touchdown(graph.t)
    contact.normal_force_scale(graph.t)
    graph.step()
    return contact


def feed(graph: dg.Graph, contact: FootContactState, forces, planned: bool = True, progress: float = 0.0,
         normal=(0.0, 0.0, 1.0)) -> list[bool]:
    """One tick per normal force, the plan's flag and the swing's progress held; the flag of each tick."""
    return [bool(tick(graph, contact, force, planned, progress, normal).active.value) for force in forces]


@pytest.mark.parametrize(("before", "held", "planned", "progress", "force", "expected"), [
    (True, 0, False, 0.0, 500.0, (False, 0)),   # planned lift-off: off at once, however loaded
    (False, 2, False, 0.49, 500.0, (False, 0)),  # a scuff in the first half of the swing: no contact
    (False, 0, False, 0.5, 20.0, (False, 1)),   # late in the swing, loaded: the touch dwell starts
    (False, 2, False, 0.8, 20.0, (True, 0)),    # ... and ends at its third tick: an early touch-down
    (True, 7, False, 0.9, 0.0, (True, 0)),      # an early contact holds, unloaded, until the plan's
    (False, 2, True, 0.0, 19.9, (False, 0)),    # planned stance in the air: off, the dwell restarts
    (True, 18, True, 0.0, 5.0, (True, 19)),     # stance unloaded: the release dwell counts
    (True, 19, True, 0.0, 5.0, (False, 0)),     # ... and releases at its 20th tick
    (True, 19, True, 0.0, 5.1, (True, 0)),      # a sample above the release force restarts it
    (True, 3, True, 0.0, 12.0, (True, 0)),      # between the thresholds the flag stays (hysteresis)
    (False, 1, True, 0.0, 12.0, (False, 0)),
])
def test_the_rule_table(before, held, planned, progress, force, expected):
    assert next_contact_flag(before, held, planned, progress, force, THRESHOLDS) == expected


def test_a_planned_lift_off_switches_the_flag_off_at_the_tick_of_the_plan():
    graph, contact = contact_graph()
    assert feed(graph, contact, [400.0] * 5) == [True] * 5  # starts active, standing
    assert feed(graph, contact, [400.0, 300.0, 0.0], planned=False, progress=0.0) == [False] * 3
    assert not contact.touchdown(graph.t)


def test_a_late_touchdown_waits_for_the_sole_to_be_loaded():
    graph, contact = contact_graph(start_active=False)
    assert feed(graph, contact, [0.0] * 500 + [19.9] * 100) == [False] * 600  # planned, in the air
    touchdowns = [(bool(c.active.value), bool(c.touchdown.value))
                  for c in (tick(graph, contact, force) for force in (25.0, 30.0, 40.0, 60.0))]
    assert touchdowns == [(False, False), (False, False), (True, True), (True, False)]


def test_an_early_touchdown_is_a_contact_in_the_second_half_of_the_swing_only():
    graph, contact = contact_graph(start_active=False)
    assert feed(graph, contact, [100.0] * 50, planned=False, progress=0.3) == [False] * 50  # a scuff
    assert feed(graph, contact, [100.0] * 3, planned=False, progress=0.6) == [False, False, True]
    # the early contact holds through the rest of the swing, unloaded, and into the planned stance
    assert feed(graph, contact, [0.0] * 100, planned=False, progress=0.9) == [True] * 100
    assert feed(graph, contact, [400.0] * 10) == [True] * 10


def test_the_early_contact_may_carry_a_little_force_the_plan_does_not_give_it():
    graph, contact = contact_graph(start_active=False, early_normal_force_scale=0.03)
    contact.planned_normal_force_scale.set(0.0)  # the plan: no force on a swinging foot
    scales = [tick(graph, contact, 100.0, planned=False, progress=0.7).normal_force_scale.value for _ in range(3)]
    assert scales == [0.0, 0.0, pytest.approx(0.03)]  # a contact from the third loaded tick
    for planned_scale, expected in ((0.0, 0.03), (0.5, 0.5)):
        contact.planned_normal_force_scale.set(planned_scale)
        assert tick(graph, contact, 0.0, planned=False, progress=0.8).normal_force_scale.value == expected
    contact.planned_normal_force_scale.set(0.2)  # planned stance: the plan's ramp, untouched
    assert tick(graph, contact, 50.0).normal_force_scale.value == 0.2


def test_a_stance_foot_unloaded_for_the_release_dwell_is_released():
    graph, contact = contact_graph(release_ticks=20)
    assert feed(graph, contact, [4.0] * 19 + [6.0] + [4.0] * 19) == [True] * 39  # the 6 N sample restarts the dwell
    assert feed(graph, contact, [4.0, 4.0]) == [False, False]
    assert feed(graph, contact, [12.0] * 50) == [False] * 50  # under the touch force: stays off


def test_only_the_force_along_the_normal_counts():
    normal = np.array([0.0, 3.0, 4.0])  # |n| = 5
    graph, contact = contact_graph(normal=normal.tolist(), start_active=False)
    unit = normal / 5.0
    assert feed(graph, contact, [19.0] * 10, normal=unit) == [False] * 10
    assert contact.normal_force.value == pytest.approx(19.0)  # 95 N with an unnormalised normal
    contact.force.set(500.0 * np.cross(unit, [1.0, 0.0, 0.0]) + 1.0 * unit)  # a large force across the normal
    assert contact.normal_force(graph.t) == pytest.approx(1.0)
    graph.step()
    assert not contact.active_before.value
    assert feed(graph, contact, [21.0] * 3, normal=unit) == [False, False, True]


def test_reset_restarts_the_same_sequence():
    forces = [0.0] * 30 + [50.0] * 10 + [3.0] * 30
    graph, contact = contact_graph(start_active=False, touch_ticks=5, release_ticks=10)
    first = feed(graph, contact, forces)
    assert first.index(True) == 34 and first.index(False, 34) == 49  # the 5th loaded tick, the 10th unloaded
    contact.reset()
    assert not contact.active_before.value and contact.held.value == 0
    again_graph, again = contact_graph(start_active=False, touch_ticks=5, release_ticks=10)
    assert feed(again_graph, again, forces) == first


@pytest.mark.parametrize(("params", "fragment"), [
    ({"touch_force": 5.0, "release_force": 5.0}, "release_force must be below touch_force"),
    ({"normal": [0.0, 0.0, 0.0]}, "normal must be a non-zero 3-vector"),
])
def test_bad_parameters_name_the_entity(params, fragment):
    with pytest.raises(dg.ParamError, match=fragment) as info:
        FootContactState("contact", **params)
    assert info.value.entity == "contact"
