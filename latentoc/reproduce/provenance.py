"""What a committed output (a notebook's outputs, a README figure) was made from, so a test can tell
when it is older than the code.

While a :class:`Recorder` is active, the checkout's files that ran or were read are noted: each
Python file one of whose functions is called (a profile hook, in every thread; importing a module
alone does not count, so ``import latentoc`` does not make every module an input) and every file
opened for reading (an audit hook: problem files, data, shipped models, the viewer's scripts).
:func:`module_files` adds the modules a piece of code imports by name (a table used as a constant,
e.g. ``latentoc.reproduce.paper.PAPER``, runs no function). :func:`fingerprint`
hashes a Python file's code without its docstrings and comments (the AST), any other file's
bytes, so an edit to a comment does not make an output stale, an edit to the code it ran does.
:func:`stale` names the inputs that changed since. Files outside the checkout (site-packages, the
GPDM cache) and the compiled extension are not recorded.
"""
from __future__ import annotations

import ast
import hashlib
import importlib.util
import subprocess
import sys
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["ROOT", "Recorder", "fingerprint", "fingerprints", "module_files", "stale", "uncommitted", "start", "stop"]

#: the source checkout (latentoc is installed editable from it)
ROOT = Path(__file__).resolve().parents[2]
_SKIP = ("build", ".venv", ".git", "notebooks", "docs")  # not inputs: build trees, environments, outputs
_RECORDING = ("latentoc/reproduce/provenance.py", "latentoc/reproduce/notebooks.py")  # the recording itself, not an input
_ACTIVE: list[set[str]] = []
_HOOKED = False


def _hook(event: str, args: tuple[Any, ...]) -> None:
    if event != "open" or not _ACTIVE or not isinstance(args[0], (str, Path)):
        return
    mode = args[1] if len(args) > 1 and isinstance(args[1], str) else "r"
    if any(c in mode for c in "wax+"):
        return
    for seen in _ACTIVE:
        seen.add(str(args[0]))


def _profile(frame: Any, event: str, arg: Any) -> None:
    if event == "call" and frame.f_code.co_name != "<module>":
        for seen in _ACTIVE:
            seen.add(frame.f_code.co_filename)


def module_files(code: str) -> set[str]:
    """The files of the latentoc modules ``code`` imports by name (IPython magics skipped)."""
    try:
        tree = ast.parse("\n".join(line for line in code.splitlines() if not line.lstrip().startswith(("%", "!"))))
    except SyntaxError:
        return set()
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
    out = set()
    for name in names:
        if name == "latentoc" or name.startswith("latentoc."):
            try:
                spec = importlib.util.find_spec(name)
            except (ImportError, ValueError):
                continue
            if spec is not None and spec.origin and spec.origin.endswith(".py"):
                out.add(spec.origin)
    return out


def _relative(path: str | Path) -> str | None:
    """``path`` relative to the checkout if it is an input there (module doc), else None."""
    try:
        rel = Path(path).resolve().relative_to(ROOT)
    except (ValueError, OSError):
        return None
    if not rel.parts or rel.parts[0] in _SKIP or "__pycache__" in rel.parts or rel.suffix in (".so", ".pyc") \
            or rel.as_posix() in _RECORDING:
        return None
    return rel.as_posix() if (ROOT / rel).is_file() else None


def _strip_docstrings(tree: ast.AST) -> ast.AST:
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                    and isinstance(body[0].value.value, str):
                node.body = body[1:] or [ast.Pass()]
    return tree


def fingerprint(path: str | Path) -> str:
    """SHA-256 of a Python file's code (its AST without docstrings; comments are not in it) or of
    another file's bytes."""
    path = Path(path)
    data = path.read_bytes()
    if path.suffix == ".py":
        try:
            data = ast.dump(_strip_docstrings(ast.parse(data)), include_attributes=False).encode()
        except SyntaxError:
            pass
    return hashlib.sha256(data).hexdigest()


def fingerprints(paths: set[str] | list[str]) -> dict[str, str]:
    """{path relative to the checkout: fingerprint} of those of ``paths`` that are inputs there."""
    rels = sorted({r for r in (_relative(p) for p in paths) if r is not None})
    return {r: fingerprint(ROOT / r) for r in rels}


class Recorder:
    """``with Recorder() as rec: ...`` then ``rec.inputs``: the checkout's files that ran or were
    read meanwhile (module doc), with their fingerprints."""

    def __init__(self) -> None:
        self.seen: set[str] = set()
        self.inputs: dict[str, str] = {}

    def __enter__(self) -> Recorder:
        global _HOOKED
        if not _HOOKED:  # an audit hook cannot be removed: one for the process, active while recording
            sys.addaudithook(_hook)
            _HOOKED = True
        _ACTIVE.append(self.seen)
        sys.setprofile(_profile)
        threading.setprofile(_profile)  # threads started from now on
        return self

    def __exit__(self, *exc: object) -> None:
        _ACTIVE.remove(self.seen)
        if not _ACTIVE:
            sys.setprofile(None)
            threading.setprofile(None)  # type: ignore[arg-type]
        self.inputs = fingerprints(self.seen)


_RUNNING: list[Recorder] = []


def start() -> None:
    """Start recording in this process (the notebook runner's first hidden cell)."""
    _RUNNING.append(Recorder().__enter__())


def stop() -> dict[str, str]:
    """Stop the recording :func:`start` began; its inputs."""
    rec = _RUNNING.pop()
    rec.__exit__(None, None, None)
    return rec.inputs


def stale(inputs: Mapping[str, str]) -> list[str]:
    """The inputs whose file changed or is gone since their fingerprints were taken."""
    return sorted(r for r, fp in inputs.items() if not (ROOT / r).is_file() or fingerprint(ROOT / r) != fp)


def uncommitted(inputs: Mapping[str, str]) -> list[str]:
    """The inputs with changes git has not committed (an output made from them is stale on a clean
    clone until they are); empty outside a git checkout."""
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--", *inputs], capture_output=True,
                             text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return []
    return sorted(line[3:].strip() for line in out.stdout.splitlines() if line[3:].strip() in inputs) \
        if out.returncode == 0 else []
