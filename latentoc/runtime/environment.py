"""Where a result or a reproduction was computed: package versions, CPU, threads."""
from __future__ import annotations

import os
import platform
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Environment", "cpu_name"]


@dataclass(frozen=True)
class Environment:
    """Where a result was computed: package versions, CPU, threads."""

    latentoc: str
    casadi: str
    pinocchio: str
    numpy: str
    python: str
    cpu: str
    cpu_count: int
    threads: int
    scipy: str = "?"  # results saved before it was recorded load without it

    @classmethod
    def current(cls) -> Environment:
        """This process's."""
        import casadi
        import pinocchio
        import scipy

        from latentoc.version import __version__
        from latentoc.runtime.threads import mapped_threads

        return cls(latentoc=__version__, casadi=casadi.CasadiMeta.version(), pinocchio=getattr(pinocchio, "__version__", "?"),
                   numpy=np.__version__, python=platform.python_version(), cpu=cpu_name(),
                   cpu_count=os.cpu_count() or 1, threads=mapped_threads(), scipy=scipy.__version__)


def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what the platform says."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()
