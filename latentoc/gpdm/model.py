"""The learned GPDM and its predictive functions (Kang & Park 2015, Eq. 17-19,
29, 30).

Conventions:

* ``mean(x)`` is Eq. 18 in the original data units: the GP is fitted to the
  centred, W-scaled data Yc W, so ``q(x) = Y_mean + (k(x)^T K_Y^-1 Yc W) / W``.
* ``variance(x)`` is Eq. 19 for the scaled data, one scalar per point::

      sigma^2(x) = k_Q(x, x) - k(x)^T K_Y^-1 k(x) = beta1 + 1/beta3 - k(x)^T K_Y^-1 k(x)

  where k(x) = [beta1 exp(-beta2/2 |x - x_i|^2)]_i has no noise term and
  k_Q(x, x) includes the noise 1/beta3 (predictive variance of a new noisy
  pose).  It lies between 1/beta3-ish on the training points and
  beta1 + 1/beta3 far from them.  The variance of output dimension j in
  original units is sigma^2(x) / w_j^2.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import solve_triangular

from latentoc.gpdm.kernels import rbf_linear_kernel
from latentoc.gpdm.objective import safe_cholesky, sequence_indices
from latentoc.gpdm.learning_settings import GPDMSettings

if TYPE_CHECKING:  # pragma: no cover
    import casadi

__all__ = ["GPDM", "LearningReport"]


@dataclass(frozen=True)
class LearningReport:
    """How learning (Eq. 16) ended: Newton iterations and objective evaluations, the final max |dL/dv|
    over the free variables and Newton decrement (the decrease of L a Newton step predicts), whether
    the convergence test held (never at the safety cap or a bound), the last message and the time (s)."""

    iterations: int = 0
    evaluations: int = 0
    gradient_norm: float = float("nan")
    newton_decrement: float = float("nan")
    converged: bool = False
    message: str = ""
    time_s: float = 0.0


def _as_points(x: np.ndarray, d: int) -> tuple[np.ndarray, bool]:
    x = np.asarray(x, dtype=float)
    single = x.ndim == 1
    x2 = np.atleast_2d(x)
    if x2.ndim != 2 or x2.shape[1] != d:
        raise ValueError(f"x: expected shape ({d},) or (n, {d}), got {x.shape}")
    return x2, single


@dataclass(eq=False)
class GPDM:
    """A learned GPDM (see :func:`latentoc.gpdm.learn_gpdm`)."""

    X: np.ndarray  # N x d latent points, all sequences stacked
    sequence_lengths: list[int]
    alpha: np.ndarray  # (4,) dynamics kernel, Eq. 15
    beta: np.ndarray  # (3,) observation kernel, Eq. 11
    W: np.ndarray  # (D,) per-dimension scales
    Y_mean: np.ndarray  # (D,)
    Y: np.ndarray  # N x D original (uncentred) training data
    settings: GPDMSettings
    objective_value: float
    learning: LearningReport = field(default_factory=LearningReport)
    _cache: dict = field(default_factory=dict, init=False, repr=False)

    # ------------------------------------------------------------------ basics
    @property
    def latent_dim(self) -> int:
        return int(self.X.shape[1])

    @property
    def output_dim(self) -> int:
        return int(self.Y.shape[1])

    @property
    def noise_variance(self) -> float:
        """Observation noise variance 1/beta3 (in W-scaled units)."""
        return float(1.0 / self.beta[2])

    @property
    def prior_variance(self) -> float:
        """beta1 + 1/beta3: sigma^2 (Eq. 19) far from the training points, the largest it can be."""
        return float(self.beta[0] + 1.0 / self.beta[2])

    def learning_summary(self) -> dict[str, float | int | bool]:
        """How learning ended, as solve results report it (``gpdm_*`` keys; :class:`LearningReport`)."""
        r = self.learning
        return {"gpdm_objective": float(self.objective_value), "gpdm_iterations": int(r.iterations),
                "gpdm_evaluations": int(r.evaluations), "gpdm_gradient_norm": float(r.gradient_norm),
                "gpdm_newton_decrement": float(r.newton_decrement), "gpdm_converged": bool(r.converged)}

    def latent_trajectories(self) -> list[np.ndarray]:
        """The latent trajectory of each training sequence (N_i x d arrays)."""
        out, start = [], 0
        for n in self.sequence_lengths:
            out.append(self.X[start:start + n].copy())
            start += n
        return out

    # ------------------------------------------------------------- precompute
    def _obs(self) -> dict:
        c = self._cache.get("obs")
        if c is None:
            X = np.asarray(self.X, dtype=float)
            b1, b2, b3 = self.beta
            r2 = np.sum((X[:, None, :] - X[None, :, :]) ** 2, axis=-1)
            K = b1 * np.exp(-0.5 * b2 * r2)
            K[np.diag_indices_from(K)] += 1.0 / b3
            L, _ = safe_cholesky(K)
            Yw = (self.Y - self.Y_mean) * self.W
            Linv = solve_triangular(L, np.eye(L.shape[0]), lower=True)
            A = Linv.T @ (Linv @ Yw)  # K_Y^-1 (Yc W)
            c = {"Linv": Linv, "A": A}
            self._cache["obs"] = c
        return c

    def _kvec(self, x2: np.ndarray) -> np.ndarray:
        b1, b2, _ = self.beta
        r2 = np.sum((x2[:, None, :] - self.X[None, :, :]) ** 2, axis=-1)
        return b1 * np.exp(-0.5 * b2 * r2)

    # ------------------------------------------------------------ predictions
    def mean(self, x: np.ndarray) -> np.ndarray:
        """Mean pose mu_Q(x) of Eq. 18 in original data units; (D,) or (n, D)."""
        x2, single = _as_points(x, self.latent_dim)
        q = self.Y_mean + (self._kvec(x2) @ self._obs()["A"]) / self.W
        return q[0] if single else q

    def variance(self, x: np.ndarray) -> np.ndarray | float:
        """sigma^2(x) of Eq. 19 (see module docstring); scalar or (n,)."""
        x2, single = _as_points(x, self.latent_dim)
        b1, _, b3 = self.beta
        v = self._kvec(x2) @ self._obs()["Linv"].T
        s = b1 + 1.0 / b3 - np.sum(v * v, axis=1)
        return float(s[0]) if single else s

    def reconstruction_rmse(self) -> float:
        """RMS over all entries of mean(X) - Y (original units)."""
        return float(np.sqrt(np.mean((self.mean(self.X) - self.Y) ** 2)))

    # --------------------------------------------------------------- dynamics
    def _dyn(self) -> dict:
        c = self._cache.get("dyn")
        if c is None:
            i_in, i_out, _ = sequence_indices(self.sequence_lengths)
            Xin, Xout = self.X[i_in], self.X[i_out]
            K = rbf_linear_kernel(Xin, None, self.alpha, noise=True)
            L, _ = safe_cholesky(K)
            B = solve_triangular(L, Xout, lower=True)
            c = {"Xin": Xin, "A": solve_triangular(L.T, B, lower=False)}
            self._cache["dyn"] = c
        return c

    def predict_next(self, x: np.ndarray) -> np.ndarray:
        """One-step latent dynamics mean X_out^T K_X^-1 k_X(x) (Eq. 14, 15)."""
        x2, single = _as_points(x, self.latent_dim)
        c = self._dyn()
        a = np.array(self.alpha, dtype=float)
        k = rbf_linear_kernel(x2, c["Xin"], a)
        out = k @ c["A"]
        return out[0] if single else out

    def simulate(self, x0: np.ndarray, steps: int) -> np.ndarray:
        """Iterate the mean dynamics from x0; returns (steps + 1, d)."""
        x = np.asarray(x0, dtype=float).reshape(self.latent_dim)
        out = np.empty((int(steps) + 1, self.latent_dim))
        out[0] = x
        for t in range(int(steps)):
            out[t + 1] = self.predict_next(out[t])
        return out

    # ------------------------------------------------------------------ tube
    def tube_size(self, trajectories: list[np.ndarray] | None = None,
                  samples_per_segment: int = 10) -> float:
        """Eq. 30: smallest delta such that every trajectory lies in T_delta (Eq. 29).

        sigma^2 is evaluated on the piecewise linear path through each
        trajectory's points, ``samples_per_segment`` intervals per segment
        (end points included).
        """
        trajs = self.latent_trajectories() if trajectories is None else trajectories
        s = np.linspace(0.0, 1.0, int(samples_per_segment) + 1)[None, :, None]
        best = -np.inf
        for T in trajs:
            T = np.atleast_2d(np.asarray(T, dtype=float))
            if T.shape[0] == 1:
                pts = T
            else:
                pts = (T[:-1, None, :] * (1.0 - s) + T[1:, None, :] * s).reshape(-1, T.shape[1])
            best = max(best, float(np.max(self.variance(pts))))
        return best

    # ----------------------------------------------------------------- casadi
    def _casadi_exprs(self) -> dict:
        c = self._cache.get("casadi")
        if c is None:
            import casadi as ca

            d, N = self.latent_dim, self.X.shape[0]
            o = self._obs()
            b1, b2, b3 = (float(v) for v in self.beta)
            x = ca.SX.sym("x", d)
            diff = ca.DM(self.X) - ca.repmat(x.T, N, 1)
            r2 = ca.sum2(diff * diff)
            k = b1 * ca.exp(-0.5 * b2 * r2)
            q = ca.DM(self.Y_mean) + ca.mtimes(ca.DM(o["A"].T), k) / ca.DM(self.W)
            v = ca.mtimes(ca.DM(o["Linv"]), k)
            s2 = (b1 + 1.0 / b3) - ca.dot(v, v)
            c = {"mean": ca.Function("gpdm_mean", [x], [q], ["x"], ["q"]),
                 "variance": ca.Function("gpdm_variance", [x], [s2], ["x"], ["sigma2"])}
            self._cache["casadi"] = c
        return c

    def mean_function(self) -> "casadi.Function":
        """casadi.Function x (d) -> q (D), equal to :meth:`mean` (SX, cached)."""
        return self._casadi_exprs()["mean"]

    def variance_function(self) -> "casadi.Function":
        """casadi.Function x (d) -> sigma2 (1), equal to :meth:`variance` (SX, cached)."""
        return self._casadi_exprs()["variance"]

    # ------------------------------------------------------------- save/load
    def save(self, path: str | Path) -> None:
        """Save to .npz (arrays, training data, settings as JSON)."""
        np.savez(Path(path), X=self.X, sequence_lengths=np.asarray(self.sequence_lengths, dtype=np.int64),
                 alpha=self.alpha, beta=self.beta, W=self.W, Y_mean=self.Y_mean, Y=self.Y,
                 objective_value=np.float64(self.objective_value),
                 settings_json=np.str_(self.settings.to_json()),
                 learning_json=np.str_(json.dumps(asdict(self.learning))))

    @classmethod
    def load(cls, path: str | Path) -> "GPDM":
        """Load a model written by :meth:`save`."""
        with np.load(Path(path), allow_pickle=False) as f:
            learning = LearningReport(**json.loads(str(f["learning_json"]))) if "learning_json" in f \
                else LearningReport(message="not recorded")
            return cls(X=f["X"], sequence_lengths=[int(n) for n in f["sequence_lengths"]],
                       alpha=f["alpha"], beta=f["beta"], W=f["W"], Y_mean=f["Y_mean"], Y=f["Y"],
                       settings=GPDMSettings.from_json(str(f["settings_json"])),
                       objective_value=float(f["objective_value"]), learning=learning)
