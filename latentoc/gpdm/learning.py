"""GPDM learning: minimise the negative log posterior of Eq. 16 (Kang & Park
2015, Sect. 3.1.1), following the structure of Wang et al.'s reference GPDM
code.

Procedure (:func:`learn_gpdm`):

1. Stack the training sequences, subtract the column means.
2. Initialise X by PCA (scores scaled so that the first latent coordinate has
   unit standard deviation), alpha = (0.9, 1, 0.1, e), beta = (1, 1, e).
3. ``outer_iterations`` times: set W in closed form
   (w_d = sqrt(N / (y_d^T K_Y^-1 y_d + 1/kappa^2)), kappa^2 = 1e6), then run
   L-BFGS-B for at most ``max_iterations`` iterations on (X, ln alpha, ln beta)
   with the exact gradient of :mod:`latentoc.gpdm.objective`.
4. A final closed-form W update; the recorded objective uses that W.

Balanced GPDM (Urtasun et al. 2006): the dynamics term is multiplied by
lambda = D/d (``balanced=True``).  Default: ``balanced=False``, chosen by
measurement.  Data: the benchmark's smooth motion (N = 150, D = 37, d = 3) and
the tests' latent circle (N = 80, D = 20, d = 2, tanh of a random linear map),
each with white noise of std 0.01, 0.05, 0.2 and known noise-free signal.
Measures: roughness r = mean|Delta^2 x| / mean|Delta x| of the latent
trajectory (:func:`roughness`; PCA gives 0.16-1.25 on these data) and the RMS
of mu_Q(X) against the noise-free signal ("clean RMS").  Converged runs
(10 outer x 200 iterations), plain vs balanced, r and clean RMS:

=========  ======  ===============  ===============
data       noise   plain r / RMS    balanced r / RMS
=========  ======  ===============  ===============
motion     0.01    0.105 / 0.0028   0.129 / 0.0032
circle     0.01    0.170 / 0.0045   0.305 / 0.0049
motion     0.05    0.138 / 0.0148   0.189 / 0.0185
circle     0.05    0.172 / 0.0212   0.160 / 0.0229
motion     0.20    0.122 / 0.0499   0.166 / 0.0775
circle     0.20    0.160 / 0.0842   0.201 / 0.0591
=========  ======  ===============  ===============

The plain GPDM was smoother in 5 of 6 cases and closer to the noise-free
signal in 5 of 6; the balanced model fits the noisy training poses more
closely (lower training RMS, smaller learned noise), i.e. it overfits the
noise, and did not give smoother latent trajectories here.  The default
budget (5 x 60 iterations) shows the same pattern.  Both are smooth relative
to PCA; for mocap with D >> d the balanced variant remains available.
"""

from __future__ import annotations

import ctypes
import json
import time
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Iterator, Sequence

import numpy as np
from scipy.optimize import minimize

from ..errors import LatentocError
from .objective import KAPPA_SQ, GPDMProblem, neg_log_posterior, optimal_w, pack, unpack

if TYPE_CHECKING:  # pragma: no cover
    from .model import GPDM

__all__ = ["GPDMSettings", "GPDMInputError", "learn_gpdm", "prepare_data",
           "pca_initialization", "roughness"]


class GPDMInputError(LatentocError, ValueError):
    """Invalid training data or settings for GPDM learning."""


@dataclass
class GPDMSettings:
    """Settings of :func:`learn_gpdm` (all recorded in the learned model)."""

    latent_dim: int = 3
    balanced: bool = False  # see module docstring for the measurement
    outer_iterations: int = 5
    max_iterations: int = 60
    seed: int = 0  # only used by init="random"
    init: str = "pca"  # "pca" or "random"
    kappa_sq: float = KAPPA_SQ
    alpha0: tuple[float, ...] = (0.9, 1.0, 0.1, float(np.e))
    beta0: tuple[float, ...] = (1.0, 1.0, float(np.e))
    log_hyper_bound: float = 18.0  # |ln alpha_i|, |ln beta_i| <= this
    # Optional upper bound on beta_3, i.e. a floor 1/beta3_max on the observation noise
    # variance (W-scaled units).  None (default): only log_hyper_bound applies.
    beta3_max: float | None = None
    gtol: float = 1e-6
    blas_threads: int | None = 1  # BLAS threads during learning (None: leave as is)

    def to_json(self) -> str:
        """Settings as a JSON string."""
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "GPDMSettings":
        """Inverse of :meth:`to_json`."""
        data = json.loads(text)
        for key in ("alpha0", "beta0"):
            if key in data:
                data[key] = tuple(data[key])
        return cls(**data)


def _check_settings(settings: GPDMSettings) -> None:
    if not isinstance(settings.latent_dim, (int, np.integer)) or settings.latent_dim < 1:
        raise GPDMInputError(f"settings.latent_dim must be a positive integer, got {settings.latent_dim!r}")
    if settings.outer_iterations < 1 or settings.max_iterations < 1:
        raise GPDMInputError("settings.outer_iterations and settings.max_iterations must be >= 1")
    if settings.init not in ("pca", "random"):
        raise GPDMInputError(f"settings.init must be 'pca' or 'random', got {settings.init!r}")
    if len(settings.alpha0) != 4 or len(settings.beta0) != 3 or min(settings.alpha0) <= 0 \
            or min(settings.beta0) <= 0:
        raise GPDMInputError("settings.alpha0 must be 4 positive numbers and settings.beta0 3 positive numbers")
    if settings.beta3_max is not None and not settings.beta3_max > 0:
        raise GPDMInputError(f"settings.beta3_max must be positive or None, got {settings.beta3_max!r}")


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


