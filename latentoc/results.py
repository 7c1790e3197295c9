"""The result schema: :class:`Result`, its folder (``result.json``, ``trajectory.npz``, ``gpdm.npz``).

``result.json`` holds :data:`SCHEMA_VERSION` and the same core fields for every kind (problem,
kind, method, status, success, iterations, cost_initial, cost, gain_pct, cost_meaning, times,
tube, violations, environment, the problem's resolved settings), ``convergence`` (Ipopt's
per-iteration log of every phase and exchange round, :func:`convergence_entry`), then
``details``, the kind's own fields. ``trajectory.npz`` holds the arrays of :data:`TRAJECTORY_KEYS`, the one list of its
keys; ``gpdm.npz`` the GPDM the motion was optimised in (:meth:`latentoc.gpdm.GPDM.save`), so a
folder is self-contained: the plots read nothing else. The folder is written into a temporary
folder beside it and renamed into place (:func:`latentoc.runtime.files.write_folder`; into an existing
folder, the old ``result.json`` goes first and the new one comes last), and ``result.json``
records the SHA-256 of the other files (``checksums``), which :func:`load_result` verifies, so a
folder with a ``result.json`` is one complete write. JSON is strict: a non-finite number is the
string ``"NaN"``, ``"Infinity"`` or ``"-Infinity"``; every core field's type is checked on load.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.runtime.environment import Environment
from latentoc.errors import ResultFileError
from latentoc.arguments import expect
from latentoc.runtime.files import NPZ_ERRORS, dumps_json, json_number, plain, sha256, write_folder
from latentoc.gpdm import GPDM
from latentoc.problem.kinds import Solution
from latentoc.problem.declaration import Problem
from latentoc.latent.tube import TubeResult

__all__ = ["Result", "Times", "load_result", "SCHEMA_VERSION", "TRAJECTORY_KEYS",
           "RESULT_NAME", "TRAJECTORY_NAME", "GPDM_NAME", "convergence_entry",
           "HISTORY_KEYS", "result_and_output"]

SCHEMA_VERSION = 1
RESULT_NAME, TRAJECTORY_NAME, GPDM_NAME = "result.json", "trajectory.npz", "gpdm.npz"

#: every key of trajectory.npz: key -> what it holds (n = samples of the 1 kHz grid)
TRAJECTORY_KEYS: dict[str, str] = {
    # every kind
    "t": "time, s (n)",
    "q": "configuration (n x nq); a free-flyer base first",
    "v": "velocity (n x nv)",
    "a": "acceleration (n x nv)",
    "tau": "joint torques (n x nv, or n x (nv - 6) without the free-flyer base)",
    "model": "pinocchio.Model.saveToString() of the robot",
    # a latent solve (the arm's latent method, the broad jump)
    "x": "latent path (n x d)",
    "P": "spline control points: latent (m x d), or joint (m x nq) for the joint-range method",
    "sigma2": "GPDM variance along x (n), Eq. 19",
    "leg_residual": "the broad jump's residual on the legs' sagittal joints beside x, rad (n x r)",
    "leg_residual_control_points": "its spline's control points (m x r)",
    "leg_residual_joints": "the learned coordinates it is added to (r)",
    # the arm (latent-min-torque)
    "x_initial": "latent path of the training fit (n x d)",
    "P_initial": "control points of the training fit",
    "q_initial": "configuration along the training fit (n x nq)",
    # the broad jump: contacts and limits (latentoc.jump.check.export)
    "wrench": "toe-tip wrench of each (symmetric) foot, N and N m (n x 6)",
    "point_forces": "heel, ball, toe and pad forces of each foot (n x 4 x 2)",
    "point_lambda": "friction-pyramid edge weights, body weights (n x 8)",
    "force_correction": "largest change of the interpolated edge weights that balances the base rows (n)",
    "contact": "1 where the feet are on the ground (n)",
    "loaded": "1 where heel, ball, toe, pad carry load (n x 4)",
    "node_t": "contact node times, s",
    "node_wrench": "toe-tip wrench at the contact nodes",
    "node_lambda": "edge weights at the contact nodes",
    "contact_frames": "names of the contact frames",
    "contact_points": "names of the contact points (heel, ball, toe, pad)",
    "heel_offset": "heel point in its frame (contact_frames), m (3)",
    "ball_offset": "ball point in its frame, m (3)",
    "toe_offset": "toe tip in its frame, m (3)",
    "pad_offset": "the toes' pad point in the toe tip's frame, m (3)",
    "pad_setback": "how far the pad stands behind the toe tip, m: the centre of pressure's rear edge on the toes alone",
    "takeoff": "takeoff time, s",
    "touchdown": "touchdown time, s",
    "settle": "end of the landing's settling, s",
    "tau_min": "lower torque limits, N m (as tau's columns; where enforced)",
    "tau_max": "upper torque limits, N m (as tau's columns; where enforced)",
    # the enforced joint limits (latent-min-torque; a broad jump with limits = "urdf"): what the plots draw
    "q_min": "lower joint limits, rad (nq; -inf: none)",
    "q_max": "upper joint limits, rad (nq; inf: none)",
    "v_max": "velocity limits |v| <= v_max, rad/s (nv; inf: none)",
    "friction": "friction coefficient mu",
}
_REQUIRED_ARRAYS = ("t", "q", "v", "a", "tau", "model")

#: the per-iteration series of a convergence entry's history (Ipopt's log)
HISTORY_KEYS = ("iter", "objective", "inf_pr", "inf_du", "mu", "alpha_pr", "alpha_du")


def convergence_entry(phase: str, round: int, history: Mapping[str, Any]) -> dict[str, Any]:
    """One element of ``result.json``'s ``convergence``: Ipopt's per-iteration ``history``
    (:attr:`latentoc.nlp.ipopt.IpoptResult.history`) of one run, named by its ``phase`` and
    exchange ``round`` (1-based). A kind's result dict carries the list under the key
    ``"convergence"``."""
    return {"phase": str(phase), "round": int(round),
            "history": {k: [float(v) for v in history.get(k, [])] for k in HISTORY_KEYS}}


@dataclass(frozen=True)
class Times:
    """Wall times of one solve, s: GPDM learning (0 when reused), NLP build, block compilation, Ipopt
    (building its solver included), the 1 kHz checks and export, and the whole solve (these and the
    set-up between them)."""

    gpdm_s: float = 0.0
    build_s: float = 0.0
    compile_s: float = 0.0
    solve_s: float = 0.0
    check_s: float = 0.0
    total_s: float = 0.0


# the kind contract's result keys that become core fields (the rest are the kind's details)
_CORE_KEYS = ("problem", "kind", "method", "status", "success", "iterations", "cost_initial", "cost",
              "performance_gain_pct", "cost_meaning", "gpdm_time_s", "build_time_s", "compile_time_s",
              "solve_time_s", "check_time_s", "total_time_s", "tube_spec", "tube", "tube_relative", "tube_training", "max_sigma2", "violations",
              "convergence")


@dataclass
class Result:
    """One solved problem in the versioned result schema (module doc)."""

    problem: str
    kind: str
    method: str
    status: str
    success: bool
    iterations: int
    cost_initial: float
    cost: float
    gain_pct: float
    cost_meaning: str
    times: Times
    tube: TubeResult | None
    violations: dict[str, float]
    environment: Environment
    settings: dict[str, Any]
    details: dict[str, Any] = field(default_factory=dict)
    convergence: list[dict[str, Any]] = field(default_factory=list)  # convergence_entry per Ipopt run
    trajectory: dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    gpdm: GPDM | None = field(default=None, repr=False)
    warm: dict[str, Any] | None = field(default=None, repr=False)  # for a neighbouring tube; not saved
    schema_version: int = SCHEMA_VERSION

    @classmethod
    def from_solution(cls, solution: Solution, problem: Problem) -> Result:
        """A kind's :class:`~latentoc.problem.kinds.Solution` of ``problem`` in the schema."""
        r = solution.result
        unknown = set(solution.trajectory) - set(TRAJECTORY_KEYS)
        if unknown:
            raise KeyError(f"trajectory keys {sorted(unknown)} are not in latentoc.results.TRAJECTORY_KEYS")
        return cls(problem=r["problem"], kind=r["kind"], method=r["method"], status=r["status"],
                   success=bool(r["success"]), iterations=int(r["iterations"]),
                   cost_initial=float(r["cost_initial"]), cost=float(r["cost"]),
                   gain_pct=float(r["performance_gain_pct"]), cost_meaning=r["cost_meaning"],
                   times=Times(gpdm_s=r.get("gpdm_time_s", 0.0), build_s=r.get("build_time_s", 0.0),
                               check_s=r.get("check_time_s", 0.0), total_s=r.get("total_time_s", 0.0),
                               compile_s=r.get("compile_time_s", 0.0), solve_s=r["solve_time_s"]),
                   tube=TubeResult.from_result(r), violations={k: float(v) for k, v in r["violations"].items()},
                   environment=Environment.current(), settings=dict(problem.settings),
                   details={"source": problem.source, **{k: v for k, v in r.items() if k not in _CORE_KEYS}},
                   convergence=[convergence_entry(c["phase"], c["round"], c["history"]) for c in r.get("convergence", [])],
                   trajectory=dict(solution.trajectory), gpdm=solution.gpdm, warm=solution.warm)

    # ------------------------------------------------------------------ JSON and files
    def to_json(self) -> dict[str, Any]:
        """``result.json``'s content (JSON-ready) but the checksums of the files."""
        data: dict[str, Any] = {"schema_version": self.schema_version}
        for name in ("problem", "kind", "method", "status", "success", "iterations", "cost_initial", "cost",
                     "gain_pct", "cost_meaning"):
            data[name] = getattr(self, name)
        data.update(times=asdict(self.times), tube=None if self.tube is None else asdict(self.tube),
                    violations=self.violations, environment=asdict(self.environment), settings=self.settings,
                    convergence=self.convergence, details=self.details)
        return _plain(data)

    def files(self) -> dict[str, bytes]:
        """The folder's files by name: what :meth:`save` writes and a sweep task returns."""
        files = {TRAJECTORY_NAME: _npz_bytes({k: np.asarray(v) for k, v in self.trajectory.items()})}
        if self.gpdm is not None:
            files[GPDM_NAME] = _gpdm_bytes(self.gpdm)
        checksums = {name: sha256(data) for name, data in files.items()}
        files[RESULT_NAME] = dumps_json({**self.to_json(), "checksums": checksums}).encode()
        return files  # result.json last: written last, it marks the folder complete

    def save(self, out_dir: str | Path) -> list[Path]:
        """Write the folder (created if needed); returns the paths, result.json first."""
        return write_files(self.files(), out_dir)

    @classmethod
    def from_files(cls, files: Mapping[str, bytes], where: str = "result") -> Result:
        """Inverse of :meth:`files` (a :class:`ResultFileError` naming what is wrong): the
        checksums verified, every core field's type checked."""
        if RESULT_NAME not in files or TRAJECTORY_NAME not in files:
            raise ResultFileError(f"{where}: needs {RESULT_NAME} and {TRAJECTORY_NAME}")
        try:
            data = json.loads(files[RESULT_NAME], parse_constant=_no_constant)
        except (json.JSONDecodeError, UnicodeDecodeError, ValueError) as exc:
            raise ResultFileError(f"{where}: {RESULT_NAME} is not JSON: {exc}") from None
        version = data.get("schema_version") if isinstance(data, dict) else None
        if version != SCHEMA_VERSION:
            raise ResultFileError(f"{where}: {RESULT_NAME} has schema_version {version!r}; this latentoc "
                                  f"reads {SCHEMA_VERSION} (a result written by another version)")
        names = _verified(files, data.get("checksums"), where)
        try:
            with np.load(io.BytesIO(files[TRAJECTORY_NAME]), allow_pickle=False) as f:
                trajectory = {k: f[k] for k in f.files}
            gpdm = _gpdm_from_bytes(files[GPDM_NAME]) if GPDM_NAME in names else None
        except NPZ_ERRORS as exc:
            raise ResultFileError(f"{where}: unreadable arrays: {exc}") from None
        missing = [k for k in _REQUIRED_ARRAYS if k not in trajectory]
        if missing:
            raise ResultFileError(f"{where}: {TRAJECTORY_NAME} lacks {missing}")
        problem = _array_problem(trajectory)
        if problem is not None:
            raise ResultFileError(f"{where}: {TRAJECTORY_NAME}: {problem}")
        core = _typed(data, where)
        return cls(**core, trajectory=trajectory, gpdm=gpdm)


