"""Where a jump solve's Ipopt iterations go (``python -m latentoc bench jump --profile [PROBLEM]``).

Within :func:`profiled`, every Ipopt run (phase 1, each exchange round of phase 2) is timed in the
pieces each of its iterations is made of (:func:`profile_table` prints them per iteration):

* the compiled robot blocks (:class:`latentoc.nlp.evaluators.BlockEvaluator`: values, local
  Jacobians, local Hessians, the closure's Newton steps and implicit derivatives included, since
  they are inside each block), without the latent layer they call;
* the latent layer (:mod:`latentoc.latent.gp_layer`, :mod:`latentoc.latent.residual_layer`): the GP
  mean and its tangents (Eq. 18, 26-28), its curvature term, the tube's sigma^2 (Eq. 19);
* the chain rule and assembly: the rest of the NLP callbacks (:mod:`latentoc.nlp.assemble`: local
  inputs, the sparse products, scattering into Ipopt's patterns);
* MUMPS (Ipopt's own timing statistics: symbolic and numeric factorisations, back-solves) and the
  rest of Ipopt;

Timers cost a few microseconds a call; the solve and its result are the ones without them.
"""
from __future__ import annotations

import re
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["IterationProfile", "SolveProfile", "ipopt_timing", "profiled", "profile_table", "block_table"]

PARTS = ("block values", "block Jacobians", "block Hessians", "latent layer", "chain rule & assembly", "MUMPS",
         "rest of Ipopt")
MUMPS_LINES = ("LinearSystemSymbolicFactorization", "LinearSystemFactorization", "LinearSystemBackSolve")


def ipopt_timing(text: str) -> dict[str, float]:
    """Wall seconds of each line of Ipopt's timing statistics (``print_timing_statistics``)."""
    out = {}
    for m in re.finditer(r"^\s*([A-Za-z0-9 ]+?)\.*:\s+[-0-9.e]+ \(sys:\s+[-0-9.e]+ wall:\s+([-0-9.e]+)\)", text, re.M):
        out[m.group(1).strip()] = float(m.group(2))
    return out


@dataclass
class IterationProfile:
    """One Ipopt run: its description, iterations, wall seconds and each part's seconds (:data:`PARTS`)."""

    desc: str
    iterations: int
    time_s: float
    parts: dict[str, float] = field(default_factory=dict)
    blocks: dict[tuple[str, str], float] = field(default_factory=dict)  # (block, kind): its seconds

    def per_iteration_ms(self) -> dict[str, float]:
        it = max(self.iterations, 1)
        return {k: 1e3 * self.parts.get(k, 0.0) / it for k in PARTS}


@dataclass
class SolveProfile:
    """A solve's Ipopt runs and its timers' seconds (``seconds["consistent start"]``: the consistent
    start, counted by the solve within its NLP builds)."""

    runs: list[IterationProfile]
    seconds: dict[str, float]


