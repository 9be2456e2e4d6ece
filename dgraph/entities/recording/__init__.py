"""Recording: the Recorder entity (numpy columns saved as .npz, streamed to Rerun) and the
RobotView (the robot in Rerun's 3D view), sharing one Rerun recording per sink, with the blueprint
(the viewer's layout) of :mod:`~dgraph.entities.recording.layout`."""

from dgraph.entities.recording.layout import read_blueprint
from dgraph.entities.recording.recorder import Recorder
from dgraph.entities.recording.rerun_stream import open_stream, read_series
from dgraph.entities.recording.robot_view import RobotView

__all__ = ["Recorder", "RobotView", "open_stream", "read_blueprint", "read_series"]
