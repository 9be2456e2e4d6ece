"""FootstepPlan and its builders: footprints, timing, phases, ZMP reference, support polygons, plain data."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from dgraph.entities.walking.footsteps import (
    Footstep,
    FootstepPlan,
    SoleShape,
    lateral_walk,
    straight_walk,
    turning_walk,
    yaw_placement,
)
from dgraph.signals.value_types import VALUE_TYPES

LEFT0 = yaw_placement([0.0, 0.085, 0.0])
RIGHT0 = yaw_placement([0.0, -0.085, 0.0])
SOLE = SoleShape()


def yaw_of(placement: np.ndarray) -> float:
    return math.atan2(placement[1, 0], placement[0, 0])


def inside(plan: FootstepPlan, time: float, points: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """Signed distance of each point to the nearest edge of the support polygon (> 0 inside)."""
    normals, offsets = plan.support_polygon(time, margin)
    return (offsets[None, :] - points[:, :2] @ normals.T).min(axis=1)


def test_the_20cm_walk_has_six_steps_and_a_closing_step_and_advances_1_2_m():
    plan = straight_walk(LEFT0, RIGHT0)
    assert [s.side for s in plan.steps] == ["left", "right", "left", "right", "left", "right", "left"]
    xs = [s.placement[0, 3] for s in plan.steps]
    assert xs == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.2], abs=1e-12)
    ys = [s.placement[1, 3] for s in plan.steps]
    assert ys == pytest.approx([0.085, -0.085] * 3 + [0.085], abs=1e-12)
    start_midpoint = 0.5 * (SOLE.center(LEFT0) + SOLE.center(RIGHT0))
    assert plan.final_midpoint() - start_midpoint == pytest.approx([1.2, 0.0, 0.0], abs=1e-12)
    assert plan.duration == pytest.approx(1.0 + 7 * 0.9 + 6 * 0.115 + 1.0, abs=1e-12)
    kinds = [p.kind for p in plan.phases]
    assert kinds == ["double"] + ["single", "double"] * 7
    assert [p.duration for p in plan.phases[1:4]] == pytest.approx([0.9, 0.115, 0.9])
    assert plan.phases[-1].duration == pytest.approx(1.0)
    assert plan.phases[1].swing_side == "left" and plan.phases[1].stance == ("right",)


def test_the_60cm_walk_and_the_half_step_options():
    plan = straight_walk(LEFT0, RIGHT0, length=0.6)
    assert plan.final_midpoint()[0] - SOLE.center(LEFT0)[0] == pytest.approx(3.6, abs=1e-12)
    # half_last off: the closing foot lands one length ahead instead of beside
    staggered = straight_walk(LEFT0, RIGHT0, steps=2, length=0.2, half_last=False, first_side="right")
    assert [s.placement[0, 3] for s in staggered.steps] == pytest.approx([0.2, 0.4, 0.6], abs=1e-12)
    assert [s.side for s in staggered.steps] == ["right", "left", "right"]
    # half_first off continues from there: every foot travels a full 0.4 m stride
    left, right = staggered.steps[1].placement, staggered.steps[2].placement
    resumed = straight_walk(left, right, steps=2, length=0.2, half_first=False)
    assert [s.placement[0, 3] for s in resumed.steps] == pytest.approx([0.8, 1.0, 1.0], abs=1e-12)


def test_lateral_walk_moves_the_leading_foot_first_and_keeps_the_width():
    plan = lateral_walk(LEFT0, RIGHT0, steps=2, length=-0.1)
    assert [s.side for s in plan.steps] == ["right", "left", "right", "left"]
    assert [s.placement[1, 3] for s in plan.steps] == pytest.approx([-0.185, -0.015, -0.285, -0.115], abs=1e-12)
    assert all(s.placement[0, 3] == pytest.approx(0.0, abs=1e-12) for s in plan.steps)
    assert plan.final_midpoint()[1] == pytest.approx(-0.2, abs=1e-12)


def test_turning_walk_yaws_the_feet_and_rotates_the_polygons():
    angle = 0.2
    plan = turning_walk(LEFT0, RIGHT0, steps=4, angle_per_step=angle, length=0.1)
    assert [s.side for s in plan.steps] == ["left", "right", "left", "right", "left"]
    assert [yaw_of(s.placement) for s in plan.steps] == pytest.approx([0.2, 0.4, 0.6, 0.8, 0.8], abs=1e-12)
    last_left, last_right = plan.steps[-1].placement, plan.steps[-2].placement
    lateral = np.array([-math.sin(0.8), math.cos(0.8), 0.0])
    assert (last_left - last_right)[:3, 3] == pytest.approx(0.17 * lateral, abs=1e-12)  # width kept across the path
    # single support on the right foot yawed by 0.4: its polygon's edge normals are the sole axes turned by 0.4
    time = plan.phases[5].start + 0.1
    assert plan.phases[5].stance == ("right",)
    normals, _ = plan.support_polygon(time)
    expected = [[math.cos(a + k * math.pi / 2), math.sin(a + k * math.pi / 2)] for a in [0.4] for k in range(4)]
    assert sorted(map(tuple, normals.round(12))) == sorted(map(tuple, np.round(expected, 12)))
    straight = straight_walk(LEFT0, RIGHT0, steps=4)
    flat = turning_walk(LEFT0, RIGHT0, steps=4, angle_per_step=0.0, length=0.2)
    assert all(np.allclose(a.placement, b.placement, atol=1e-12) for a, b in zip(straight.steps, flat.steps,
                                                                                 strict=True))


@pytest.mark.parametrize("plan", [
    straight_walk(LEFT0, RIGHT0),
    straight_walk(yaw_placement([1.0, 2.1, 0.0], 0.7), yaw_placement([1.1, 1.95, 0.0], 0.7), first_side="right"),
    turning_walk(LEFT0, RIGHT0, steps=5, angle_per_step=-0.25, length=0.15),
    lateral_walk(LEFT0, RIGHT0, steps=2, length=0.1, single_support=0.7, double_support=0.3),
], ids=["straight", "yawed", "turning", "lateral"])
def test_phases_tile_the_plan_and_the_zmp_reference_is_continuous_and_supported(plan):
    phases = plan.phases
    assert phases[0].start == 0.0 and phases[-1].end == plan.duration
    assert all(a.end == b.start for a, b in itertools.pairwise(phases))
    jumps = [np.abs(a.zmp_to - b.zmp_from).max() for a, b in itertools.pairwise(phases)]
    assert max(jumps) < 1e-9
    times = np.arange(-0.1, plan.duration + 0.5, 0.001)
    zmp = plan.zmp_reference(times)
    steps = np.abs(np.diff(zmp, axis=0)).max()
    fastest = max(np.abs(p.zmp_to - p.zmp_from).max() / p.duration for p in phases if p.duration > 0)
    assert steps <= fastest * 0.001 + 1e-12  # no jump: at most the steepest ramp's change per ms
    for time, point in zip(times, zmp, strict=True):  # every 1 ms sample
        assert inside(plan, time, point[None])[0] >= -1e-12
    assert zmp[0] == pytest.approx(phases[0].zmp_from[:2], abs=1e-15)
    assert zmp[-1] == pytest.approx(plan.final_midpoint()[:2], abs=1e-12)


def test_zmp_reference_values_in_each_kind_of_phase():
    plan = straight_walk(LEFT0, RIGHT0)
    right_centre = SOLE.center(RIGHT0)[:2]
    midpoint = 0.5 * (SOLE.center(LEFT0) + SOLE.center(RIGHT0))[:2]
    assert plan.zmp_reference([0.5])[0] == pytest.approx(0.5 * (midpoint + right_centre), abs=1e-12)
    assert plan.zmp_reference([1.4])[0] == pytest.approx(right_centre, abs=1e-12)  # first single support
    first_left = SOLE.center(plan.steps[0].placement)[:2]
    middle_ds = 1.9 + 0.115 / 2
    assert plan.zmp_reference([middle_ds])[0] == pytest.approx(0.5 * (right_centre + first_left), abs=1e-12)


def test_polygons_hold_the_soles_on_the_ground_and_the_margin_shrinks_them():
    plan = straight_walk(LEFT0, RIGHT0)
    left, right = SOLE.corners(LEFT0), SOLE.corners(RIGHT0)
    assert inside(plan, 0.5, np.vstack([left, right])).min() == pytest.approx(0.0, abs=1e-12)  # DS: both, on edges
    single = 1.5  # the left foot swings, the right one stands
    assert inside(plan, single, right).min() == pytest.approx(0.0, abs=1e-12)
    assert (inside(plan, single, left) < -0.03).all()  # the lifted sole is outside
    normals, offsets = plan.support_polygon(single)
    assert len(offsets) == 4 and np.linalg.norm(normals, axis=1) == pytest.approx(np.ones(4))
    centre = SOLE.center(RIGHT0)[None]
    assert inside(plan, single, centre)[0] == pytest.approx(0.069, abs=1e-12)
    assert inside(plan, single, centre, margin=0.02)[0] == pytest.approx(0.049, abs=1e-12)
    with pytest.raises(ValueError, match="leaves nothing"):
        plan.support_polygon(single, margin=0.069)
    assert inside(plan, single, centre, margin=0.0689)[0] == pytest.approx(1e-4, abs=1e-12)
    with pytest.raises(ValueError, match="margin must be >= 0"):
        plan.support_polygon(single, margin=-0.01)
    double = 1.95  # double support with the left foot 0.2 m ahead: a six-sided hull
    assert len(plan.support_polygon(double)[1]) == 6


def test_queries_before_during_and_after_the_plan():
    plan = straight_walk(LEFT0, RIGHT0)
    assert plan.phase_at(-1.0)[0] == 0 and plan.phase_at(-1.0)[2] == 0.0
    assert plan.phase_at(0.5)[2] == pytest.approx(0.5)
    index, phase, progress = plan.phase_at(1.45)
    assert (index, phase.kind, progress) == (1, "single", pytest.approx(0.5))
    assert plan.phase_at(100.0)[0] == len(plan.phases) - 1 and plan.phase_at(100.0)[2] == 1.0
    assert set(plan.stance_placements(1.45)) == {"right"}
    assert set(plan.stance_placements(0.2)) == {"left", "right"}
    assert plan.foot_placement("left", 1.45) is plan.initial_left  # swinging: where it lifted off
    assert plan.foot_placement("left", 1.95)[0, 3] == pytest.approx(0.2)  # touched down
    final = plan.stance_placements(100.0)
    assert final["left"][0, 3] == pytest.approx(1.2) and final["right"][0, 3] == pytest.approx(1.2)


def test_a_zero_double_support_is_never_the_current_phase():
    plan = straight_walk(LEFT0, RIGHT0, steps=2, double_support=0.0, initial_double_support=0.0)
    touch_down = plan.phases[1].end
    assert plan.phases[2].duration == 0.0
    index, phase, progress = plan.phase_at(touch_down)
    assert (index, phase.kind, phase.swing_side, progress) == (3, "single", "right", 0.0)
    # without an initial double support the ZMP reference starts on the stance foot: it jumps at 0
    assert plan.phase_at(0.0)[:1] == (1,) and plan.phase_at(-0.5)[::2] == (0, 0.0)
    midpoint = 0.5 * (SOLE.center(LEFT0) + SOLE.center(RIGHT0))[:2]
    zmp = plan.zmp_reference([-0.5, 0.0, touch_down - 1e-9, touch_down])
    assert zmp[0] == pytest.approx(midpoint) and zmp[1] == pytest.approx(SOLE.center(RIGHT0)[:2])
    assert zmp[2] == pytest.approx(SOLE.center(RIGHT0)[:2])
    assert zmp[3] == pytest.approx(SOLE.center(plan.steps[0].placement)[:2])


def test_invalid_plans_name_the_step():
    steps = list(straight_walk(LEFT0, RIGHT0, steps=2).steps)
    with pytest.raises(ValueError, match="step 1: side must be"):
        FootstepPlan(LEFT0, RIGHT0, (steps[0], Footstep("up", LEFT0, 0.9, 0.1), steps[2]), 1.0, 1.0)
    with pytest.raises(ValueError, match="step 0: single_support must be > 0"):
        FootstepPlan(LEFT0, RIGHT0, (Footstep("left", LEFT0, 0.0, 0.1), steps[2]), 1.0, 1.0)
    sheared = LEFT0.copy()
    sheared[0, 1] = 0.1
    with pytest.raises(ValueError, match="step 1: the placement's rotation"):
        FootstepPlan(LEFT0, RIGHT0, (steps[0], Footstep("left", sheared, 0.9, 0.1), steps[2]), 1.0, 1.0)
    with pytest.raises(ValueError, match="step 2: the double support after the last touch-down"):
        FootstepPlan(LEFT0, RIGHT0, tuple(steps), 1.0, 2.0)
    with pytest.raises(ValueError, match="final_double_support must be > 0"):
        FootstepPlan(LEFT0, RIGHT0, (Footstep("left", LEFT0, 0.9, 0.0),), 1.0, 0.0)
    with pytest.raises(ValueError, match="at least one footstep"):
        FootstepPlan(LEFT0, RIGHT0, (), 1.0, 1.0)
    with pytest.raises(ValueError, match="steps must be an integer"):
        straight_walk(LEFT0, RIGHT0, steps=0)


def test_plain_data_round_trip_and_errors():
    assert VALUE_TYPES["FootstepPlan"] is FootstepPlan
    plan = turning_walk(LEFT0, RIGHT0, steps=3, angle_per_step=0.3, length=0.1, sole=SoleShape(0.12, 0.1, 0.06))
    again = FootstepPlan.from_plain(plan.to_plain())
    assert again.to_plain() == plan.to_plain()
    assert again.zmp_reference(np.arange(0, 6, 0.01)) == pytest.approx(plan.zmp_reference(np.arange(0, 6, 0.01)))
    written = {"initial_left": {"position": [0, 0.085, 0]}, "initial_right": {"position": [0, -0.085, 0]},
               "initial_double_support": 1, "final_double_support": 1.5,
               "steps": [{"side": "left", "position": [0.2, 0.085, 0], "yaw": 0.1, "single_support": 0.9,
                          "double_support": 0.1},
                         {"side": "right", "position": [0.2, -0.085, 0], "yaw": 0.1, "single_support": 0.8}]}
    plan = FootstepPlan.from_plain(written)
    assert plan.final_double_support == 1.5 and plan.steps[-1].double_support == 1.5
    assert plan.start == 0.0 and FootstepPlan.from_plain({**written, "start": 2.5}).time(3.0) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="start must be >= 0"):
        FootstepPlan.from_plain({**written, "start": -1})
    assert yaw_of(plan.steps[1].placement) == pytest.approx(0.1) and plan.duration == pytest.approx(4.3)
    bad_side = {**written, "steps": [{**written["steps"][0], "side": "middle"}, written["steps"][1]]}
    with pytest.raises(ValueError, match="step 0: side must be"):
        FootstepPlan.from_plain(bad_side)
    with pytest.raises(ValueError, match="step 0: single_support is missing"):
        FootstepPlan.from_plain({**written, "steps": [{"side": "left", "position": [0, 0, 0]}]})
    with pytest.raises(ValueError, match="step 1: position must be"):
        FootstepPlan.from_plain({**written, "steps": [written["steps"][0], {"side": "left", "position": [0, 0],
                                                                                "single_support": 1}]})
    with pytest.raises(ValueError, match="needs final_double_support"):
        FootstepPlan.from_plain({k: v for k, v in written.items() if k != "final_double_support"})
    with pytest.raises(ValueError, match="unknown key"):
        FootstepPlan.from_plain({**written, "speed": 1})
    with pytest.raises(TypeError, match="must be a number"):
        FootstepPlan.from_plain({**written, "initial_double_support": "long"})
    with pytest.raises(TypeError, match="must be a mapping"):
        FootstepPlan.from_plain([1, 2])
