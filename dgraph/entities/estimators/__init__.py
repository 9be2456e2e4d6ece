"""Estimators: the robot state (base pose and velocity, joints) from sensors, behind ``q`` / ``v`` ports."""

from dgraph.entities.estimators.contact_detector import ContactDetector
from dgraph.entities.estimators.external_force import ExternalForce
from dgraph.entities.estimators.floating_base import FloatingBaseEstimator
from dgraph.entities.estimators.foot_contact import FootContactState
from dgraph.entities.estimators.ground_truth import GroundTruthEstimator

__all__ = ["ContactDetector", "ExternalForce", "FloatingBaseEstimator", "FootContactState", "GroundTruthEstimator"]
