"""Robot models: the Pinocchio pass shared by features, tasks, contacts and solvers."""

from dgraph.entities.robot.loading import load_model, load_robot
from dgraph.entities.robot.model import RobotModel
from dgraph.entities.robot.robot_state import RobotState

__all__ = ["RobotModel", "RobotState", "load_model", "load_robot"]
