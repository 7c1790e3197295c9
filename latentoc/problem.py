"""Problem declarations: what to optimise, never how (the solver code lives in
:mod:`latentoc.solve`).

A problem is a TOML file in ``problems/`` (``arm-raise`` -> ``problems/arm-raise.toml``)
or any path to a ``.toml`` file. Layout (every key optional except the top four)::

    name = "arm-raise"            # defaults to the file stem
    description = "..."
    kind = "latent-min-torque"    # which solver in latentoc.solve.SOLVERS handles it
    robot = "human-arm"           # latentoc.robots.load_robot name
    training = "human-arm-trial"  # a name of TRAINING_MOTIONS
    duration = 2.9                # s (Table 1)
    seed = 0

    [latent]                      # Sect. 3.2-3.3
    dim = 3                       # latent dimension d
    control_points = 9            # m
    spline_degree = 3
    boundary = "rest"             # "rest": fix p1, p2, p(m-1), pm (poses + zero end velocity)
                                  # "pose": fix p1, pm only (end poses)
    tube = "1.5x"                 # delta: a number (units of sigma^2) or "<k>x" = k * tube_training

    [transcription]
    quadrature_points = 8         # Gauss-Legendre nodes per knot interval (objective)
    constraint_points = 24        # tube/joint-limit nodes per knot interval (+ the breakpoints)
    joint_limits = true           # model.lowerPositionLimit <= q <= upper on the constraint grid
    torque_limits = []            # [] none, [s] every joint |tau| <= s, or one per joint (N m)

    [solver]
    hessian = "exact"             # "exact" | "lbfgs"
    max_iter = 300
    tol = 1e-8

    [gpdm]                        # GPDMSettings fields, plus:
    training_stride = 1           # use every k-th training frame for learning

    [baseline]                    # full configuration-space baseline (Sect. 4.1.1)
    joint_range_deg = 45.0

    [sweep]
    tubes = ["1x", "2x"]          # numbers or "<k>x" strings
    ranges = [5, 10]              # baseline joint ranges, degrees

    [start_poses]                 # Sect. 4.1.4
    tubes = ["1x", "2x"]
    frame = "lhand_end"

    [options]                     # free-form, read by the problem kind's solver

Errors are :class:`ProblemError` naming the file, the key and what is wrong.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .paths import data_dir

__all__ = ["Problem", "ProblemError", "load_problem", "problem_names", "problems_dir",
           "TRAINING_MOTIONS", "PROBLEM_KINDS", "parse_tube", "training_motion"]


class ProblemError(ValueError):
    """A problem declaration that cannot be used (file, key and reason in the message)."""


def _arm_trial() -> tuple[np.ndarray, np.ndarray]:
    from .human_models import arm_training_motion
    return arm_training_motion()


def _broad_jump() -> tuple[np.ndarray, np.ndarray]:
    from .human_models import broad_jump_training_motion
    return broad_jump_training_motion()


#: Named training motions: name -> () -> (t [N], Q [N x nq]).
TRAINING_MOTIONS: dict[str, Callable[[], tuple[np.ndarray, np.ndarray]]] = {
    "human-arm-trial": _arm_trial,
    "cmu-broad-jump": _broad_jump,
}

#: Problem kinds the package knows (a solver for each is registered in latentoc.solve.SOLVERS).
PROBLEM_KINDS: set[str] = {"latent-min-torque", "broad-jump"}

_GPDM_KEYS = {"balanced": bool, "outer_iterations": int, "max_iterations": int, "init": str,
              "seed": int, "kappa_sq": float, "log_hyper_bound": float, "gtol": float,
              "training_stride": int, "beta3_max": float}


@dataclass
class Problem:
    """A motion optimisation problem as declared by the user (see module docstring)."""

    name: str
    kind: str
    robot: str
    training: str
    duration: float
    description: str = ""
    seed: int = 0
    # [latent]
    latent_dim: int = 3
    control_points: int = 9
    spline_degree: int = 3
    boundary: str = "rest"
    tube: float | str = "1.5x"
    # [transcription]
    quadrature_points: int = 8
    constraint_points: int = 24
    joint_limits: bool = True
    torque_limits: list[float] = field(default_factory=list)
    # [solver]
    hessian: str = "exact"
    max_iter: int = 300
    tol: float = 1e-8
    # [gpdm]
    gpdm: dict[str, Any] = field(default_factory=dict)
    # [baseline]
    joint_range_deg: float = 45.0
    # [sweep]
    sweep_tubes: list[float | str] = field(default_factory=lambda: ["1x", "2x", "5x"])
    sweep_ranges: list[float] = field(default_factory=lambda: [5.0, 10.0, 20.0])
    # [start_poses]
    start_pose_tubes: list[float | str] = field(default_factory=lambda: ["1x", "2x", "5x"])
    start_pose_frame: str = "lhand_end"
    # [options]
    options: dict[str, Any] = field(default_factory=dict)
    source: str = ""

    def to_dict(self) -> dict[str, Any]:
        """Every field as JSON-ready data."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @property
    def training_stride(self) -> int:
        return int(self.gpdm.get("training_stride", 1))


