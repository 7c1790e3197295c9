"""Writing and reading a solved problem: ``result.json`` and ``trajectory.npz``.

Both files are written atomically: to a temporary file in the output folder, then
``os.replace``d into place, so a reader never sees a half-written file.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .solve import Solution

__all__ = ["write_solution", "read_solution", "atomic_write", "RESULT_NAME", "TRAJECTORY_NAME"]

RESULT_NAME = "result.json"
TRAJECTORY_NAME = "trajectory.npz"


def _json_default(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def atomic_write(path: Path, write: Callable[[Any], None], binary: bool = False) -> None:
    """Call ``write(file)`` on a temporary file next to ``path``, then move it into place."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb" if binary else "w") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_json(path: Path, data: Any) -> None:
    """Atomically write ``data`` as indented JSON."""
    atomic_write(Path(path), lambda f: json.dump(data, f, indent=2, default=_json_default, allow_nan=True))


def write_solution(solution: Solution, out_dir: str | Path) -> tuple[Path, Path]:
    """Write ``result.json`` and ``trajectory.npz`` into ``out_dir`` (created if needed)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    traj_path, result_path = out / TRAJECTORY_NAME, out / RESULT_NAME
    arrays = {k: np.asarray(v) for k, v in solution.trajectory.items()}
    atomic_write(traj_path, lambda f: np.savez(f, **arrays), binary=True)
    write_json(result_path, solution.result)
    return result_path, traj_path


def read_solution(out_dir: str | Path) -> Solution:
    """Read a folder written by :func:`write_solution`."""
    out = Path(out_dir)
    result = json.loads((out / RESULT_NAME).read_text())
    with np.load(out / TRAJECTORY_NAME, allow_pickle=False) as f:
        trajectory = {k: f[k] for k in f.files}
    return Solution(result=result, trajectory=trajectory)
