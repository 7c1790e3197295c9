"""Optimised libraries built in the background: a hot piece of :data:`QUICK_FIRST` instructions or
more is compiled at once with ``-O0`` and then with ``-O1`` by a detached process that outlives the
command (gcc's optimiser takes five times as long: the arm's Hessian piece 1.4 s at -O0, 6.8 s at
-O1); when that library is in the cache, the process rewrites the block's cache index to name it:
the process that started it switches to it there (:meth:`~latentoc.nlp.blocks.RobotBlock.mapped`),
later ones load it. Both compile the same C, whose values do not depend on the
optimisation level (no fast-math, no fused multiply-add on the baseline x86-64).

A Ctrl-C does not reach the detached process (a session of its own); if it is killed, the index
keeps naming the quick library.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from latentoc.nlp.jit import JIT_FLAGS, build_library, cache_dir, compiler

__all__ = ["QUICK_FIRST", "quick_first", "settle", "start", "wait"]

QUICK_FIRST = 10_000  # instructions from which a hot piece's first library is the quick one
_started: list[subprocess.Popen] = []


def quick_first(instructions: int, flags: tuple[str, ...]) -> bool:
    """Whether a piece compiled with ``flags`` gets a quick library first (module doc)."""
    return tuple(flags) == JIT_FLAGS and instructions >= QUICK_FIRST


def start(index: Path, entry: dict, jobs: list[tuple[str, tuple[str, ...], str]]) -> None:
    """Compile ``jobs`` (source, flags, library name) into the cache in a detached process, then
    write ``entry`` (the index naming the optimised libraries) to ``index``."""
    cache = cache_dir()
    folder = Path(tempfile.mkdtemp(dir=cache, prefix=".upgrade-"))
    try:
        for i, (source, _, _) in enumerate(jobs):
            (folder / f"{i}.c").write_text(source)
        plan = {"index": index.name, "entry": entry,
                "jobs": [{"source": f"{i}.c", "flags": list(flags), "library": lib} for i, (_, flags, lib) in enumerate(jobs)]}
        (folder / "plan.json").write_text(json.dumps(plan))
        env = {**os.environ, "LATENTOC_CACHE": str(cache)}
        _started.append(subprocess.Popen([sys.executable, "-m", "latentoc.nlp.upgrade", str(folder)], env=env,
                                         stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                         stderr=subprocess.DEVNULL, start_new_session=True))
    except BaseException:  # a Ctrl-C before the process owns the folder leaves none behind
        shutil.rmtree(folder, ignore_errors=True)
        raise


def wait() -> None:
    """Wait for the background compilations this process started (benchmarks, tests)."""
    while _started:
        _started.pop().wait()


def settle(cache: Path, timeout: float = 300.0) -> bool:
    """Wait until the background compilations any process started in ``cache`` are done (each
    removes its ``.upgrade-*`` folder last), at most ``timeout`` s: whether they are. Benchmarks and
    tests call it before they time the next thing or remove the cache."""
    t0 = time.monotonic()
    while any(Path(cache).glob(".upgrade-*")):
        if time.monotonic() - t0 > timeout:
            return False
        time.sleep(0.05)
    return True


def _run(folder: Path) -> None:
    plan = json.loads((folder / "plan.json").read_text())
    cc = compiler()
    if cc is None:
        return
    cache = cache_dir()
    for job in plan["jobs"]:
        build_library(cc, (folder / job["source"]).read_text(), tuple(job["flags"]), cache / job["library"])
    tmp = cache / f".{plan['index']}.{os.getpid()}"
    tmp.write_text(json.dumps(plan["entry"]))
    os.replace(tmp, cache / plan["index"])


if __name__ == "__main__":
    try:
        _run(Path(sys.argv[1]))
    finally:
        shutil.rmtree(sys.argv[1], ignore_errors=True)
