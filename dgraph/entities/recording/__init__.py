"""Recording: the Recorder entity (numpy columns saved as .npz, streamed to Rerun)."""

from dgraph.entities.recording.recorder import Recorder
from dgraph.entities.recording.rerun_stream import read_series

__all__ = ["Recorder", "read_series"]