def pca_initialization(Yc: np.ndarray, d: int) -> np.ndarray:
    """PCA scores of centred data, scaled so the first column has unit std."""
    U, S, _ = np.linalg.svd(Yc, full_matrices=False)
    X = U[:, :d] * S[:d]
    # deterministic signs: largest-magnitude entry of each column positive
    idx = np.argmax(np.abs(X), axis=0)
    X = X * np.sign(X[idx, np.arange(d)])
    sd = float(np.std(X[:, 0]))
    return X / sd if sd > 0 else X


def roughness(X: np.ndarray) -> float:
    """mean |x_{t+1} - 2 x_t + x_{t-1}| / mean |x_{t+1} - x_t| of one trajectory.

    Scale invariant.  For a circle sampled with n points per turn it is
    2 sin(pi/n) (0.1 for n = 60); for white noise it is about sqrt(3) ~ 1.7.
    """
    X = np.asarray(X, dtype=float)
    d1 = np.linalg.norm(np.diff(X, axis=0), axis=1).mean()
    d2 = np.linalg.norm(np.diff(X, n=2, axis=0), axis=1).mean()
    return float(d2 / d1)


_GET_NAMES = ("openblas_get_num_threads", "openblas_get_num_threads64_",
              "scipy_openblas_get_num_threads", "scipy_openblas_get_num_threads64_")
_SET_NAMES = ("openblas_set_num_threads", "openblas_set_num_threads64_",
              "scipy_openblas_set_num_threads", "scipy_openblas_set_num_threads64_")


def _openblas_handles() -> list[tuple]:
    handles = []
    try:
        with open("/proc/self/maps") as fh:
            paths = {line.split()[-1] for line in fh if "openblas" in line.lower() and "/" in line}
    except OSError:
        return handles
    for p in sorted(paths):
        try:
            lib = ctypes.CDLL(p)
        except OSError:
            continue
        get = next((getattr(lib, n) for n in _GET_NAMES if hasattr(lib, n)), None)
        set_ = next((getattr(lib, n) for n in _SET_NAMES if hasattr(lib, n)), None)
        if get is not None and set_ is not None:
            handles.append((get, set_))
    return handles


@contextmanager
def _blas_threads(n: int | None) -> Iterator[None]:
    """Temporarily limit OpenBLAS threads (best effort; no-op if not found).

    The kernel matrices are only a few hundred wide; on a small shared machine
    multi-threaded BLAS was measured up to 10x slower than one thread.
    """
    if n is None:
        yield
        return
    handles = []
    try:
        for get, set_ in _openblas_handles():
            old = int(get())
            set_(int(n))
            handles.append((set_, old))
    except Exception:  # pragma: no cover - defensive
        pass
    try:
        yield
    finally:
        for set_, old in handles:
            set_(old)


def learn_gpdm(Y: np.ndarray | Sequence[np.ndarray], settings: GPDMSettings | None = None,
               verbose: bool = False) -> "GPDM":
    """Learn a GPDM from one sequence (N x D) or a list of sequences (Eq. 16)."""
    from .model import GPDM

    settings = GPDMSettings() if settings is None else settings
    _check_settings(settings)
    d = int(settings.latent_dim)
    Ys, lengths = prepare_data(Y, d)
    N, D = Ys.shape
    Y_mean = Ys.mean(axis=0)
    Yc = Ys - Y_mean

    if settings.init == "pca":
        X = pca_initialization(Yc, d)
    else:
        X = np.random.default_rng(settings.seed).standard_normal((N, d))
    alpha = np.asarray(settings.alpha0, dtype=float)
    beta = np.asarray(settings.beta0, dtype=float)
    lam = D / d if settings.balanced else 1.0
    problem = GPDMProblem(Yc, lengths, d, dynamics_weight=lam)
    v = pack(X, alpha, beta)
    b = float(settings.log_hyper_bound)
    bounds = [(None, None)] * (N * d) + [(-b, b)] * 7
    if settings.beta3_max is not None:
        bounds[-1] = (-b, min(b, float(np.log(settings.beta3_max))))
        v[-1] = np.clip(v[-1], *bounds[-1])
    t0 = time.perf_counter()
    f = np.nan
    with _blas_threads(settings.blas_threads):
        for it in range(settings.outer_iterations):
            X, alpha, beta = unpack(v, N, d)
            w = optimal_w(Yc, X, beta, settings.kappa_sq)
            res = minimize(neg_log_posterior, v, args=(problem, w), jac=True, method="L-BFGS-B",
                           bounds=bounds,
                           options={"maxiter": settings.max_iterations, "gtol": settings.gtol,
                                    "maxcor": 20})
            v = res.x
            f = float(res.fun)
            if verbose:
                print(f"outer {it}: L = {f:.6g} ({res.nit} iterations, {res.message}) "
                      f"{time.perf_counter() - t0:.2f} s")
        X, alpha, beta = unpack(v, N, d)
        w = optimal_w(Yc, X, beta, settings.kappa_sq)
        f = float(neg_log_posterior(v, problem, w, with_grad=False))
    return GPDM(X=np.array(X), sequence_lengths=list(lengths), alpha=np.array(alpha),
                beta=np.array(beta), W=np.array(w), Y_mean=Y_mean, Y=Ys,
                settings=settings, objective_value=f)
