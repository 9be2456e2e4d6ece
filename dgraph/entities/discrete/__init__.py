"""Discrete-time state entities: their output is a State, so they may close a loop."""

from dgraph.entities.discrete.configuration_integrator import ConfigurationIntegrator
from dgraph.entities.discrete.delay import Delay
from dgraph.entities.discrete.integrator import Integrator

__all__ = ["ConfigurationIntegrator", "Delay", "Integrator"]
