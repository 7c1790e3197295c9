"""Reader for Acclaim motion files (AMC), ``:FULLY-SPECIFIED`` as in the CMU database."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from latentoc.mocap.asf import Skeleton
from latentoc.mocap.format_errors import MocapFormatError, parse_number


@dataclass
class Motion:
    """Per-bone channel arrays of shape (n_frames, n_dof), values as in the file.

    Angles stay in degrees (or whatever the file uses); the root array holds the
    6 values in the root ``order`` of the skeleton (TX TY TZ RX RY RZ for CMU).
    """

    n_frames: int
    channels: dict[str, np.ndarray]
    frame_numbers: np.ndarray
    fps: float = 120.0
    degrees: bool = True
    path: str | None = None
    header: list[str] = field(default_factory=list)

    @property
    def duration(self) -> float:
        """Duration in seconds between first and last frame."""
        return (self.n_frames - 1) / self.fps

    def __getitem__(self, bone: str) -> np.ndarray:
        return self.channels[bone]


def _expected_counts(skeleton: Skeleton) -> dict[str, int]:
    counts = {"root": len(skeleton.root.order)}
    for nm, b in skeleton.bones.items():
        counts[nm] = len(b.dof)
    return counts


def parse_amc(text: str, skeleton: Skeleton, path: str | Path | None = None,
              fps: float = 120.0) -> Motion:
    """Parse AMC text against ``skeleton``.

    Every frame must give each bone with dofs (and the root) exactly once, with as many
    values as the bone has dofs; anything else raises :class:`MocapFormatError`.
    """
    p = None if path is None else str(path)
    counts = _expected_counts(skeleton)
    needed = {k for k, v in counts.items() if v > 0}
    frames: list[dict[str, list[float]]] = []
    frame_numbers: list[int] = []
    frame_start_line: list[int] = []
    header: list[str] = []
    degrees = True
    cur: dict[str, list[float]] | None = None
    last_ln = 0

    def close(ln: int) -> None:
        if cur is None:
            return
        missing = needed - set(cur)
        if missing:
            raise MocapFormatError(p, ln, f"frame {frame_numbers[-1]} lacks bones {sorted(missing)}")

    for ln, raw in enumerate(text.splitlines(), start=1):
        last_ln = ln
        s = raw.split("#", 1)[0].strip()
        if not s:
            continue
        if s.startswith(":"):
            if frames:
                raise MocapFormatError(p, ln, "header keyword after the first frame")
            kw = s.split()[0].upper()
            if kw == ":RADIANS":
                degrees = False
            elif kw not in (":FULLY-SPECIFIED", ":DEGREES"):
                raise MocapFormatError(p, ln, f"unknown keyword {s.split()[0]!r}")
            header.append(s)
            continue
        toks = s.split()
        if len(toks) == 1 and toks[0].isascii() and toks[0].isdigit():
            close(ln)
            n = int(toks[0])
            if frame_numbers and n != frame_numbers[-1] + 1:
                raise MocapFormatError(p, ln, f"frame number {n} does not follow {frame_numbers[-1]}")
            frame_numbers.append(n)
            frame_start_line.append(ln)
            cur = {}
            frames.append(cur)
            continue
        if cur is None:
            raise MocapFormatError(p, ln, "bone values before the first frame number")
        bone = toks[0]
        if bone not in counts:
            raise MocapFormatError(p, ln, f"bone {bone!r} is not in the skeleton")
        if bone in cur:
            raise MocapFormatError(p, ln, f"bone {bone!r} given twice in one frame")
        vals = toks[1:]
        if len(vals) != counts[bone]:
            raise MocapFormatError(p, ln, f"bone {bone!r} needs {counts[bone]} values, got {len(vals)}")
        cur[bone] = [parse_number(t, p, ln) for t in vals]
    close(last_ln)
    if not frames:
        raise MocapFormatError(p, last_ln or None, "no frames")
    n = len(frames)
    channels = {}
    for bone, c in counts.items():
        arr = np.zeros((n, c))
        if c:
            for i, fr in enumerate(frames):
                arr[i] = fr[bone]
        channels[bone] = arr
    return Motion(n_frames=n, channels=channels, frame_numbers=np.array(frame_numbers),
                  fps=fps, degrees=degrees, path=p, header=header)


def read_amc(path: str | Path, skeleton: Skeleton, fps: float = 120.0) -> Motion:
    """Read an AMC file (see :func:`parse_amc`)."""
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8", errors="strict")
    except UnicodeDecodeError as e:
        raise MocapFormatError(path, None, f"not UTF-8 text: {e}") from None
    return parse_amc(text, skeleton, path, fps)
