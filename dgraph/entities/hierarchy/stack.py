"""The priority stack of a hierarchical solver and its run-time commands (push, remove, up, down)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import dgraph as dg
from dgraph.signals.value_types import value_type


@value_type
class PriorityStack(tuple):
    """The levels of a priority stack, highest priority first; each level is a tuple of task
    names (which tasks exist is checked by the solver that reads it, :meth:`StackCommands.read_stack`)."""

    __slots__ = ()

    def __new__(cls, levels: Any = ()) -> PriorityStack:
        """Levels from any iterable of iterables of names (a graph file's lists, tuples)."""
        stack = super().__new__(cls, (tuple(level) for level in levels))
        if not all(isinstance(task, str) for level in stack for task in level):
            raise TypeError("every level must be a list of task names")
        return stack

    @classmethod
    def from_plain(cls, value: Any) -> PriorityStack:
        """The stack a graph file or ``--set`` writes: a list of levels, each a list of names."""
        if isinstance(value, str) or any(isinstance(level, str) for level in value):
            raise TypeError("expected a list of levels, each a list of task names")
        return cls(value)


def initial_stack(tasks: Sequence[str], priorities: Sequence[int]) -> PriorityStack:
    """Levels from one priority per task (0 highest; equal priorities share a level; gaps are
    closed). Without priorities, each task is its own level, in order."""
    priorities = list(priorities) if priorities else list(range(len(tasks)))
    order = sorted(set(priorities))
    return PriorityStack(tuple(t for t, p in zip(tasks, priorities, strict=True) if p == level) for level in order)


def _without(stack: PriorityStack, task: str) -> PriorityStack:
    """``stack`` with ``task`` taken out (an emptied level disappears)."""
    return PriorityStack(kept for level in stack if (kept := tuple(t for t in level if t != task)))


def _level_of(stack: PriorityStack, task: str) -> int:
    return next(i for i, level in enumerate(stack) if task in level)


def pushed(stack: PriorityStack, task: str, level: int | None = None) -> PriorityStack:
    """``task`` added as a new lowest level, or into the existing ``level``."""
    if level is None or level == len(stack):
        return PriorityStack((*stack, (task,)))
    return PriorityStack((*lv, task) if i == level else lv for i, lv in enumerate(stack))


def moved(stack: PriorityStack, task: str, direction: int) -> PriorityStack:
    """``task`` one priority up (``direction = -1``) or down (``+1``): alone on its level, that
    level swaps with its neighbour; sharing a level, the task leaves it for a new level of its
    own just above (below) it. At the top (bottom) of the stack nothing changes."""
    index = _level_of(stack, task)
    levels = list(stack)
    if len(stack[index]) > 1:
        levels[index] = tuple(t for t in stack[index] if t != task)
        levels.insert(index if direction < 0 else index + 1, (task,))
    elif 0 <= index + direction < len(levels):
        levels[index], levels[index + direction] = levels[index + direction], levels[index]
    return PriorityStack(levels)


class StackCommands:
    """Mixin for a solver entity with a ``tasks`` parameter (its task inputs) and a ``stack``
    input (a :class:`PriorityStack`, declared by :meth:`declare_stack`): the commands edit the stack
    between ticks, the solver reads it each tick (a change makes the solution recompute).

    Commands: ``push(task, level=None)`` (a new lowest level, or into level ``level``),
    ``remove(task)``, ``up(task)``, ``down(task)`` (see :func:`moved`), ``clear()``,
    ``levels()`` (the current stack as lists).
    """

    def declare_stack(self, priorities: Sequence[int]) -> None:
        """Declare the ``stack`` input, by default the levels given by ``priorities``."""
        if priorities and len(priorities) != len(self.tasks):
            raise dg.ParamError(f"{self.name}: {len(priorities)} priorities for {len(self.tasks)} tasks",
                                entity=self.name)
        if any(p < 0 for p in priorities):
            raise dg.ParamError(f"{self.name}: priorities must be >= 0", entity=self.name)
        self._checked_stack: Any = None
        self.declare("stack", dg.Input(dtype=PriorityStack, default=initial_stack(self.tasks, priorities),
                                       doc="priority levels, highest first (tuples of task names)"))

    def _known(self, task: str) -> str:
        if task not in self.tasks:
            raise dg.ParamError(f"{self.name}: no task {task!r}; its tasks are {list(self.tasks)}", entity=self.name)
        return task

    def _in_stack(self, task: str) -> bool:
        return any(self._known(task) in level for level in self.stack.value)

    @dg.command
    def push(self, task: str, level: int | None = None) -> None:
        """Add ``task`` at the bottom of the stack (a new lowest level), or into level ``level``."""
        stack = self.stack.value
        if self._in_stack(task):
            raise dg.ParamError(f"{self.name}: task {task!r} is already in the stack", entity=self.name)
        if level is not None and not 0 <= level <= len(stack):
            raise dg.ParamError(f"{self.name}: level {level} does not exist (the stack has {len(stack)})",
                                entity=self.name)
        self.stack.set(pushed(stack, task, level))

    @dg.command
    def remove(self, task: str) -> None:
        """Take ``task`` out of the stack (its input stays plugged; push it back to use it)."""
        self._require(task)
        self.stack.set(_without(self.stack.value, task))

    @dg.command
    def up(self, task: str) -> None:
        """Raise ``task`` by one priority."""
        self._require(task)
        self.stack.set(moved(self.stack.value, task, -1))

    @dg.command
    def down(self, task: str) -> None:
        """Lower ``task`` by one priority."""
        self._require(task)
        self.stack.set(moved(self.stack.value, task, +1))

    @dg.command
    def clear(self) -> None:
        """Empty the stack."""
        self.stack.set(PriorityStack())

    @dg.command
    def levels(self) -> list[list[str]]:
        """The current levels, highest priority first."""
        return [list(level) for level in self.stack.value]

    def _require(self, task: str) -> None:
        if not self._in_stack(task):
            raise dg.ParamError(f"{self.name}: task {task!r} is not in the stack", entity=self.name)

    def constant_problem(self, name: str, value: Any) -> str | None:
        """A stack set as a constant (a graph file's, a command's) is checked where it is set."""
        return self._stack_problem(value) if name == "stack" else None

    def _stack_problem(self, stack: PriorityStack) -> str | None:
        """What is wrong with ``stack`` (unknown or repeated task names), or None."""
        names = [task for level in stack for task in level]
        if len(set(names)) != len(names) or not set(names) <= set(self.tasks):
            return f"expected levels of distinct task names among {list(self.tasks)}, got {stack!r}"
        return None

    def read_stack(self, t: int) -> PriorityStack:
        """``stack(t)`` (a :class:`PriorityStack`: the input's type), checked once per value:
        known task names, each at most once (``SpecError`` otherwise)."""
        stack = self.stack(t)
        if stack is not self._checked_stack:
            problem = self._stack_problem(stack)
            if problem is not None:
                raise dg.SpecError(f"{self.name}.stack at tick {t}: {problem}", entity=self.name, signal="stack")
            self._checked_stack = stack
        return stack
