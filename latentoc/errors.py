"""The one root of latentoc's errors: every error about the user's input derives from
:class:`LatentocError`, and the CLI shows it as ``latentoc: error: ...`` (exit code 2)."""
from __future__ import annotations

__all__ = ["LatentocError"]


class LatentocError(Exception):
    """Input latentoc cannot use: a problem file, motion, robot, model or setting."""
