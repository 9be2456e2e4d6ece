"""Devices: the entities whose state closes the control loop."""

from dgraph.entities.devices.kinematic import KinematicDevice

__all__ = ["KinematicDevice"]
