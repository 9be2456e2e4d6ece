"""Tasks: weighted acceleration-level tasks built from features, and the force task."""

from dgraph.entities.tasks.force_task import ForceTask
from dgraph.entities.tasks.task import Task

__all__ = ["ForceTask", "Task"]
