"""Training motions: registered names and the user's recorded files (CSV, NPZ, ASF + AMC), read
(:mod:`.readers`), resampled and checked against the robot (:mod:`.demonstration`), and the robot
and motion a problem names (:mod:`.problem_inputs`)."""

from latentoc.motions.demonstration import (TRAINING, TRAINING_MOTIONS, Demonstration, check_frames, demonstration_from_file,
                                            load_demonstration, one_dof_joints)
from latentoc.motions.readers import MotionFileError

__all__ = ["Demonstration", "TRAINING", "TRAINING_MOTIONS", "demonstration_from_file", "load_demonstration",
           "one_dof_joints", "check_frames", "MotionFileError"]
