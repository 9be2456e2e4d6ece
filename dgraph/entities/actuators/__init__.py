"""Actuator chains (thesis Ch. 3): the chain's model, its heating, its protection, its identification."""

from dgraph.entities.actuators.chain import TALOS_ELBOW, ChainParameters, friction

__all__ = ["TALOS_ELBOW", "ChainParameters", "friction"]
