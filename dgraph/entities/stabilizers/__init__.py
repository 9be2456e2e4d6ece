"""Balance stabilisers of the position-controlled schemes: measured ZMP, DCM control, CoM admittance."""

from dgraph.entities.stabilizers.dcm_admittance import DcmAdmittance
from dgraph.entities.stabilizers.lipm import divergent_component, lipm_zmp, natural_frequency
from dgraph.entities.stabilizers.zmp import ZmpEstimator, point_force, world_wrench, zero_moment_point

__all__ = ["DcmAdmittance", "ZmpEstimator", "divergent_component", "lipm_zmp", "natural_frequency", "point_force",
           "world_wrench", "zero_moment_point"]
