"""GPDM learning benchmark: learning time and final objective (Eq. 16) for
N = 150 and 350 frames, D = 7 and 37, d = 3 on synthetic smooth motion data.

Run: ``python -m latentoc.benchmarks.gpdm_bench [--quick]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.gpdm.learning import roughness


def synthetic_motion(N: int, D: int, seed: int = 0, cycles: float = 2.0,
                     noise: float = 0.01) -> np.ndarray:
    """Smooth periodic 'joint angle' data: each column a random mix of the
    first three harmonics of a phase running over ``cycles`` periods, plus
    small white noise (fixed seed)."""
    rng = np.random.default_rng(seed)
    phase = np.linspace(0.0, 2.0 * np.pi * cycles, N)
    H = np.stack([f(k * phase) for k in (1, 2, 3) for f in (np.sin, np.cos)], axis=1)
    H = H / np.array([1, 1, 2, 2, 3, 3])
    M = rng.standard_normal((H.shape[1], D))
    return H @ M + rng.standard_normal(D) + noise * rng.standard_normal((N, D))


def main(argv: list[str] | None = None) -> int:
    """Print learning time and final objective for each benchmark size."""
    p = argparse.ArgumentParser(prog="gpdm_bench", description=__doc__)
    p.add_argument("--quick", action="store_true", help="only N=150")
    p.add_argument("--balanced", action="store_true", help="balanced GPDM (lambda = D/d)")
    args = p.parse_args(argv)
    sizes = [(150, 7), (150, 37)] + ([] if args.quick else [(350, 7), (350, 37)])
    settings = GPDMSettings(latent_dim=3)
    if args.balanced:
        settings.balanced = True
    print(f"GPDM learning benchmark (d=3, balanced={settings.balanced}, "
          f"ftol={settings.ftol:g}, max_iterations={settings.max_iterations})")
    print(f"{'N':>5} {'D':>4} {'time [s]':>9} {'objective':>13} {'rec. RMS':>9} {'roughness':>9}")
    for N, D in sizes:
        Y = synthetic_motion(N, D, seed=0)
        t0 = time.perf_counter()
        model = learn_gpdm(Y, settings)
        dt = time.perf_counter() - t0
        print(f"{N:5d} {D:4d} {dt:9.2f} {model.objective_value:13.6g} "
              f"{model.reconstruction_rmse():9.4f} {roughness(model.X):9.4f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
