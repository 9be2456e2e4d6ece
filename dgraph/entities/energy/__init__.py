"""Energy: the global energy tank of a passive inverse-dynamics controller (thesis Ch. 5)."""

from dgraph.entities.energy.tank import EnergyBudget, EnergyTank

__all__ = ["EnergyBudget", "EnergyTank"]
