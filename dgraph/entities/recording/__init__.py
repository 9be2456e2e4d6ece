"""Recording: the Recorder entity (numpy columns saved as .npz, streamed to Rerun)."""
