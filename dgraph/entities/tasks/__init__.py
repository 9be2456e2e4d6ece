"""Tasks: weighted acceleration-level task equations built from features."""

from dgraph.entities.tasks.equation import TaskEquation
from dgraph.entities.tasks.task import Task

__all__ = ["Task", "TaskEquation"]
