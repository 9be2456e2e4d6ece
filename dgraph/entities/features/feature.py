"""Feature: the base class of task-space features (error, its rate, Jacobian and drift)."""

from __future__ import annotations

import abc
from typing import Any

import numpy as np

import dgraph as dg
from dgraph.control.feature import FeatureValue
from dgraph.entities.constants import per_row_problem
from dgraph.entities.robot.robot_state import RobotState
from dgraph.entities.selection import Rows, contiguous


def parse_mask(entity: dg.Entity, mask: str, width: int) -> Rows:
    """Rows selected by a mask string such as ``"000111"``: ``None`` when all are selected, a
    slice when they are contiguous, else their indices."""
    if len(mask) != width or set(mask) - {"0", "1"} or "1" not in mask:
        raise dg.ParamError(f"{entity.name}: mask must be {width} characters 0/1 with at least one 1, "
                            f"got {mask!r}", entity=entity.name)
    return contiguous(np.flatnonzero([c == "1" for c in mask]), width)


class Feature(dg.Entity, abc.ABC):
    """Base of features: subclasses implement :meth:`evaluate` on the robot's shared state.

    Input: ``robot`` (the ``state`` output of a :class:`~dgraph.entities.robot.RobotModel`).
    Outputs: ``feature`` (a :class:`FeatureValue`, what a task plugs), ``error`` (``x (-) x*``)
    and ``error_velocity`` (for plots). Subclasses set ``self.size`` (rows after the mask,
    known before any tick: tasks check the lengths of their gains against it,
    :func:`feature_rows`) and ``self.rows`` (the :data:`Rows` of :meth:`evaluate`'s value that
    the mask keeps) in ``configure``.
    """

    robot = dg.Input(dtype=RobotState, doc="the RobotModel's shared state")

    @abc.abstractmethod
    def evaluate(self, state: RobotState, t: int) -> FeatureValue:
        """The feature at ``t`` before ``self.rows`` are selected (each feature type defines it)."""

    @dg.output(dtype=FeatureValue)
    def feature(self, t: int) -> FeatureValue:
        """Error, error rate, Jacobian, drift and reference acceleration (masked rows)."""
        return self.evaluate(self.robot(t), t).select(self.rows)

    @dg.output(shape=("size",), depends=("feature",))
    def error(self, t: int) -> np.ndarray:
        """``x (-) x*``."""
        return self.feature(t).error

    @dg.output(shape=("size",), depends=("feature",))
    def error_velocity(self, t: int) -> np.ndarray:
        """``x_dot - x_dot*``."""
        return self.feature(t).error_velocity


def feature_rows(inp: dg.Input) -> int | None:
    """The number of rows of the feature plugged into ``inp`` (a task's ``feature`` input), known
    before any tick: the ``size`` of the :class:`Feature` whose ``feature`` output is plugged;
    None if nothing is plugged or the source is not a Feature's ``feature``."""
    source = inp.source
    if source is None or source.name != "feature" or not isinstance(source.entity, Feature):
        return None
    return source.entity.size


def per_row_of_feature_problem(inp: dg.Input, value: Any) -> str | None:
    """What is wrong with the constant ``value`` of a gain that takes a scalar or one value per
    row of the feature plugged into ``inp`` (:func:`per_row_problem`), or None; None too while the
    rows are not known (:func:`feature_rows`)."""
    rows = feature_rows(inp)
    return None if rows is None else per_row_problem(value, rows, f"row of its feature {inp.source.full_name}")
