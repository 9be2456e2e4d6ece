"""Features: task-space quantities (error, rate, Jacobian, drift) computed from the robot state."""

from dgraph.entities.features.angular_momentum import AngularMomentum
from dgraph.entities.features.center_of_mass import CenterOfMass
from dgraph.entities.features.feature import Feature
from dgraph.entities.features.frame_pose import FramePose
from dgraph.entities.features.joint_posture import JointPosture

__all__ = ["AngularMomentum", "CenterOfMass", "Feature", "FramePose", "JointPosture"]
