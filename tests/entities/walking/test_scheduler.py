"""ContactScheduler: contacts and swings per phase, the removal and creation ramps, the motion weights."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import dgraph as dg
from dgraph.entities.walking.footsteps import straight_walk, yaw_placement
from dgraph.entities.walking.scheduler import ContactScheduler
from tests.conftest import Ticker

DT = 0.001
LEFT0 = yaw_placement([0.0, 0.085, 0.0])
RIGHT0 = yaw_placement([0.0, -0.085, 0.0])
SIDES = ("left", "right")


def scheduler(plan, **params) -> ContactScheduler:
    graph = dg.Graph(dt=DT)
    graph.add(Ticker("clock"))
    entity = graph.add(ContactScheduler("schedule", **params))
    entity.plan.set(plan)
    return entity


def timeline(entity: ContactScheduler, ticks: int) -> dict[str, np.ndarray]:
    """Every output at every tick."""
    names = [f"{side}_{what}" for side in SIDES for what in
             ("contact", "swing", "normal_force_scale", "force_weight_scale", "motion_weight")]
    names += ["phase", "phase_progress", "double_support"]
    return {name: np.array([getattr(entity, name)(t) for t in range(ticks)]) for name in names}


def test_the_20cm_walk_switches_contacts_with_ramps_that_end_and_start_at_the_switches():
    plan = straight_walk(LEFT0, RIGHT0)
    transition, start = 0.1, 0.3
    entity = scheduler(dataclasses.replace(plan, start=start), transition=transition)
    ticks = round((plan.duration + start + 0.5) / DT)
    out = timeline(entity, ticks)
    ramp_step = 1.875 * DT / transition  # the minimum-jerk profile's largest slope, per tick
    lift_offs = {side: np.flatnonzero(np.diff(out[f"{side}_swing"].astype(int)) == 1) + 1 for side in SIDES}
    touch_downs = {side: np.flatnonzero(np.diff(out[f"{side}_swing"].astype(int)) == -1) + 1 for side in SIDES}
    assert len(lift_offs["left"]) == 4 and len(lift_offs["right"]) == 3
    assert lift_offs["left"][0] == round((start + 1.0) / DT)  # after the initial double support
    for side in SIDES:
        contact, swing = out[f"{side}_contact"], out[f"{side}_swing"]
        scale, weight = out[f"{side}_normal_force_scale"], out[f"{side}_force_weight_scale"]
        assert (contact != swing).all()  # a foot is either a contact or swinging
        assert (scale[swing] == 0.0).all() and (out[f"{side}_motion_weight"] == np.where(swing, 2e3, 0.0)).all()
        for tick in lift_offs[side]:
            assert scale[tick] == 0.0 and not contact[tick]  # removed unloaded
            # the ramp takes the last 100 ticks (the lift-off tick itself may round to the tick after)
            assert 0.0 <= scale[tick - 1] < 1e-4 and scale[tick - 102] == 1.0 and scale[tick - 90] < 1.0
            ramp = scale[tick - 102:tick + 1]
            assert (np.diff(ramp) <= 0.0).all() and np.abs(np.diff(ramp)).max() <= ramp_step + 1e-12
        for tick in touch_downs[side]:
            assert contact[tick] and weight[tick] == pytest.approx(1e3, rel=1e-4)  # at most a tick into the ramp
            ramp = np.log(weight[tick:tick + 102])
            assert (np.diff(ramp) <= 0.0).all() and ramp[-2:] == pytest.approx([0.0, 0.0], abs=1e-12)
            assert np.abs(np.diff(ramp)).max() <= ramp_step * math.log(1e3) + 1e-12
        assert np.abs(np.diff(scale)[~swing[1:] & ~swing[:-1]]).max() <= ramp_step + 1e-12  # no jump on the ground
        assert (weight >= 1.0).all() and (weight[~contact] == 1.0).all()
    single = ~out["double_support"]
    for side in SIDES:  # the foot standing in single support bears the load with its plain weight
        standing = single & out[f"{side}_contact"]
        assert (out[f"{side}_normal_force_scale"][standing] == 1.0).all()
        assert (out[f"{side}_force_weight_scale"][standing] == 1.0).all()
    times = np.arange(ticks) * DT - start
    assert (out["phase"] == [plan.phase_at(s)[0] for s in times]).all()
    assert out["phase_progress"] == pytest.approx([plan.phase_at(s)[2] for s in times], abs=1e-12)
    assert out["left_contact"][-1] and out["right_contact"][-1] and out["phase"][-1] == len(plan.phases) - 1


def test_a_zero_double_support_switches_at_once():
    plan = straight_walk(LEFT0, RIGHT0, steps=2, double_support=0.0)
    entity = scheduler(plan)
    touch_down = round((1.0 + 0.9) / DT)  # the left foot lands as the right one lifts off
    assert entity.right_normal_force_scale(touch_down - 1) == 1.0 and entity.right_swing(touch_down)
    assert entity.left_contact(touch_down) and entity.left_force_weight_scale(touch_down) == 1.0


def test_a_transition_longer_than_a_double_support_is_a_param_error():
    entity = scheduler(straight_walk(LEFT0, RIGHT0, double_support=0.115), transition=0.12)
    with pytest.raises(dg.ParamError, match=r"schedule.*'transition' \(0.12 s\) exceeds the double support of phase 2"):
        entity.left_contact(0)
    assert scheduler(straight_walk(LEFT0, RIGHT0, double_support=0.0), transition=0.5).phase(0) == 0


def test_a_new_plan_is_read_at_once():
    entity = scheduler(straight_walk(LEFT0, RIGHT0))
    assert entity.left_swing(1500) and not entity.right_swing(1500)
    entity.plan.set(straight_walk(LEFT0, RIGHT0, first_side="right"))
    assert entity.right_swing(1500) and not entity.left_swing(1500)


def test_all_outputs_of_a_tick_come_from_one_computation(monkeypatch):
    plan = straight_walk(LEFT0, RIGHT0)
    entity = scheduler(plan)
    calls = []
    phase_at = type(plan).phase_at
    monkeypatch.setattr(type(plan), "phase_at", lambda self, time: calls.append(time) or phase_at(self, time))
    names = list(entity.outputs)
    assert len(names) == 13
    for tick in range(3):  # as the loop reads them: every output at one tick, then the next tick
        for name in names:
            getattr(entity, name)(tick)
    assert calls == pytest.approx([0.0, 0.001, 0.002])
