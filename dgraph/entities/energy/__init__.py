"""Energy: the global energy tank of a passive inverse-dynamics controller (thesis Ch. 5)."""

from dgraph.entities.energy.tank import EnergyTank, TankStage

__all__ = ["EnergyTank", "TankStage"]