def _array_problem(traj: Mapping[str, np.ndarray]) -> str | None:
    """What is wrong with a trajectory's core arrays, or None: ``model`` a Pinocchio model string, ``t``
    finite and increasing, ``q`` (len(t) x nq), ``v``, ``a``, ``tau`` one row per time, all finite."""
    model = traj["model"]
    if model.ndim != 0 or model.dtype.kind != "U":
        return f"'model' must be one string (Pinocchio's saveToString), got {model.dtype} of shape {model.shape}"
    robot = pin.Model()
    try:
        robot.loadFromString(str(model))
    except (RuntimeError, ValueError) as exc:
        return f"'model' is not a Pinocchio model string ({exc})"
    t = traj["t"]
    if t.ndim != 1 or len(t) < 1 or t.dtype.kind not in "fi" or not np.isfinite(t).all() or (np.diff(t) <= 0).any():
        return "'t' must be finite, increasing times (one row per sample)"
    shapes = {"q": robot.nq, "v": robot.nv, "a": robot.nv}
    for key in ("q", "v", "a", "tau"):
        a = traj[key]
        if a.ndim != 2 or len(a) != len(t) or (key in shapes and a.shape[1] != shapes[key]):
            want = f"({len(t)}, {shapes[key]})" if key in shapes else f"({len(t)}, n)"
            return f"'{key}' has shape {a.shape}, the model and t need {want}"
        if a.dtype.kind not in "fi" or not np.isfinite(a).all():
            return f"'{key}' has values that are not finite numbers"
    return None


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not strict JSON")


