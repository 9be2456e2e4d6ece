"""Evaluation of recorded runs (thesis §4.4.3): pure functions over arrays, one row per tick.

numpy only, no entity and no robotics library: a recording (the Recorder's .npz columns, or
Rerun series read back) is evaluated the same way whatever the scenario (standing, swaying,
walking). Nothing in the core imports this package.
"""

from dgraph.evaluation.energy import cost_of_transport, mechanical_energy, path_length
from dgraph.evaluation.passivity import passivity_gait_measure, rms_torque
from dgraph.evaluation.timing import TickStatistics, tick_statistics
from dgraph.evaluation.tracking import TrackingError, tracking_error
from dgraph.evaluation.walking import (
    ForceJump,
    PhasePassivity,
    before_fall,
    contact_switch_force_jumps,
    first_fall,
    jerk_statistics,
    phase_passivity,
    polygon_margin,
)

__all__ = ["ForceJump", "PhasePassivity", "TickStatistics", "TrackingError", "before_fall",
           "contact_switch_force_jumps", "cost_of_transport", "first_fall", "jerk_statistics", "mechanical_energy",
           "passivity_gait_measure", "path_length", "phase_passivity", "polygon_margin", "rms_torque",
           "tick_statistics", "tracking_error"]
