"""The one Ipopt path: a :class:`~latentoc.nlp.assemble.SparseNLP` solved by CasADi's Ipopt.

The NLP's objective, constraints, gradient, Jacobian and exact Hessian are handed to
``casadi.nlpsol`` as callbacks (numpy on the Python side, compiled robot blocks inside), so
Ipopt gets every derivative from the assembled layers; with ``hessian="lbfgs"`` Ipopt's
limited-memory quasi-Newton approximation replaces the Hessian (the paper used L-BFGS, Sect. 3.4). A progress bar shows the iterations,
the objective and the constraint violation. Warm starts are explicit: the previous solve's
primal point and multipliers are arguments, never module state.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import casadi as ca
import numpy as np

from latentoc.runtime.interrupts import deferred, interrupts_seen
from latentoc.runtime.progress import bar
from latentoc.runtime.threads import openblas_threads_at_load
from latentoc.nlp.assemble import SparseNLP

__all__ = ["IpoptResult", "solve", "load_ipopt", "HESSIANS", "DEFAULT_OPTIONS", "WARM_START_OPTIONS"]

HESSIANS = ("exact", "lbfgs")
DEFAULT_OPTIONS = {"tol": 1e-8, "max_iter": 3000, "mu_strategy": "adaptive", "print_level": 0, "sb": "yes"}
# a warm start from a neighbouring optimum: its point and multipliers pushed only 1e-5 off their bounds
WARM_START_OPTIONS = {"warm_start_init_point": "yes", "mu_init": 1e-4, "warm_start_bound_push": 1e-5,
                      "warm_start_mult_bound_push": 1e-5, "warm_start_slack_bound_push": 1e-5}


@dataclass
class IpoptResult:
    """The outcome of one Ipopt run."""

    x: np.ndarray
    f: float
    g: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray
    status: str
    success: bool
    iterations: int
    time_s: float
    timings: dict[str, float] = field(default_factory=dict)  # wall seconds per callback kind
    calls: dict[str, int] = field(default_factory=dict)  # evaluations per callback kind
    # per iteration (Ipopt's log): iter, objective, inf_pr, inf_du, mu, alpha_pr, alpha_du
    history: dict[str, list[float]] = field(default_factory=dict)

    def multipliers(self) -> dict[str, np.ndarray]:
        """The point and multipliers a warm start of a neighbouring problem takes."""
        return {"x0": self.x, "lam_g0": self.lam_g, "lam_x0": self.lam_x}


_IPOPT_LOADED = False


def load_ipopt() -> None:
    """Load CasADi's Ipopt plugin, with the OpenBLAS it brings (under MUMPS) on one thread unless
    ``$OPENBLAS_NUM_THREADS`` is set: its spinning workers slowed the threaded node evaluations."""
    global _IPOPT_LOADED
    if _IPOPT_LOADED:
        return
    with openblas_threads_at_load(1):
        ca.load_nlpsol("ipopt")
    _IPOPT_LOADED = True


class _Raised:
    """The first exception raised inside a callback, or a Ctrl-C during the solve: the callbacks
    record it and return a failure (an exception let through into CasADi would be printed with its
    traceback), the progress callback then stops Ipopt, and :func:`solve` raises it afterwards."""

    def __init__(self) -> None:
        self.error: BaseException | None = None
        self._interrupts = interrupts_seen()

    def record(self, exc: BaseException) -> None:
        if self.error is None:
            self.error = exc

    def stopped(self) -> bool:
        """Whether the solve must stop: an error was recorded or a SIGINT arrived."""
        if self.error is None and interrupts_seen() > self._interrupts:
            self.record(KeyboardInterrupt())
        return self.error is not None


class _Callback(ca.Callback):
    def __init__(self, name: str, fn: Callable, ins: list[tuple[str, ca.Sparsity]], outs: list[tuple[str, ca.Sparsity]],
                 timings: dict[str, float], calls: dict[str, int], raised: _Raised, jac_x: ca.Sparsity | None = None):
        ca.Callback.__init__(self)
        self._fn, self._ins, self._outs, self._timings, self._calls = fn, ins, outs, timings, calls
        self._jac_x, self._raised = jac_x, raised
        # finite differences only so that CasADi can build (never call) derivative Functions
        self.construct(name, {"enable_fd": True})

    def get_n_in(self):
        return len(self._ins)

    def get_n_out(self):
        return len(self._outs)

    def get_name_in(self, i):
        return self._ins[i][0]

    def get_name_out(self, i):
        return self._outs[i][0]

    def get_sparsity_in(self, i):
        return self._ins[i][1]

    def get_sparsity_out(self, i):
        return self._outs[i][1]

    # the pattern of d(out 0)/dx: without it CasADi takes the block dense (m x n) and building the
    # solver costs seconds per thousand rows
    def has_jac_sparsity(self, oind, iind):
        return self._jac_x is not None and oind == 0

    def get_jac_sparsity(self, oind, iind, symmetric):
        if iind == 0:
            return self._jac_x
        return ca.Sparsity(self._outs[oind][1].nnz(), self._ins[iind][1].nnz())

    # evaluated in place on CasADi's buffers (inputs and outputs as their nonzeros): no DM is made
    def has_eval_buffer(self):
        return True

    def eval_buffer(self, args, res):
        t0 = time.perf_counter()
        if self._raised.stopped():
            return 1
        try:
            # a missing input is zero; a missing output was not asked for
            out = self._fn(*[np.zeros(sp.nnz()) if a is None else np.frombuffer(a, dtype=np.float64)
                             for a, (_, sp) in zip(args, self._ins)])
            for r, v in zip(res, out):
                if r is not None:
                    np.frombuffer(r, dtype=np.float64)[:] = np.ravel(v)
        except BaseException as exc:
            self._raised.record(exc)
            return 1
        self._timings[self.name()] = self._timings.get(self.name(), 0.0) + time.perf_counter() - t0
        self._calls[self.name()] = self._calls.get(self.name(), 0) + 1
        return 0


class _Progress(ca.Callback):
    """Ipopt's iterations on a progress bar: objective and constraint violation."""

    def __init__(self, n: int, m: int, lbg: np.ndarray, ubg: np.ndarray, desc: str, max_iter: int, raised: _Raised):
        ca.Callback.__init__(self)
        self.n, self.m, self.lbg, self.ubg, self.raised = n, m, lbg, ubg, raised
        self.bar = bar(total=max_iter, desc=desc, unit="it")
        self.construct("ipopt_progress", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name in ("f",):
            return ca.Sparsity.dense(1)
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.n)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.m)
        return ca.Sparsity.dense(0)

    def eval(self, args):
        if self.raised.stopped():
            return [1]  # non-zero: Ipopt stops
        try:
            g = np.asarray(args[ca.nlpsol_out().index("g")]).ravel()
            viol = float(np.max(np.concatenate([[0.0], self.lbg - g, g - self.ubg]))) if g.size else 0.0
            self.bar.update(1)
            self.bar.set_postfix(f=f"{float(args[ca.nlpsol_out().index('f')]):.6g}", viol=f"{viol:.1e}")
        except BaseException as exc:
            self.raised.record(exc)
        return [1 if self.raised.error is not None else 0]  # non-zero: Ipopt stops


