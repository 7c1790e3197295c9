"""Where learning (Eq. 16) starts: PCA scores and the settings' hyperparameters, or, for a recording
of more than COARSE_ABOVE frames, the model of every second frame with its latent points
interpolated to all frames; that model starts from its own every second frame, and so on down to
COARSE_DOWN_TO frames, which start from PCA (coarse to fine: :func:`~latentoc.gpdm.learning.learn_gpdm`,
measured in docs/gpdm.md)."""
from __future__ import annotations

from typing import Any

import numpy as np

from latentoc.gpdm.objective import HYPER_NAMES, pack

__all__ = ["COARSE_ABOVE", "COARSE_DOWN_TO", "coarse_frames", "initial_variables", "interpolated_start", "pca_initialization"]

#: learning on more frames than this starts from the model of every second frame (docs/gpdm.md) ...
COARSE_ABOVE = 200
#: ... whose own start halves the frames again while they are more than this
COARSE_DOWN_TO = 100


def pca_initialization(Yc: np.ndarray, d: int) -> np.ndarray:
    """PCA scores of centred data, scaled so the first column has unit std."""
    U, S, _ = np.linalg.svd(Yc, full_matrices=False)
    X = U[:, :d] * S[:d]
    # deterministic signs: largest-magnitude entry of each column positive
    idx = np.argmax(np.abs(X), axis=0)
    X = X * np.sign(X[idx, np.arange(d)])
    sd = float(np.std(X[:, 0]))
    return X / sd if sd > 0 else X


def initial_variables(Yc: np.ndarray, settings: Any) -> np.ndarray:
    """The packed start (:func:`~latentoc.gpdm.objective.pack`): PCA (or, with ``init="random"``,
    seeded normal) latent points and the settings' alpha0, beta0 with the fixed values."""
    N, d = Yc.shape[0], int(settings.latent_dim)
    if settings.init == "pca":
        X = pca_initialization(Yc, d)
    else:
        X = np.random.default_rng(settings.seed).standard_normal((N, d))
    theta = np.concatenate([settings.alpha0, settings.beta0]).astype(float)
    for name, value in settings.fixed.items():
        theta[HYPER_NAMES.index(name)] = float(value)
    return pack(X, theta[:4], theta[4:])


def coarse_frames(lengths: list[int]) -> list[np.ndarray]:
    """Every second frame of each sequence, its last frame kept (indices within the sequence); a
    sequence of fewer than 5 frames keeps them all (a sequence needs 3)."""
    out = []
    for n in lengths:
        idx = np.arange(0, n, 2) if n >= 5 else np.arange(n)
        out.append(idx if idx[-1] == n - 1 else np.append(idx, n - 1))
    return out


def interpolated_start(X_coarse: np.ndarray, theta: np.ndarray, lengths: list[int],
                       frames: list[np.ndarray]) -> np.ndarray:
    """The packed start of the full data: the coarse model's latent points (stacked by sequence, at
    ``frames``) interpolated linearly to every frame, and its hyperparameters ``theta`` (7)."""
    parts, start = [], 0
    for n, idx in zip(lengths, frames):
        Xc = X_coarse[start:start + len(idx)]
        parts.append(np.column_stack([np.interp(np.arange(n), idx, Xc[:, a]) for a in range(Xc.shape[1])]))
        start += len(idx)
    return pack(np.vstack(parts), theta[:4], theta[4:])
