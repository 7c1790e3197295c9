"""A real headless browser for the tests of the 3-D view: Debian's chromium (``apt-get install
chromium``; .ci/run installs it), driven from its command line. Each call starts a fresh
browser with its own profile, loads a page from a file and lets ``budget_ms`` of virtual time
pass (the page's clock and requestAnimationFrame run on it) before the screenshot or the DOM."""
from __future__ import annotations

import subprocess
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from latentoc.viewer.still import FLAGS, chromium  # the package's own browser lookup and flags

__all__ = ["chromium", "screenshot", "dom"]


def _run(page: Path, budget_ms: int, *extra: str, url_suffix: str = "") -> subprocess.CompletedProcess:
    exe = chromium()
    assert exe is not None
    with tempfile.TemporaryDirectory(prefix="latentoc-chromium-") as profile:
        return subprocess.run([exe, *FLAGS, f"--user-data-dir={profile}", f"--virtual-time-budget={budget_ms}", *extra,
                               Path(page).resolve().as_uri() + url_suffix], capture_output=True, text=True, timeout=180)


def screenshot(page: Path, out: Path, budget_ms: int, size: tuple[int, int] = (800, 600), url_suffix: str = "") -> np.ndarray:
    """The page's pixels (h, w, 3) after ``budget_ms`` of virtual time."""
    done = _run(page, budget_ms, f"--window-size={size[0]},{size[1]}", f"--screenshot={out}", url_suffix=url_suffix)
    assert out.is_file(), f"chromium wrote no screenshot: {done.stderr[-2000:]}"
    with Image.open(out) as im:
        return np.asarray(im.convert("RGB")).astype(int)


def dom(page: Path, budget_ms: int, url_suffix: str = "") -> str:
    """The page's DOM (serialised) after ``budget_ms`` of virtual time."""
    done = _run(page, budget_ms, "--dump-dom", url_suffix=url_suffix)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout
