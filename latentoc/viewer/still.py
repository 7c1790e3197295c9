"""A still of the 3-D view: the page opened in headless chromium at one motion time (``#t=``),
screenshotted. Needs Debian's ``chromium`` (``apt-get install chromium``) or another Chromium
(``$LATENTOC_CHROMIUM``)."""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from latentoc.errors import LatentocError

__all__ = ["chromium", "still"]

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", "--hide-scrollbars", "--mute-audio"]


def chromium() -> str | None:
    """The Chromium executable: ``$LATENTOC_CHROMIUM``, else chromium, chromium-browser or google-chrome."""
    for name in (os.environ.get("LATENTOC_CHROMIUM"), "chromium", "chromium-browser", "google-chrome"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def still(page: str | Path, png: str | Path, t: float, size: tuple[int, int] = (1000, 640)) -> Path:
    """Screenshot the view page ``page`` paused at motion time ``t`` into ``png``."""
    exe = chromium()
    if exe is None:
        raise LatentocError("a still of the 3-D view needs Chromium: apt-get install chromium (or set LATENTOC_CHROMIUM)")
    png = Path(png).resolve()
    png.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="latentoc-chromium-") as profile:
        done = subprocess.run([exe, *FLAGS, f"--user-data-dir={profile}", "--virtual-time-budget=2000",
                               f"--window-size={size[0]},{size[1]}", f"--screenshot={png}",
                               f"{Path(page).resolve().as_uri()}#t={t:g}"], capture_output=True, text=True, timeout=300)
    if not png.is_file():
        raise LatentocError(f"chromium made no screenshot of {page}: {done.stderr[-1000:]}")
    return png
