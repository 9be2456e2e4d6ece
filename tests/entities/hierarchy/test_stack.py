"""Priority stack: the level editing functions and the solver's run-time commands in a running graph."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import dgraph as dg
from dgraph.control import RowBlock
from dgraph.entities.devices import KinematicDevice
from dgraph.entities.hierarchy import HierarchicalSolver
from dgraph.entities.hierarchy.stack import PriorityStack, initial_stack, moved, pushed


class FixedRows(dg.Entity):
    """``v[index] = target`` (one equality row), with an active input."""

    index = dg.Param(0, kind="int")
    target = dg.Param(0.0, kind="float")
    active = dg.Input(shape=(), dtype="bool", default=True)

    @dg.output(dtype=RowBlock)
    def rows(self, t):
        matrix = np.zeros((1, 6))
        matrix[0, self.index] = 1.0
        return RowBlock.equalities(matrix, np.array([self.target]), bool(self.active(t)))


def test_initial_stack_groups_equal_priorities_and_closes_gaps():
    assert initial_stack(["a", "b", "c"], []) == (("a",), ("b",), ("c",))
    assert initial_stack(["a", "b", "c"], [3, 0, 3]) == (("b",), ("a", "c"))


def test_pushed_and_moved():
    stack = (("a",), ("b", "c"), ("d",))
    assert pushed(stack, "e") == (("a",), ("b", "c"), ("d",), ("e",))
    assert pushed(stack, "e", 1) == (("a",), ("b", "c", "e"), ("d",))
    assert moved(stack, "d", -1) == (("a",), ("d",), ("b", "c"))  # alone: swaps with the level above
    assert moved(stack, "a", -1) == stack  # already on top
    assert moved(stack, "c", -1) == (("a",), ("c",), ("b",), ("d",))  # shared: its own level above
    assert moved(stack, "b", +1) == (("a",), ("c",), ("b",), ("d",))


@pytest.fixture
def graph():
    """Two conflicting tasks on v0 (+1 and -1) and one on v1, in a running graph."""
    g = dg.Graph(dt=0.01, name="stack_test")
    g.add(KinematicDevice("device", control_mode="velocity", size=6))
    g.add(FixedRows("plus", index=0, target=1.0), FixedRows("minus", index=0, target=-1.0),
          FixedRows("side", index=1, target=0.5))
    g.add(HierarchicalSolver("solver", model=pin.buildSampleModelManipulator(), tasks=["plus", "minus", "side"],
                             priorities=[0, 1, 2]))
    for name in ("plus", "minus", "side"):
        g.plug(f"{name}.rows", f"solver.{name}")
    g.plug("solver.velocity", "device.control")
    return g


def step(g):
    g.run(ticks=1)
    return g["device"].v.value


def test_push_remove_up_down_change_the_result_at_run_time(graph):
    solver = graph["solver"]
    assert step(graph)[:2] == pytest.approx([1.0, 0.5])  # "plus" wins over "minus"
    solver.up("minus")
    assert solver.levels() == [["minus"], ["plus"], ["side"]]
    assert step(graph)[:2] == pytest.approx([-1.0, 0.5])
    solver.remove("minus")
    assert step(graph)[:2] == pytest.approx([1.0, 0.5])
    solver.push("minus", 0)  # into the top level with "plus": least squares of +1 and -1
    assert step(graph)[:2] == pytest.approx([0.0, 0.5])
    solver.down("minus")
    assert solver.levels() == [["plus"], ["minus"], ["side"]]
    assert step(graph)[:2] == pytest.approx([1.0, 0.5])
    solver.remove("side")
    solver.push("side")  # re-pushed at the bottom: the same answer, no stale workspace
    assert step(graph)[:2] == pytest.approx([1.0, 0.5])
    graph["plus"].active.set(False)  # inactive: its level is empty this tick
    assert step(graph)[:2] == pytest.approx([-1.0, 0.5])
    graph["plus"].active.set(True)
    solver.clear()
    assert step(graph) == pytest.approx(np.zeros(6))  # only the minimum-norm level remains
    assert solver.solution.value.status == 0


def test_commands_name_the_solver_on_bad_requests(graph):
    solver = graph["solver"]
    with pytest.raises(dg.ParamError, match="solver: no task 'hand'"):
        solver.push("hand")
    with pytest.raises(dg.ParamError, match="already in the stack"):
        solver.push("plus")
    solver.remove("plus")
    with pytest.raises(dg.ParamError, match="not in the stack"):
        solver.up("plus")
    with pytest.raises(dg.ParamError, match="level 7 does not exist"):
        solver.push("plus", 7)


def test_a_stack_set_by_hand_is_checked_where_it_is_set_and_a_plugged_one_at_the_tick(graph):
    with pytest.raises(dg.SpecError, match=r"solver\.stack: expected levels of distinct task names .*'nope'") as info:
        graph["solver"].stack.set((("plus",), ("nope",)))
    assert (info.value.entity, info.value.signal) == ("solver", "stack")
    with pytest.raises(dg.SpecError, match=r"solver\.stack: expected levels of distinct task names"):
        graph["solver"].stack.set((("plus",), ("plus",)))

    class Stacks(dg.Entity):
        @dg.output(dtype=PriorityStack, depends=())
        def stack(self, t):
            return PriorityStack((("plus",), ("nope",)))

    graph.add(Stacks("stacks"))
    graph.plug("stacks.stack", "solver.stack")
    with pytest.raises(dg.SpecError, match=r"solver\.stack at tick 0: .*'nope'") as info:
        graph.run(ticks=1)
    assert (info.value.entity, info.value.signal) == ("solver", "stack")


def test_an_edited_stack_is_saved_and_loaded_back_as_a_stack():
    from dgraph.files import dumps, loads

    g = dg.Graph(dt=0.01, name="saved_stack")
    solver = g.add(HierarchicalSolver("solver", model="talos", tasks=["a", "b", "c"]))
    solver.down("a")
    saved = dumps(g)
    assert "solver.stack:\n  - [b]\n  - [a]\n  - [c]\n" in saved
    again = loads(saved)
    assert again["solver"].levels() == [["b"], ["a"], ["c"]] and dumps(again) == saved
    with pytest.raises(dg.GraphFileError, match=r"solver\.stack: cannot make a PriorityStack of 'b'"):
        loads(saved.replace("solver.stack:\n  - [b]\n  - [a]\n  - [c]", "solver.stack: b"))
    with pytest.raises(dg.GraphFileError, match=r"<string>:\d+ \[set\.solver\.stack\]: solver\.stack: expected "
                                                r"levels of distinct task names among \['a', 'b', 'c'\]"):
        loads(saved.replace("  - [c]", "  - [cc]"))  # a typo: refused at its line, not at tick 0