def _verified(files: Mapping[str, bytes], checksums: Any, where: str) -> list[str]:
    """The names of the array files that belong to result.json: each one its ``checksums`` list,
    with the content recorded there (results written before checksums: the files present)."""
    if checksums is None:
        return [n for n in (TRAJECTORY_NAME, GPDM_NAME) if n in files]
    if not isinstance(checksums, dict) or TRAJECTORY_NAME not in checksums:
        raise ResultFileError(f"{where}: {RESULT_NAME}: key 'checksums' must map each array file to its SHA-256")
    for name, digest in checksums.items():
        if name not in files:
            raise ResultFileError(f"{where}: {name} is missing ({RESULT_NAME} lists it)")
        if sha256(files[name]) != digest:
            raise ResultFileError(f"{where}: {name} is not the file {RESULT_NAME} was written with (its SHA-256 "
                                  "differs: damaged, or left by another solve); solve again")
    return list(checksums)


def _text(v: Any) -> str:
    if not isinstance(v, str):
        raise ValueError
    return v


def _integer(v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise ValueError
    return v


def _flag(v: Any) -> bool:
    if not isinstance(v, bool):
        raise ValueError
    return v


def _dict(v: Any) -> dict:
    if not isinstance(v, dict):
        raise ValueError
    return v


def _spec(v: Any) -> float | str:
    return v if isinstance(v, str) else json_number(v)


_KINDS = {_text: "a string", _integer: "an integer", _flag: "true or false", _dict: "an object",
          json_number: "a number", _spec: "a number or a string"}
_CORE_TYPES: dict[str, Callable[[Any], Any]] = {
    "problem": _text, "kind": _text, "method": _text, "status": _text, "success": _flag, "iterations": _integer,
    "cost_initial": json_number, "cost": json_number, "gain_pct": json_number, "cost_meaning": _text,
    "times": _dict, "violations": _dict, "environment": _dict, "settings": _dict, "details": _dict}
_TUBE_TYPES = {"spec": _spec, "delta": json_number, "relative": json_number, "training": json_number,
               "max_sigma2": json_number}


def _typed(data: dict[str, Any], where: str) -> dict[str, Any]:
    """Result's fields from result.json, each checked: a ResultFileError naming the key."""
    def get(table: Mapping[str, Any], key: str, check: Callable[[Any], Any], name: str) -> Any:
        if key not in table:
            raise ResultFileError(f"{where}/{RESULT_NAME}: misses the field {name!r}")
        try:
            return check(table[key])
        except (TypeError, ValueError):
            raise ResultFileError(f"{where}/{RESULT_NAME}: key {name!r} must be {_KINDS[check]}, "
                                  f"got {table[key]!r}") from None

    out = {k: get(data, k, check, k) for k, check in _CORE_TYPES.items()}
    out["times"] = Times(**{f.name: get(out["times"], f.name, json_number, f"times.{f.name}")
                            for f in fields(Times) if f.name in out["times"]})
    out["violations"] = {k: get(out["violations"], k, json_number, f"violations.{k}") for k in out["violations"]}
    env = out["environment"]
    out["environment"] = Environment(**{f.name: get(env, f.name, _integer if f.type == "int" else _text,
                                                    f"environment.{f.name}")
                                        for f in fields(Environment) if f.name in env or f.name != "scipy"})
    convergence = data.get("convergence", [])  # results saved before it: none
    if not isinstance(convergence, list) or not all(isinstance(c, dict) for c in convergence):
        raise ResultFileError(f"{where}/{RESULT_NAME}: key 'convergence' must be a list of objects")
    out["convergence"] = convergence
    tube = data.get("tube")
    if tube is not None:
        tube = get(data, "tube", _dict, "tube")
        tube = TubeResult(**{k: get(tube, k, c, f"tube.{k}") for k, c in _TUBE_TYPES.items()})
    out["tube"] = tube
    return out


def load_result(out_dir: str | Path) -> Result:
    """Read a folder written by :meth:`Result.save` (a :class:`ResultFileError` if it cannot)."""
    expect("load_result", "out_dir", out_dir, (str, os.PathLike), "a result folder's path")
    out = Path(out_dir)
    if not (out / RESULT_NAME).is_file():
        raise ResultFileError(f"{out}: no {RESULT_NAME} (not a result folder, or a solve that did not finish)")
    names = [n for n in (RESULT_NAME, TRAJECTORY_NAME, GPDM_NAME) if (out / n).is_file()]
    try:
        files = {n: (out / n).read_bytes() for n in names}
    except OSError as exc:
        raise ResultFileError(f"{out}: cannot be read: {exc}") from None
    return Result.from_files(files, str(out))


_plain = plain  # JSON-ready values (latentoc.runtime.files.plain)


def result_and_output(result: Result | str | Path, out: str | Path | None, name: str, who: str) -> tuple[Result, Path]:
    """``result``, or the Result read from the folder a path names, and where ``who`` writes:
    ``out``, else ``name`` in that folder (a ValueError for a Result not read from a folder)."""
    if not isinstance(result, Result):
        folder = Path(result)
        result = load_result(folder)
        out = folder / name if out is None else out
    if out is None:
        raise ValueError(f"{who} needs the output path for a Result that was not read from a folder")
    return result, Path(out)


def _npz_bytes(arrays: dict[str, Any]) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def _gpdm_bytes(gpdm: GPDM) -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        gpdm.save(Path(tmp) / GPDM_NAME)
        return (Path(tmp) / GPDM_NAME).read_bytes()


def _gpdm_from_bytes(data: bytes) -> GPDM:
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / GPDM_NAME).write_bytes(data)
        return GPDM.load(Path(tmp) / GPDM_NAME)


def write_files(files: Mapping[str, bytes], out_dir: str | Path, marker: str = RESULT_NAME) -> list[Path]:
    """Write ``files`` (name -> content) as the folder ``out_dir``, all at once
    (:func:`latentoc.runtime.files.write_folder`, ``marker`` last); returns the paths, the marker first."""
    paths = write_folder(files, out_dir, marker, owned=(RESULT_NAME, TRAJECTORY_NAME, GPDM_NAME))
    return sorted(paths, key=lambda p: (p.name != marker, p.name != TRAJECTORY_NAME))
