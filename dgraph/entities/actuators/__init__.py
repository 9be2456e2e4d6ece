"""Actuator chains (thesis Ch. 3): the chain's model, its heating, its protection, its identification."""

from dgraph.entities.actuators.actuator_model import ActuatorModel
from dgraph.entities.actuators.chain import TALOS_ELBOW, ChainParameters, friction
from dgraph.entities.actuators.identification import Identification, Payload, identify
from dgraph.entities.actuators.protection import TorqueProtection
from dgraph.entities.actuators.thermal_model import ThermalModel

__all__ = ["TALOS_ELBOW", "ActuatorModel", "ChainParameters", "Identification", "Payload", "ThermalModel",
           "TorqueProtection", "friction", "identify"]
