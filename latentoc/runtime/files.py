"""Files latentoc writes: atomic files and folders, output checks, strict JSON, checksums.

* :func:`atomic_write`: a file is written under a temporary name beside it, then renamed.
* :func:`write_folder`: a result folder is written into a temporary folder beside the target
  and renamed into place; into an existing folder, its ``marker`` file (``result.json``) is
  removed first and written last, so at no moment does a folder claim a mixture of two writes;
  writers into the same parent folder take turns (an exclusive lock on the parent), so two
  processes saving into one folder leave one whole write, the last.
* :func:`exclusive_lock`: processes take turns on a folder or a lock file (result folders, the
  compiled-library cache).
* :func:`check_out_dir`: ``--out`` must be a folder (or not exist yet) that can be written,
  checked before any work.
* :func:`dumps_json`: strict JSON (no ``NaN``/``Infinity`` tokens): a non-finite float is the
  string ``"NaN"``, ``"Infinity"`` or ``"-Infinity"``, read back by :func:`json_number`;
  :func:`write_json` writes it atomically.
"""
from __future__ import annotations

import glob
import hashlib
import json
import math
import os
import shutil
import tempfile
import zipfile
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from latentoc.errors import LatentocError

__all__ = ["OutputError", "NPZ_ERRORS", "atomic_write", "write_folder", "check_out_dir", "exclusive_lock", "dumps_json", "write_json",
           "plain", "json_number", "sha256", "NON_FINITE"]

#: what reading a damaged, truncated, empty or foreign .npz raises (numpy, zipfile, json)
NPZ_ERRORS: tuple[type[BaseException], ...] = (OSError, ValueError, KeyError, TypeError, EOFError,
                                               AttributeError, zipfile.BadZipFile)


class OutputError(LatentocError):
    """An output folder or file that cannot be written (a file where a folder must be, no permission)."""


_UMASK = os.umask(0)
os.umask(_UMASK)


def atomic_write(path: Path, write: Callable[[Any], None], binary: bool = False) -> None:
    """Call ``write(file)`` on a temporary file next to ``path``, then move it into place."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb" if binary else "w") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp's files are private; results are not
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _write_bytes(path: Path, data: bytes) -> None:
    atomic_write(path, lambda f: f.write(data), binary=True)


def sha256(data: bytes) -> str:
    """The hex SHA-256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


