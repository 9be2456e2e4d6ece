"""Signals: time-stamped, lazily cached entity ports (see ``docs/design.md``)."""

from dgraph.signals.clock import Clock
from dgraph.signals.signal import Input, Output, Signal, State, commit_all, output, stage_views
from dgraph.signals.spec import Spec
from dgraph.signals.value_types import VALUE_TYPES, value_type

__all__ = ["VALUE_TYPES", "Clock", "Input", "Output", "Signal", "Spec", "State", "commit_all", "output", "stage_views",
           "value_type"]