class _Clock:
    """Seconds per part (``"layer"``, ``"consistent start"``), counting only the outermost call of a
    part (a layer calling a layer), and per (block, kind) of robot-block evaluation, the layer's
    seconds inside an evaluation taken out of it."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.blocks: dict[tuple[str, str], float] = defaultdict(float)
        self.depth: dict[str, int] = defaultdict(int)
        self.evaluating: tuple[str, str] | None = None

    def wrap(self, part: str, fn: Callable) -> Callable:
        def timed(*args, **kwargs):
            self.depth[part] += 1
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                dt = time.perf_counter() - t0
                self.depth[part] -= 1
                if self.depth[part] == 0:
                    self.seconds[part] += dt
                    if part == "layer" and self.evaluating:
                        self.blocks[self.evaluating] -= dt
        return timed

    def wrap_evaluation(self, kind: str, fn: Callable) -> Callable:
        def timed(evaluator, *args, **kwargs):
            self.evaluating = (evaluator.block.name, kind)
            t0 = time.perf_counter()
            try:
                return fn(evaluator, *args, **kwargs)
            finally:
                self.blocks[self.evaluating] += time.perf_counter() - t0
                self.evaluating = None
        return timed


def _patch(owner, name: str, new) -> Callable[[], None]:
    old = owner.__dict__[name]
    setattr(owner, name, new)
    return lambda: setattr(owner, name, old)


@contextmanager
def profiled() -> Iterator["SolveProfile"]:
    """Within it, every :func:`latentoc.nlp.ipopt.solve` appends its :class:`IterationProfile` to the
    yielded profile's runs, and the jump's consistent start (:mod:`latentoc.jump.solve.consistent_path`)
    is timed."""
    from latentoc.latent import gp_layer, residual_layer
    from latentoc.nlp import evaluators, ipopt

    clock, runs, undo = _Clock(), [], []
    for kind in ("values", "jacobian", "hessian"):
        fn = evaluators.BlockEvaluator.__dict__[kind]
        undo.append(_patch(evaluators.BlockEvaluator, kind, clock.wrap_evaluation(kind, fn)))
    for cls in (gp_layer.GPLayer, gp_layer.IdentityLayer, residual_layer.ResidualLayer):
        for method in ("motion", "curvature", "variance"):
            if method in cls.__dict__:
                undo.append(_patch(cls, method, clock.wrap("layer", cls.__dict__[method])))
    from latentoc.jump.solve import solve as jump_solve

    undo.append(_patch(jump_solve, "consistent_path", clock.wrap("consistent start", jump_solve.consistent_path)))
    solve = ipopt.solve

    def profiled_solve(*args, **kwargs):
        before = dict(clock.blocks), clock.seconds["layer"]
        with tempfile.TemporaryDirectory(prefix="latentoc-profile-") as tmp:
            log = Path(tmp) / "ipopt.txt"
            args = list(args)
            opts = dict(args[6] if len(args) > 6 else kwargs.pop("options", None) or {})
            opts.update(print_timing_statistics="yes", output_file=str(log), file_print_level=3)
            if len(args) > 6:
                args[6] = opts
            else:
                kwargs["options"] = opts
            run = solve(*args, **kwargs)
            timing = ipopt_timing(log.read_text()) if log.exists() else {}
        blocks = {k: v - before[0].get(k, 0.0) for k, v in clock.blocks.items()}
        parts = {f"block {name}": sum(v for (_, k), v in blocks.items() if k == kind)
                 for kind, name in (("values", "values"), ("jacobian", "Jacobians"), ("hessian", "Hessians"))}
        parts["latent layer"] = clock.seconds["layer"] - before[1]
        callbacks = sum(run.timings.values())
        parts["chain rule & assembly"] = callbacks - sum(parts.values())
        parts["MUMPS"] = sum(timing.get(k, 0.0) for k in MUMPS_LINES)
        parts["rest of Ipopt"] = run.time_s - callbacks - parts["MUMPS"]
        runs.append(IterationProfile(kwargs.get("desc", "ipopt"), run.iterations, run.time_s, parts, blocks))
        return run

    undo.append(_patch(ipopt, "solve", profiled_solve))
    try:
        yield SolveProfile(runs, clock.seconds)
    finally:
        for u in reversed(undo):
            u()


def profile_table(runs: list[IterationProfile]) -> list[str]:
    head = "| Ipopt run | iterations | s | " + " | ".join(f"{p} ms/it" for p in PARTS) + " |"
    lines = [head, "|" + " --- |" * (3 + len(PARTS))]
    for r in runs:
        ms = r.per_iteration_ms()
        lines.append(f"| {r.desc} | {r.iterations} | {r.time_s:.1f} | " + " | ".join(f"{ms[p]:.1f}" for p in PARTS) + " |")
    its = sum(r.iterations for r in runs)
    total = IterationProfile("all runs", its, sum(r.time_s for r in runs),
                             {p: sum(r.parts.get(p, 0.0) for r in runs) for p in PARTS})
    ms = total.per_iteration_ms()
    lines.append(f"| **{total.desc}** | {its} | {total.time_s:.1f} | " + " | ".join(f"{ms[p]:.1f}" for p in PARTS) + " |")
    return lines


def block_table(runs: list[IterationProfile]) -> list[str]:
    """Each robot block's ms per iteration over all ``runs`` (values, Jacobians, Hessians), slowest first."""
    its = max(sum(r.iterations for r in runs), 1)
    total: dict[tuple[str, str], float] = defaultdict(float)
    for r in runs:
        for k, v in r.blocks.items():
            total[k] += v
    names = sorted({b for b, _ in total}, key=lambda b: -sum(total[b, k] for k in ("values", "jacobian", "hessian")))
    lines = ["| block | values ms/it | Jacobians ms/it | Hessians ms/it |", "| --- | --- | --- | --- |"]
    for b in names:
        lines.append(f"| {b} | " + " | ".join(f"{1e3 * total[b, k] / its:.1f}" for k in ("values", "jacobian", "hessian")) + " |")
    return lines
