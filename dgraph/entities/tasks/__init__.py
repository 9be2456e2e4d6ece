"""Tasks: weighted acceleration-level task equations built from features."""

from dgraph.entities.tasks.equation import TaskEquation
from dgraph.entities.tasks.force_task import ForceTask
from dgraph.entities.tasks.task import Task

__all__ = ["ForceTask", "Task", "TaskEquation"]
