"""GPDM learning: the MAP estimate of Eq. 16 (Kang & Park 2015, Sect. 3.1.1) with proper
hyperparameter priors, iterated until it converges (docs/gpdm.md has the measurements).

The model (the same for every problem, :class:`GPDMSettings` defaults):

* Eq. 16's p(theta) ~ 1/theta priors make the MAP degenerate: L has no minimum (a latent
  rescaling X -> sX with alpha, beta_2 following lowers L by (d n - 4) ln(1/s), n the dynamics'
  input points; an unneeded
  kernel term's amplitude runs to 0; on noise-free data the noise precisions run to infinity).
  Every learned hyperparameter (alpha_1..3, beta_2, beta_3) gets instead the same weak
  Gamma(2, 1) prior (mode 1): P(theta) = -ln theta + theta; the dynamics' noise precision
  alpha_4 a wider Gamma(2, 0.01) (mode 100).
* beta_1 = 1: Eq. 16 is exactly invariant under (beta_1, beta_3, W) -> (c beta_1, beta_3 / c,
  W / sqrt c), so W carries the data's scale and sigma^2 (Eq. 19) is in units of the signal
  variance.

Procedure (:func:`learn_gpdm`):

1. Stack the training sequences, subtract the column means; refuse data too long for the memory
   learning needs (:mod:`latentoc.gpdm.size`).
2. X from PCA (scores scaled so that the first latent coordinate has unit standard
   deviation), alpha = (0.9, 1, 0.1, e), beta = (1, 1, e); above 200 frames, the model of every
   second frame instead, its latent points interpolated (:mod:`latentoc.gpdm.start`).
3. W profiled out in closed form (:mod:`latentoc.gpdm.objective`); a damped saddle-free Newton
   method (:mod:`latentoc.gpdm.newton`) on X and the free log-hyperparameters with the exact
   gradient and Hessian (:mod:`latentoc.gpdm.hessian`), until the Newton decrement (the decrease
   of L a Newton step predicts) is at most ``ftol`` |L|. Reaching ``max_iterations``, or a
   hyperparameter on ``log_hyper_bound``, is reported as not converged
   (:class:`~latentoc.gpdm.model.LearningReport`).

Balanced GPDM (Urtasun et al. 2006): the dynamics term times lambda = D/d (``balanced=True``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from latentoc.arguments import expect
from latentoc.runtime.progress import bar
from latentoc.runtime.threads import blas_threads
from latentoc.gpdm.hessian import hessian
from latentoc.gpdm.newton import minimize_newton
from latentoc.gpdm.model import GPDM, LearningReport
from latentoc.gpdm.objective import HYPER_NAMES, Evaluation, GPDMProblem, evaluate, optimal_w, unpack
from latentoc.gpdm.learning_settings import GPDMInputError, GPDMSettings, check_settings
from latentoc.gpdm.size import check_size
from latentoc.gpdm.start import COARSE_ABOVE, COARSE_DOWN_TO, coarse_frames, initial_variables, interpolated_start

__all__ = ["learn_gpdm", "learning_problem", "prepare_data", "roughness"]


def prepare_data(Y: np.ndarray | Sequence[np.ndarray], latent_dim: int) -> tuple[np.ndarray, list[int]]:
    """Validate training data (one N x D array or a list of N_i x D arrays).

    Returns the stacked data and the sequence lengths.  Raises
    :class:`GPDMInputError` naming the problem.
    """
    if isinstance(Y, np.ndarray) or not isinstance(Y, (list, tuple)):
        seqs = [Y]
    else:
        seqs = list(Y)
        if not seqs:
            raise GPDMInputError("Y: the list of training sequences is empty")
    arrays = []
    for i, s in enumerate(seqs):
        name = "Y" if len(seqs) == 1 else f"Y[{i}]"
        try:
            a = np.asarray(s, dtype=float)
        except (TypeError, ValueError) as exc:
            raise GPDMInputError(f"{name}: cannot convert to a float array ({exc})") from None
        if a.ndim != 2:
            raise GPDMInputError(
                f"{name}: wrong shape {a.shape}; expected a 2-D array (frames x dimensions)")
        bad = ~np.isfinite(a)
        if bad.any():
            r, c = np.argwhere(bad)[0]
            kind = "NaN" if np.isnan(a[r, c]) else "inf"
            raise GPDMInputError(
                f"{name}: {kind} value at row {r}, column {c} ({int(bad.sum())} non-finite entries)")
        if a.shape[0] < 3:
            raise GPDMInputError(f"{name}: too few frames ({a.shape[0]}); each sequence needs at least 3")
        arrays.append(a)
    D = arrays[0].shape[1]
    for i, a in enumerate(arrays):
        if a.shape[1] != D:
            raise GPDMInputError(f"Y[{i}]: wrong shape {a.shape}; all sequences need {D} columns")
    Ys = np.vstack(arrays)
    N = Ys.shape[0]
    if latent_dim >= D:
        raise GPDMInputError(
            f"latent_dim d={latent_dim} must be smaller than the data dimension D={D} (d >= D)")
    if N < latent_dim + 2:
        raise GPDMInputError(f"Y: too few frames (N={N}) for latent_dim {latent_dim}; need N >= d + 2")
    return Ys, [a.shape[0] for a in arrays]


def roughness(X: np.ndarray) -> float:
    """mean |x_{t+1} - 2 x_t + x_{t-1}| / mean |x_{t+1} - x_t| of one trajectory.

    Scale invariant.  For a circle sampled with n points per turn it is
    2 sin(pi/n) (0.1 for n = 60); for white noise it is about sqrt(3) ~ 1.7.
    """
    X = np.asarray(X, dtype=float)
    d1 = np.linalg.norm(np.diff(X, axis=0), axis=1).mean()
    d2 = np.linalg.norm(np.diff(X, n=2, axis=0), axis=1).mean()
    return float(d2 / d1)


def _prior_arrays(settings: GPDMSettings) -> tuple[np.ndarray, np.ndarray]:
    shape, rate = np.zeros(7), np.zeros(7)
    for name, (a, b) in settings.gamma.items():
        i = HYPER_NAMES.index(name)
        shape[i], rate[i] = float(a), float(b)
    return shape, rate


def learning_problem(Yc: np.ndarray, lengths: list[int], settings: GPDMSettings) -> GPDMProblem:
    """The objective :func:`learn_gpdm` minimises for centred data ``Yc`` (Eq. 16, the settings'
    priors and balancing)."""
    shape, rate = _prior_arrays(settings)
    D, d = Yc.shape[1], int(settings.latent_dim)
    return GPDMProblem(Yc, list(lengths), d, dynamics_weight=D / d if settings.balanced else 1.0,
                       prior_shape=shape, prior_rate=rate, kappa_sq=settings.kappa_sq)


@dataclass
class _FreePoint:
    """An evaluation of Eq. 16 seen on the learned variables (:func:`learn_gpdm`)."""

    f: float
    g: np.ndarray
    ev: Evaluation


def learn_gpdm(Y: np.ndarray | Sequence[np.ndarray], settings: GPDMSettings | None = None) -> GPDM:
    """Learn a GPDM from one sequence (N x D) or a list of sequences: minimise Eq. 16 with the
    settings' fixed hyperparameters and priors, W profiled out, until the convergence test holds.
    Shows its progress (iteration, L, Newton decrement) on stderr (:mod:`latentoc.runtime.progress`).

    Module docstring: the model and the procedure. Raises :class:`~latentoc.gpdm.size.GPDMSizeError` before anything is
    computed when the data need more memory than the machine has.
    """
    if settings is not None:
        expect("learn_gpdm", "settings", settings, GPDMSettings, "a GPDMSettings or None")
    settings = GPDMSettings() if settings is None else settings
    with blas_threads(settings.blas_threads):  # all of learning's linear algebra, its coarse levels and W included
        return _learn(Y, settings, COARSE_ABOVE)


def _learn(Y: np.ndarray | Sequence[np.ndarray], settings: GPDMSettings, coarse_above: int) -> GPDM:
    """:func:`learn_gpdm`, starting from the model of every second frame above ``coarse_above`` frames
    (that model's own levels halve down to COARSE_DOWN_TO frames: start.py)."""
    check_settings(settings)
    d = int(settings.latent_dim)
    Ys, lengths = prepare_data(Y, d)
    N, D = Ys.shape
    check_size(N, D, d)
    Y_mean = Ys.mean(axis=0)
    Yc = Ys - Y_mean
    problem = learning_problem(Yc, lengths, settings)
    t0 = time.perf_counter()
    frames = coarse_frames(lengths)
    if N > coarse_above and sum(map(len, frames)) <= 0.75 * N:  # coarse to fine (start.py)
        starts = np.cumsum([0] + lengths)
        coarse = _learn([Ys[a + idx] for a, idx in zip(starts[:-1], frames)], settings, COARSE_DOWN_TO)
        v0 = interpolated_start(coarse.X, np.concatenate([coarse.alpha, coarse.beta]), lengths, frames)
        origin = f" from the model of {coarse.X.shape[0]} of the frames"
    else:
        v0, origin = initial_variables(Yc, settings), ""
    free = np.ones(v0.size, dtype=bool)
    for name in settings.fixed:
        free[N * d + HYPER_NAMES.index(name)] = False
    bound = float(settings.log_hyper_bound)
    n_free_x = N * d

    def full(z: np.ndarray) -> np.ndarray:
        v = v0.copy()
        v[free] = z
        return v

    def evaluate_free(z: np.ndarray) -> _FreePoint | None:
        try:
            ev = evaluate(full(z), problem)
        except np.linalg.LinAlgError:  # a trial point with a kernel matrix beyond repair: rejected
            return None
        return _FreePoint(ev.f, ev.g[free], ev)

    def hessian_free(point: _FreePoint) -> np.ndarray:
        return hessian(point.ev, free[n_free_x:])

    lower = np.r_[np.full(n_free_x, -np.inf), np.full(int(free[n_free_x:].sum()), -bound)]
    with bar(desc=f"GPDM on {N} frames", unit="it") as progress:
        def report_step(step: int, f: float, decrement: float) -> None:
            progress.update(1)
            progress.set_postfix_str(f"L = {f:.10g}, decrement {decrement:.2g}")  # each iteration shown

        res = minimize_newton(evaluate_free, hessian_free, v0[free], lower, -lower,  # type: ignore[arg-type]
                              settings.ftol, settings.max_iterations, report_step)
    z, f, g, converged, decrement = res.z, res.f, res.g, res.converged, res.decrement
    message = res.message + origin
    gnorm = float(np.max(np.abs(g)))
    v = full(z)
    X, alpha, beta = unpack(v, N, d)
    at_bound = [name for name, lv, fr in zip(HYPER_NAMES, v[n_free_x:], free[n_free_x:])
                if fr and abs(lv) >= bound]
    if at_bound:
        message += f"; at the bound |ln theta| = {bound:g}: {', '.join(at_bound)}"
    report = LearningReport(iterations=res.steps, evaluations=res.evaluations, gradient_norm=gnorm,
                            newton_decrement=decrement,
                            converged=bool(converged and not at_bound), message=message,
                            time_s=time.perf_counter() - t0)
    w = optimal_w(Yc, X, beta, settings.kappa_sq)
    return GPDM(X=np.array(X), sequence_lengths=list(lengths), alpha=np.array(alpha),
                beta=np.array(beta), W=np.array(w), Y_mean=Y_mean, Y=Ys,
                settings=settings, objective_value=float(f), learning=report)