# (toml table or "" for top level, key) -> (Problem field, checker)
def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_num(v: Any) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool)) and math.isfinite(v)


def _tube_ok(v: Any) -> bool:
    try:
        parse_tube(v)
    except ValueError:
        return False
    return True


_CHECKS: dict[str, tuple[str, Callable[[Any], bool], str]] = {
    "name": ("name", lambda v: isinstance(v, str) and v != "", "a non-empty string"),
    "description": ("description", lambda v: isinstance(v, str), "a string"),
    "kind": ("kind", lambda v: isinstance(v, str), "a string"),
    "robot": ("robot", lambda v: isinstance(v, str), "a string"),
    "training": ("training", lambda v: isinstance(v, str), "a string"),
    "duration": ("duration", lambda v: _is_num(v) and v > 0, "a positive number (s)"),
    "seed": ("seed", _is_int, "an integer"),
    "latent.dim": ("latent_dim", lambda v: _is_int(v) and v >= 1, "a positive integer"),
    "latent.control_points": ("control_points", lambda v: _is_int(v) and v >= 2, "an integer >= 2"),
    "latent.spline_degree": ("spline_degree", lambda v: _is_int(v) and v >= 1, "a positive integer"),
    "latent.boundary": ("boundary", lambda v: v in ("rest", "pose"), '"rest" or "pose"'),
    "latent.tube": ("tube", _tube_ok, 'a positive number or a relative spec like "1.5x"'),
    "transcription.quadrature_points": ("quadrature_points", lambda v: _is_int(v) and 1 <= v <= 20,
                                        "an integer in 1..20"),
    "transcription.constraint_points": ("constraint_points", lambda v: _is_int(v) and v >= 1,
                                        "a positive integer"),
    "transcription.joint_limits": ("joint_limits", lambda v: isinstance(v, bool), "true or false"),
    "transcription.torque_limits": ("torque_limits",
                                    lambda v: isinstance(v, list) and all(_is_num(s) and s > 0 for s in v),
                                    "a list of positive numbers (N m)"),
    "solver.hessian": ("hessian", lambda v: v in ("exact", "lbfgs"), '"exact" or "lbfgs"'),
    "solver.max_iter": ("max_iter", lambda v: _is_int(v) and v >= 1, "a positive integer"),
    "solver.tol": ("tol", lambda v: _is_num(v) and v > 0, "a positive number"),
    "baseline.joint_range_deg": ("joint_range_deg", lambda v: _is_num(v) and v > 0, "a positive number (deg)"),
    "sweep.tubes": ("sweep_tubes", lambda v: isinstance(v, list) and all(_tube_ok(s) for s in v),
                    'a list of tubes (numbers or "<k>x")'),
    "sweep.ranges": ("sweep_ranges", lambda v: isinstance(v, list) and all(_is_num(s) and s > 0 for s in v),
                     "a list of positive numbers (deg)"),
    "start_poses.tubes": ("start_pose_tubes", lambda v: isinstance(v, list) and all(_tube_ok(s) for s in v),
                          'a list of tubes (numbers or "<k>x")'),
    "start_poses.frame": ("start_pose_frame", lambda v: isinstance(v, str), "a frame name"),
}
_TABLES = {"latent", "transcription", "solver", "baseline", "sweep", "start_poses", "gpdm", "options"}


