"""The robot and the training motion a problem names: registered names, or files relative to the problem file.

``robot`` (:data:`latentoc.robots.ROBOT`) and ``training`` (:data:`.demonstration.TRAINING`)
are checked as values when the file is loaded; :func:`check_problem_files` checks that the
files they name exist (at load time, naming the problem file), and :func:`problem_demonstration`
reads them: the robot, then the motion on it, the robot reduced to the joints the motion moves.
"""
from __future__ import annotations

from pathlib import Path

import pinocchio as pin

from latentoc.errors import ProblemError, SolveError
from latentoc.problem.declaration import Problem
from latentoc.robots.setting import describe_robot, robot_files, robot_from_setting
from latentoc.motions.demonstration import Demonstration, load_demonstration

__all__ = ["problem_dir", "problem_robot", "problem_demonstration", "check_problem_files", "require_fixed_base"]


def problem_dir(problem: Problem) -> Path:
    """The folder the problem's relative paths start from: its file's, else the working folder."""
    return Path(problem.source).parent if problem.source else Path(".")


def problem_robot(problem: Problem) -> pin.Model:
    """The robot the problem names (the full model, before the motion locks joints)."""
    return robot_from_setting(problem.robot, problem_dir(problem))


def problem_demonstration(problem: Problem) -> Demonstration:
    """The problem's training motion on its robot, all frames (:mod:`.demonstration`)."""
    return load_demonstration(problem.training, problem_robot(problem), problem_dir(problem))


def check_problem_files(problem: Problem, where: str) -> None:
    """A ProblemError naming the first file the problem's robot or training names that does not exist."""
    base = problem_dir(problem)
    files = [("robot", p) for p in robot_files(problem.robot, base)]
    if isinstance(problem.training, dict):
        files.append(("training", base / problem.training["file"]))
        if problem.training["asf"] is not None:
            files.append(("training.asf", base / problem.training["asf"]))
    for key, path in files:
        if not path.is_file():
            raise ProblemError(f"{where}: key '{key}': file {path} does not exist")


def require_fixed_base(model: pin.Model, robot: str | dict, kind: str) -> None:
    """A SolveError unless every joint of ``model`` has one coordinate (nq = nv, no free-flyer)."""
    multi = [f"{model.names[j]} ({model.joints[j].shortname()})" for j in range(1, model.njoints)
             if model.joints[j].nq != 1 or model.joints[j].nv != 1]
    if multi:
        raise SolveError(f"robot {describe_robot(robot)}: a {kind} problem needs a fixed-base robot whose moving "
                         f"joints have one coordinate each; {', '.join(multi)} do not (lock them with fixed_pose "
                         "by leaving them out of the motion file, or set free_flyer = false)")
