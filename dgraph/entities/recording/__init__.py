"""Recording: the Recorder entity (numpy columns saved as .npz, streamed to Rerun), the RobotView
(the robot in Rerun's 3D view) and the WalkingView (footprints, support polygon, ZMP, CoM and DCM
on the ground), sharing one Rerun recording per sink, with the blueprint (the viewer's layout) of
:mod:`~dgraph.entities.recording.layout`."""

from dgraph.entities.recording.layout import read_blueprint
from dgraph.entities.recording.recorder import Recorder
from dgraph.entities.recording.rerun_stream import open_stream, read_series
from dgraph.entities.recording.robot_view import RobotView
from dgraph.entities.recording.walking_view import WalkingView

__all__ = ["Recorder", "RobotView", "WalkingView", "open_stream", "read_blueprint", "read_series"]