def parse_tube(spec: float | int | str) -> tuple[float, bool]:
    """A tube spec as (value, relative): ``1e-3`` -> (1e-3, False); ``"1.5x"`` -> (1.5, True).

    Raises ValueError for anything else, zero or negative values.
    """
    if isinstance(spec, bool):
        raise ValueError(f"tube {spec!r} is not a number")
    if isinstance(spec, (int, float)):
        value, relative = float(spec), False
    elif isinstance(spec, str):
        s = spec.strip().lower()
        relative = s.endswith("x")
        try:
            value = float(s[:-1] if relative else s)
        except ValueError:
            raise ValueError(f'tube {spec!r} is neither a number nor a relative spec like "1.5x"') from None
    else:
        raise ValueError(f"tube {spec!r} is not a number")
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"tube {spec!r} must be positive (delta bounds sigma^2 >= 0 from above)")
    return value, relative


def problems_dir() -> Path:
    """The folder of the packaged problem declarations."""
    return data_dir("problems")


def problem_names() -> list[str]:
    """Names of the packaged problems (file stems of ``problems/*.toml``)."""
    return sorted(p.stem for p in problems_dir().glob("*.toml"))


def _resolve(name_or_path: str | Path) -> Path:
    text = str(name_or_path)
    path = Path(text)
    if text.endswith(".toml") or path.is_file() or "/" in text:
        if not path.is_file():
            raise ProblemError(f"problem file {text} does not exist")
        return path
    candidate = problems_dir() / f"{text}.toml"
    if not candidate.is_file():
        raise ProblemError(f"unknown problem {text!r}; known problems: {', '.join(problem_names())}")
    return candidate


def load_problem(name_or_path: str | Path) -> Problem:
    """Read a problem by name (``problems/<name>.toml``) or path, validating every key."""
    from .robots import robot_names

    path = _resolve(name_or_path)
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ProblemError(f"{path}: not valid TOML: {exc}") from None
    values: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            if key not in _TABLES:
                raise ProblemError(f"{path}: unknown table [{key}]; known tables: {', '.join(sorted(_TABLES))}")
            if key == "options":
                values["options"] = dict(value)
                continue
            if key == "gpdm":
                for k, v in value.items():
                    if k not in _GPDM_KEYS:
                        raise ProblemError(f"{path}: unknown key gpdm.{k}; known: {', '.join(sorted(_GPDM_KEYS))}")
                    want = _GPDM_KEYS[k]
                    ok = (_is_num(v) if want is float else _is_int(v) if want is int else isinstance(v, want))
                    if not ok or (k == "training_stride" and v < 1):
                        raise ProblemError(f"{path}: key gpdm.{k} must be {want.__name__}"
                                           f"{' >= 1' if k == 'training_stride' else ''}, got {v!r}")
                values["gpdm"] = dict(value)
                continue
            items = [(f"{key}.{k}", v) for k, v in value.items()]
        else:
            items = [(key, value)]
        for full, v in items:
            if full not in _CHECKS:
                raise ProblemError(f"{path}: unknown key {full!r}")
            attr, check, what = _CHECKS[full]
            if not check(v):
                raise ProblemError(f"{path}: key {full!r} must be {what}, got {v!r}")
            values[attr] = float(v) if attr in ("duration", "tol", "joint_range_deg") else v
    for required in ("kind", "robot", "training", "duration"):
        if required not in values:
            raise ProblemError(f"{path}: missing key {required!r}")
    if values["kind"] not in PROBLEM_KINDS:
        raise ProblemError(f"{path}: key 'kind': unknown kind {values['kind']!r}; known: {', '.join(sorted(PROBLEM_KINDS))}")
    if values["robot"] not in robot_names():
        raise ProblemError(f"{path}: key 'robot': unknown robot {values['robot']!r}; known: {', '.join(robot_names())}")
    if values["training"] not in TRAINING_MOTIONS:
        raise ProblemError(f"{path}: key 'training': unknown training motion {values['training']!r}; "
                           f"known: {', '.join(sorted(TRAINING_MOTIONS))}")
    values.setdefault("name", path.stem)
    problem = Problem(**values, source=str(path))
    if problem.control_points < problem.spline_degree + 1:
        raise ProblemError(f"{path}: key 'latent.control_points' = {problem.control_points} is fewer than "
                           f"spline_degree + 1 = {problem.spline_degree + 1}")
    return problem


def training_motion(problem: Problem) -> tuple[np.ndarray, np.ndarray]:
    """The problem's training motion (t, Q), subsampled by ``gpdm.training_stride``."""
    t, Q = TRAINING_MOTIONS[problem.training]()
    k = problem.training_stride
    idx = np.arange(0, len(t), k)
    if idx[-1] != len(t) - 1:
        idx = np.append(idx, len(t) - 1)  # keep the goal pose
    return np.asarray(t)[idx], np.asarray(Q)[idx]