def solve(nlp: SparseNLP, x0: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, lbg: np.ndarray, ubg: np.ndarray,
          options: dict | None = None, warm: dict[str, np.ndarray] | None = None, desc: str = "ipopt",
          hessian: str = "exact") -> IpoptResult:
    """Run Ipopt on ``nlp`` from ``x0``. ``options`` are Ipopt's (over :data:`DEFAULT_OPTIONS`);
    ``warm`` = :meth:`IpoptResult.multipliers` of a neighbouring solve starts from its
    multipliers too (:data:`WARM_START_OPTIONS`); ``hessian`` is one of :data:`HESSIANS`."""
    if hessian not in HESSIANS:
        raise ValueError(f"hessian must be one of {', '.join(HESSIANS)}, got {hessian!r}")
    load_ipopt()
    n, m = nlp.n_w, nlp.m
    timings: dict[str, float] = {}
    calls: dict[str, int] = {}
    raised = _Raised()
    dense = ca.Sparsity.dense
    xin = [("x", dense(n)), ("p", dense(0))]
    cbs = {
        "f": _Callback("nlp_f", lambda w, p: [nlp.objective(w)], xin, [("f", dense(1))], timings, calls, raised,
                       jac_x=dense(1, n)),
        "g": _Callback("nlp_g", lambda w, p: [nlp.constraints(w)], xin, [("g", dense(m))], timings, calls, raised,
                       jac_x=nlp.jac_sparsity),
        "grad_f": _Callback("nlp_grad_f", lambda w, p: [nlp.objective(w), nlp.gradient(w)], xin,
                            [("f", dense(1)), ("grad_f_x", dense(n))], timings, calls, raised),
        "jac_g": _Callback("nlp_jac_g", lambda w, p: [nlp.constraints(w), nlp.jacobian(w)], xin,
                           [("g", dense(m)), ("jac_g_x", nlp.jac_sparsity)], timings, calls, raised),
    }
    if hessian == "exact":
        cbs["hess_lag"] = _Callback("nlp_hess_l", lambda w, p, lf, lg: [nlp.hessian(w, float(lf[0]), lg)],
                                    xin + [("lam_f", dense(1)), ("lam_g", dense(m))],
                                    [("triu_hess_gamma_x_x", nlp.hess_sparsity)], timings, calls, raised)
    ipopt = {**DEFAULT_OPTIONS, **(options or {})}
    if warm is not None:
        ipopt = {**ipopt, **WARM_START_OPTIONS, **(options or {})}
    if hessian == "lbfgs":
        ipopt["hessian_approximation"] = "limited-memory"
    max_iter = int(ipopt["max_iter"])
    progress = _Progress(n, m, np.asarray(lbg, float), np.asarray(ubg, float), desc, max_iter, raised)
    t0 = time.perf_counter()  # time_s: the solver's construction and its run
    w = ca.MX.sym("w", n)
    p = ca.MX.sym("p", 0)
    problem = {"x": w, "f": cbs["f"](w, p), "g": cbs["g"](w, p)}
    opts: dict[str, Any] = {"ipopt": ipopt, "print_time": False, "error_on_fail": False, "calc_lam_p": False,
            "iteration_callback": progress, **{k: cbs[k] for k in ("grad_f", "jac_g", "hess_lag") if k in cbs}}
    solver = ca.nlpsol("latentoc_ipopt", "ipopt", problem, opts)
    args = {"x0": x0, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}
    if warm is not None:
        args.update({"lam_g0": warm["lam_g0"], "lam_x0": warm["lam_x0"]})
    try:
        with deferred():  # a Ctrl-C is counted; the next callback stops Ipopt
            sol = solver(**args)
    except KeyboardInterrupt as exc:
        raised.record(exc)
    except Exception:  # CasADi's report of a failed callback: the callback's own error is raised below
        if raised.error is None:
            raise
    finally:
        progress.bar.close()
    if raised.error is not None:  # Ctrl-C or a failing callback: never a result
        raise raised.error
    elapsed = time.perf_counter() - t0
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    success = bool(stats.get("success", False)) or status == "Solved_To_Acceptable_Level"
    return IpoptResult(x=np.asarray(sol["x"]).ravel(), f=float(sol["f"]), g=np.asarray(sol["g"]).ravel(),
                       lam_g=np.asarray(sol["lam_g"]).ravel(), lam_x=np.asarray(sol["lam_x"]).ravel(),
                       status=status, success=success, iterations=int(stats.get("iter_count", -1)),
                       time_s=elapsed, timings=timings, calls=calls, history=_history(stats))


HISTORY_KEYS = {"objective": "obj", "inf_pr": "inf_pr", "inf_du": "inf_du", "mu": "mu", "alpha_pr": "alpha_pr",
                "alpha_du": "alpha_du"}


def _history(stats: dict) -> dict[str, list[float]]:
    """Ipopt's per-iteration log from CasADi's solver statistics (:attr:`IpoptResult.history`)."""
    its = stats.get("iterations") or {}
    out = {k: [float(v) for v in its.get(src, [])] for k, src in HISTORY_KEYS.items()}
    out["iter"] = [float(i) for i in range(len(out["objective"]))]
    return out
