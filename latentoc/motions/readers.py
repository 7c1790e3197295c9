"""Readers of recorded motions: CSV, NPZ and Acclaim ASF + AMC files, as raw samples.

Each reader returns a :class:`RawMotion`: time stamps, one column per named joint and, for every
sample, where it is in the file (line, row or frame), so that later checks can point at it. A
file that cannot be read is a :class:`MotionFileError` naming the file and the place.

* CSV: a header row with ``t`` and one column per joint (named as the robot's joints), then one
  row per sample; blank lines and lines starting with ``#`` are skipped.
* NPZ: arrays ``t`` (N) and ``q`` (N x k), optionally ``joint_names`` (k strings); without them
  the columns are the robot's configuration q in order (k = nq).
* AMC with its ASF skeleton: frames at ``fps`` mapped to the robot's joints ``<bone>_<dof>`` as
  the CMU humanoid's are (:func:`latentoc.mocap.motion_to_q`).
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError
from latentoc.runtime.files import NPZ_ERRORS
from latentoc.mocap import motion_to_q, read_amc, read_asf
from latentoc.mocap.skeleton_model import joint_q_index

__all__ = ["MotionFileError", "RawMotion", "read_csv", "read_npz", "read_amc_motion", "read_raw_motion",
           "FORMATS"]

FORMATS = ("csv", "npz", "amc")


class MotionFileError(LatentocError, ValueError):
    """A motion file that does not exist, cannot be read, or does not fit the robot."""


@dataclass
class RawMotion:
    """Samples as read: ``t`` (N), ``values`` (N x k) of the joints ``names`` (None: the robot's
    q in order), ``where[i]`` the place of sample i in the file (``line 12``, ``row 3``, ...)."""

    path: Path
    t: np.ndarray
    values: np.ndarray
    names: list[str] | None
    where: list[str]


def _number(text: str, path: Path, line: int, column: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise MotionFileError(f"{path}, line {line}, column {column!r}: not a number: {text!r}") from None


def read_csv(path: Path) -> RawMotion:
    """A CSV file with a header (``t`` and joint names) and one sample per row (module doc)."""
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark (spreadsheet exports) skipped
    except UnicodeDecodeError as exc:
        raise MotionFileError(f"{path}: not a text file ({exc})") from None
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        rows = [(reader.line_num, r) for r in reader
                if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    except csv.Error as exc:
        raise MotionFileError(f"{path}, line {reader.line_num}: not CSV ({exc})") from None
    if not rows:
        raise MotionFileError(f"{path}: empty; a motion CSV has a header (t and joint names) and one row per sample")
    header_line, header = rows[0]
    header = [h.strip() for h in header]
    if "t" not in header:
        raise MotionFileError(f"{path}, line {header_line}: the header has no column 't' (time, s); "
                              f"it has {', '.join(map(repr, header))}")
    seen = set()
    for h in header:
        if not h:
            raise MotionFileError(f"{path}, line {header_line}: an empty column name in the header")
        if h in seen:
            raise MotionFileError(f"{path}, line {header_line}: column {h!r} appears twice in the header")
        seen.add(h)
    if len(header) < 2:
        raise MotionFileError(f"{path}, line {header_line}: the header names no joint column besides 't'")
    data = np.empty((len(rows) - 1, len(header)))
    where = []
    for k, (line, row) in enumerate(rows[1:]):
        if len(row) != len(header):
            raise MotionFileError(f"{path}, line {line}: {len(row)} values, the header has {len(header)} columns")
        data[k] = [_number(c.strip(), path, line, h) for c, h in zip(row, header)]
        where.append(f"line {line}")
    it = header.index("t")
    names = [h for h in header if h != "t"]
    return RawMotion(path, data[:, it], np.delete(data, it, axis=1), names, where)


def read_npz(path: Path) -> RawMotion:
    """An NPZ file with ``t``, ``q`` and optionally ``joint_names`` (module doc)."""
    try:
        loaded = np.load(path, allow_pickle=False)
        single = not isinstance(loaded, np.lib.npyio.NpzFile)  # a .npy array under an .npz name
        if not single:
            with loaded as f:
                arrays = {k: f[k] for k in f.files}
    except NPZ_ERRORS as exc:
        raise MotionFileError(f"{path}: not a readable NPZ file ({type(exc).__name__}: {exc})") from None
    if single:
        raise MotionFileError(f"{path}: a single array (.npy), not an NPZ archive of t, q and joint_names "
                              "(numpy.savez writes one)")
    for key in ("t", "q"):
        if key not in arrays:
            raise MotionFileError(f"{path}: no array {key!r}; an NPZ motion has t (N), q (N x nq) and optionally "
                                  f"joint_names (it has {', '.join(map(repr, arrays)) or 'nothing'})")
    t, q = arrays["t"], arrays["q"]
    if not (np.issubdtype(t.dtype, np.number) and np.issubdtype(q.dtype, np.number)):
        raise MotionFileError(f"{path}: t and q must be numeric arrays, got {t.dtype} and {q.dtype}")
    if q.ndim != 2 or t.ndim != 1 or t.shape[0] != q.shape[0]:
        raise MotionFileError(f"{path}: t must have shape (N,) and q (N, k); got {t.shape} and {q.shape}")
    names = None
    if "joint_names" in arrays:
        jn = arrays["joint_names"]
        if jn.ndim != 1 or jn.dtype.kind not in "US" or len(jn) != q.shape[1]:
            raise MotionFileError(f"{path}: joint_names must be {q.shape[1]} strings (one per column of q), "
                                  f"got {jn.dtype} of shape {jn.shape}")
        names = [str(n) for n in jn]
        if len(set(names)) != len(names):
            raise MotionFileError(f"{path}: joint_names repeats a name: {names}")
    return RawMotion(path, t.astype(float), q.astype(float), names, [f"row {i}" for i in range(len(t))])


def read_amc_motion(path: Path, asf: Path, model: pin.Model, fps: float = 120.0) -> RawMotion:
    """AMC frames (at ``fps``) of the skeleton ``asf`` on the robot's joints ``<bone>_<dof>``: the
    columns are the joints of ``model`` the skeleton moves."""
    if not asf.is_file():
        raise MotionFileError(f"{path}: its skeleton {asf} does not exist")
    skeleton = read_asf(asf)
    motion = read_amc(path, skeleton, fps)
    jq = joint_q_index(model)
    names = [f"{b}_{d}" for b, bone in skeleton.bones.items() for d in bone.dof if f"{b}_{d}" in jq]
    if not names:
        raise MotionFileError(f"{path}: the skeleton {asf} moves none of the robot's joints "
                              f"({', '.join(list(jq)[:8])}, ...); its joints are named <bone>_<dof>")
    names.sort(key=lambda n: jq[n])
    Q = motion_to_q(model, skeleton, motion)
    values = Q[:, [jq[n] for n in names]]
    frames = motion.frame_numbers
    return RawMotion(path, np.arange(motion.n_frames) / float(fps), values, names,
                     [f"frame {int(n)}" for n in frames])


def read_raw_motion(path: Path, model: pin.Model, fmt: str | None = None, asf: Path | None = None,
                    fps: float = 120.0) -> RawMotion:
    """The samples of the motion file ``path`` (its format from ``fmt`` or the file's extension)."""
    if not path.is_file():
        raise MotionFileError(f"motion file {path} does not exist")
    fmt = fmt or path.suffix.lower().lstrip(".")
    if fmt == "csv":
        raw = read_csv(path)
    elif fmt == "npz":
        raw = read_npz(path)
    elif fmt == "amc":
        if asf is None:
            raise MotionFileError(f"{path}: an AMC motion needs its ASF skeleton (training key 'asf', CLI --asf)")
        raw = read_amc_motion(path, asf, model, fps)
    else:
        raise MotionFileError(f"{path}: unknown motion format {fmt!r}; latentoc reads {', '.join(FORMATS)} "
                              "(by the file's extension or the training key 'format')")
    if len(raw.t) < 2:
        raise MotionFileError(f"{path}: {len(raw.t)} samples; a motion needs at least 2")
    bad = ~np.isfinite(raw.values)
    bad_t = ~np.isfinite(raw.t)
    if bad_t.any():
        i = int(np.argmax(bad_t))
        raise MotionFileError(f"{path}, {raw.where[i]}: time t = {raw.t[i]} is not finite")
    if bad.any():
        i, j = (int(v) for v in np.argwhere(bad)[0])
        column = raw.names[j] if raw.names is not None else f"q[{j}]"
        kind = "NaN" if math.isnan(raw.values[i, j]) else "Inf"
        raise MotionFileError(f"{path}, {raw.where[i]}, column {column!r}: {kind} ({int(bad.sum())} values are "
                              "not finite)")
    return raw
