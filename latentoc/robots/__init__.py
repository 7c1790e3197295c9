"""Robot models: by name (:mod:`.catalog`), the user's URDF (:mod:`.urdf`) or ASF skeleton, a problem
file's ``robot`` (:mod:`.setting`), the human models of the paper (:mod:`.human_models`,
:mod:`.human_arm`, and :mod:`.cmu_humanoid`, the symmetrised one the jump uses) and the physics
checks of a user's model (:mod:`.robot_checks`)."""

from latentoc.robots.catalog import UnknownRobotError, example_robot_data_dir, load_robot, robot_names, robot_urdf
from latentoc.robots.setting import ROBOT, describe_robot, robot_files, robot_from_setting
from latentoc.robots.urdf import RobotFileError, continuous_as_revolute, load_urdf

__all__ = ["load_robot", "robot_names", "robot_urdf", "example_robot_data_dir", "UnknownRobotError", "RobotFileError",
           "ROBOT", "load_urdf", "robot_from_setting", "robot_files", "describe_robot", "continuous_as_revolute"]
