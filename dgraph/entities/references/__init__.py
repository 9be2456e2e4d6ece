"""Reference generators: signals that are functions of time (constants: ``operators.Constant``)."""

from dgraph.entities.references.drilling import DrillingSequence
from dgraph.entities.references.minimum_jerk import MinimumJerk
from dgraph.entities.references.pulse import Pulse
from dgraph.entities.references.sinusoid import Sinusoid
from dgraph.entities.references.trajectory_file import TrajectoryFile

__all__ = ["DrillingSequence", "MinimumJerk", "Pulse", "Sinusoid", "TrajectoryFile"]
