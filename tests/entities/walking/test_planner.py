"""FootstepPlanner: the robot's standing soles, the walks it builds, plan time, parameter errors."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.entities.robot.loading import load_model
from dgraph.entities.walking.footsteps import FootstepPlan, SoleShape
from dgraph.entities.walking.planner import FootstepPlanner
from dgraph.files import loads
from tests.conftest import Ticker


def half_sitting_soles() -> tuple[np.ndarray, np.ndarray]:
    """TALOS's sole placements at the SRDF half-sitting, the base lowered so the lower sole is at z = 0."""
    model = load_model("talos")
    data = model.createData()
    q = np.array(model.referenceConfigurations["half_sitting"])
    pin.framesForwardKinematics(model, data, q)
    ids = [model.getFrameId(f) for f in ("left_sole_link", "right_sole_link")]
    q[2] -= min(data.oMf[i].translation[2] for i in ids)
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[ids[0]].homogeneous, data.oMf[ids[1]].homogeneous


def test_initial_placements_are_talos_soles_at_half_sitting_on_the_floor():
    planner = FootstepPlanner("planner")
    left, right = half_sitting_soles()
    assert np.abs(planner.initial_left - left).max() < 1e-9
    assert np.abs(planner.initial_right - right).max() < 1e-9
    plan = planner.plan(0)
    assert plan.initial_left == pytest.approx(left, abs=1e-9) and plan.initial_right == pytest.approx(right, abs=1e-9)
    for sole in (plan.initial_left, plan.initial_right):
        assert abs(sole[2, 3]) < 1e-3 and np.abs(SoleShape().corners(sole)[:, 2]).max() < 1e-3
    assert left[1, 3] - right[1, 3] == pytest.approx(0.17, abs=1e-3)  # the §1.4 width


def test_initial_placements_are_the_soles_of_the_mujoco_robot_at_tick_0():
    from dgraph_sim.device import MujocoDevice

    graph = dg.Graph(dt=0.001)
    device = graph.add(MujocoDevice("sim"))
    planner = graph.add(FootstepPlanner("planner"))
    model, data = device.mj_model, device.data
    for side, placement in (("left", planner.initial_left), ("right", planner.initial_right)):
        geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"leg_{side}_6_link_sole")
        rotation = data.geom_xmat[geom].reshape(3, 3)
        bottom_centre = data.geom_xpos[geom] - rotation[:, 2] * model.geom_size[geom][2]
        assert np.abs(bottom_centre - SoleShape().center(placement)).max() < 1e-3
        assert np.abs(rotation - placement[:3, :3]).max() < 1e-3
        assert abs(bottom_centre[2]) < 1e-3


def test_the_default_walk_and_the_plan_time():
    graph = dg.Graph(dt=0.001)
    graph.add(Ticker("clock"))
    planner = graph.add(FootstepPlanner("planner", start=0.5))
    plan = planner.plan(0)
    assert isinstance(plan, FootstepPlan) and len(plan.steps) == 7
    start_x = plan.initial_left[0, 3]
    assert [s.placement[0, 3] - start_x for s in plan.steps] == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.2])
    assert plan.final_midpoint()[0] - SoleShape().center(plan.initial_left)[0] == pytest.approx(1.2, abs=1e-9)
    assert plan.start == 0.5  # the plan carries it to the entities that follow it
    assert planner.time(0) == pytest.approx(-0.5) and planner.time(1500) == pytest.approx(1.0)
    graph.run(ticks=20)
    assert planner.plan(20) is plan and planner.outputs["plan"].count == 1


def test_each_walk_reads_its_parameters():
    turning = FootstepPlanner("turn", walk="turning", steps=4, angle_per_step=0.1, single_support=0.8)
    plan = turning.plan(0)
    assert [s.side for s in plan.steps] == ["left", "right", "left", "right", "left"]
    assert np.arctan2(plan.steps[-1].placement[1, 0], plan.steps[-1].placement[0, 0]) == pytest.approx(0.4)
    assert plan.phases[1].duration == pytest.approx(0.8)
    lateral = FootstepPlanner("side", walk="lateral", steps=2, length=-0.05, width=0.2).plan(0)
    middle = 0.5 * (lateral.initial_left[1, 3] + lateral.initial_right[1, 3])
    assert [s.side for s in lateral.steps] == ["right", "left", "right", "left"]
    assert [s.placement[1, 3] - middle for s in lateral.steps] == pytest.approx([-0.15, 0.05, -0.2, 0.0])


def test_explicit_footsteps_take_the_parameters_as_default_durations():
    footsteps = [{"side": "right", "position": [0.1, -0.085, 0.0], "yaw": -0.1, "double_support": 0.3},
                 {"side": "left", "position": [0.1, 0.085, 0.0], "single_support": 1.2}]
    plan = FootstepPlanner("explicit", walk="explicit", footsteps=footsteps, single_support=0.7,
                           final_double_support=2.0).plan(0)
    assert [(s.single_support, s.double_support) for s in plan.steps] == [(0.7, 0.3), (1.2, 2.0)]
    assert plan.duration == pytest.approx(1.0 + 0.7 + 0.3 + 1.2 + 2.0)
    assert np.arctan2(plan.steps[0].placement[1, 0], plan.steps[0].placement[0, 0]) == pytest.approx(-0.1)


def test_a_graph_file_lists_footsteps():
    graph = loads("""
name: plan
dt: 0.001
entities:
  planner:
    type: FootstepPlanner
    params:
      walk: explicit
      footsteps:
        - {side: left, position: [0.15, 0.085, 0.0]}
        - {side: right, position: [0.15, -0.085, 0.0], yaw: 0.0}
""")
    plan = graph["planner"].plan(0)
    assert [s.placement[0, 3] for s in plan.steps] == pytest.approx([0.15, 0.15])


@pytest.mark.parametrize(("params", "parameter", "reason"), [
    ({"walk": "lateral"}, "length", "needs it"),
    ({"walk": "turning"}, "angle_per_step", "needs it"),
    ({"walk": "explicit"}, "footsteps", "needs it"),
    ({"angle_per_step": 0.1}, "angle_per_step", "not used by walk 'straight'"),
    ({"walk": "lateral", "length": 0.1, "half_first": False}, "half_first", "not used"),
    ({"single_support": 0.0}, "single_support", "must be > 0"),
    ({"final_double_support": 0.0}, "final_double_support", "must be > 0"),
    ({"width": -0.1}, "width", "must be > 0"),
    ({"walk": "explicit", "footsteps": [{"side": "left", "position": [0, 0]}]}, "footsteps", "step 0: position"),
    ({"walk": "explicit", "footsteps": [{"side": "left", "position": [0] * 3}, {"side": "up", "position": [1, 0, 0]}]},
     "footsteps", "step 1: side must be"),
    ({"walk": "explicit", "footsteps": {"side": "left"}}, "footsteps", "expected a list"),
    ({"left_frame": "left_sole"}, "left_frame", "no frame"),
])
def test_bad_parameters_are_param_errors_naming_the_parameter(params, parameter, reason):
    with pytest.raises(dg.ParamError, match=f"planner.*{parameter}.*{reason}") as error:
        FootstepPlanner("planner", **params)
    assert error.value.entity == "planner"