def check_out_dir(path: str | Path, what: str = "--out") -> Path:
    """``path`` as an output folder: an OutputError unless it is a folder, or does not exist and its
    nearest existing parent is a folder, that this process can write (checked before any work: a
    dangling link, a name longer than the file system takes, a folder it refuses to write in)."""
    out = Path(path)
    if out.is_symlink() and not out.exists():
        raise OutputError(f"{what} {out} is a symbolic link to {os.readlink(out)}, which does not exist")
    if out.exists() and not out.is_dir():
        raise OutputError(f"{what} {out} is a file, not a folder")
    probe = out
    while not probe.exists():
        if probe.is_symlink():
            raise OutputError(f"{what} {out}: {probe} is a symbolic link to {os.readlink(probe)}, which does not exist")
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise OutputError(f"{what} {out}: {probe} is a file, not a folder")
    try:
        longest = os.pathconf(probe, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        longest = 255
    made = [p for p in (out, *out.parents) if not p.exists()]  # out and the parents to create
    too_long = [p for p in made if len(os.fsencode(p.name)) + (_TMP_EXTRA if p == out else 0) > longest]
    if too_long:
        raise OutputError(f"{what} {str(out)[:200]}: the name {too_long[0].name[:60]!r}... is "
                          f"{len(os.fsencode(too_long[0].name))} bytes; this file system takes "
                          f"{longest - _TMP_EXTRA} here")
    try:  # os.access says yes to root everywhere, also where nothing can be made (/proc)
        os.rmdir(tempfile.mkdtemp(prefix=".latentoc-probe.", dir=probe))
    except OSError as exc:
        raise OutputError(f"{what} {out}: the folder {probe} is not writable ({exc.strerror})") from None
    return out


#: the bytes a temporary folder's name adds to the output folder's (".NAME.PID.XXXXXXXX.tmp")
_TMP_EXTRA = 24


def write_folder(files: Mapping[str, bytes], out_dir: str | Path, marker: str, owned: tuple[str, ...] = ()
                 ) -> list[Path]:
    """Write ``files`` (name -> content) as the folder ``out_dir`` (module doc), ``marker`` last; an
    existing folder's ``owned`` files that ``files`` lacks are removed. Returns the paths in
    ``files``' order; an OSError becomes an OutputError naming the folder."""
    out = check_out_dir(out_dir, "output folder")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.{os.getpid()}.", suffix=".tmp", dir=out.parent))
    except OSError as exc:
        raise OutputError(f"cannot write {out}: {exc}") from None
    names = sorted(files, key=lambda n: n == marker)  # the marker last
    try:
        for name in names:
            _write_bytes(tmp / name, files[name])
        os.chmod(tmp, 0o777 & ~_UMASK)
        with exclusive_lock(out.parent):  # writers into one parent take turns
            _remove_abandoned(out)
            try:
                os.rename(tmp, out)  # the target did not exist: the whole folder at once
            except OSError:
                if not out.is_dir():
                    raise
                _replace_into(tmp, out, names, marker, owned)
    except OSError as exc:
        raise OutputError(f"cannot write {out}: {exc}") from None
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return [out / n for n in files]


def _remove_abandoned(out: Path) -> None:
    """Remove the temporary folders of ``out`` whose writer is gone (killed while writing)."""
    for tmp in out.parent.glob(f".{glob.escape(out.name)}.*.tmp"):
        pid = tmp.name[len(out.name) + 2:].split(".", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            shutil.rmtree(tmp, ignore_errors=True)
        except OSError:  # alive, another user's
            pass


@contextmanager
def exclusive_lock(path: Path) -> Iterator[None]:
    """Hold an exclusive advisory lock on ``path``, a folder or a lock file (created if missing):
    POSIX flock, released on exit, also when the process dies; without fcntl (Windows) no lock."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover
        yield
        return
    fd = os.open(path, os.O_RDONLY) if path.is_dir() else os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _replace_into(tmp: Path, out: Path, names: list[str], marker: str, owned: tuple[str, ...]) -> None:
    """Move the files of ``tmp`` into the existing folder ``out``: the old marker removed first,
    the new one moved last; stale ``owned`` files removed, the folder's others (plots) left alone."""
    for name in (marker, *owned):
        if name == marker or name not in names:
            (out / name).unlink(missing_ok=True)
    for name in names:
        os.replace(tmp / name, out / name)


def _finite_or_text(v: float) -> float | str:
    if math.isfinite(v):
        return v
    return "NaN" if math.isnan(v) else ("Infinity" if v > 0 else "-Infinity")


#: the strings :func:`dumps_json` writes for non-finite floats
NON_FINITE = {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}


def plain(value: Any) -> Any:
    """JSON-ready: numpy scalars and arrays as Python values, non-finite floats as strings."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, np.generic):
        return plain(value.item())
    if isinstance(value, float):
        return _finite_or_text(value)
    return value


def dumps_json(data: Any) -> str:
    """Strict, indented JSON of ``data`` (module doc)."""
    return json.dumps(plain(data), indent=2, allow_nan=False) + "\n"


def write_json(path: Path, data: Any) -> None:
    """Atomically write ``data`` as indented, strict JSON."""
    atomic_write(Path(path), lambda f: f.write(dumps_json(data)))


def json_number(value: Any) -> float:
    """A number of a strict-JSON file as a float (``"NaN"``, ``"Infinity"`` included); a
    ValueError for anything else (a bool, a string, null)."""
    if isinstance(value, str) and value in NON_FINITE:
        return NON_FINITE[value]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"must be a number, got {value!r}")
    return float(value)
