"""The motions GPDM learning is timed on (``python -m latentoc bench gpdm``): several kinds of
motion, each N = 350 frames of D = 37 dimensions from a fixed seed, so that learning is measured on
data it was not tuned on, not only on its own synthetic set.

* ``synthetic``: a linear mix of the first three harmonics of a phase over two periods, plus white
  noise 0.01 (:func:`synthetic_motion`, the set the learner was first measured on);
* ``jump``: the broad jump's training set (the CMU jump, 157 x 37 learned coordinates) resampled to
  350 frames by a cubic spline in time;
* ``panda``: the panda reach (examples/panda-reach/reach.csv, 251 frames of 7 joints) resampled to 350
  frames and seen as 37 measurements: the 7 joint angles, the positions of 7 moving links (link3,
  link4, link5, link7, link8, both fingers; 21) and the orientation of the hand's tool frame (9);
* ``loops``: a limacon with an inner loop, run twice around, lifted to 37 dimensions through
  tanh(Z A + b) (A, b Gaussian) plus white noise 0.05;
* ``walk``: a slow random walk in all 37 dimensions, Gaussian steps of 0.03.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

__all__ = ["MINIMA", "MOTIONS", "PANDA", "SAME_RTOL", "benchmark_motion", "resampled", "same_minimum",
           "synthetic_motion"]

ROOT = Path(__file__).resolve().parents[2]
PANDA = ROOT / "examples" / "panda-reach" / "reach.csv"
N, D = 350, 37


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


def resampled(Y: np.ndarray, n: int) -> np.ndarray:
    """The frames of ``Y`` resampled to ``n`` evenly spaced ones by a cubic spline through them."""
    from scipy.interpolate import CubicSpline

    return np.asarray(CubicSpline(np.linspace(0.0, 1.0, len(Y)), Y, axis=0)(np.linspace(0.0, 1.0, n)))


def _jump() -> np.ndarray:
    from latentoc.jump.demonstration.training import training_jumps

    return resampled(training_jumps(0)[0].Y, N)


#: the panda's moving link frames measured by the ``panda`` motion (frames with the same origin left out)
PANDA_LINKS = ("panda_link3", "panda_link4", "panda_link5", "panda_link7", "panda_link8", "panda_leftfinger",
               "panda_rightfinger")


def _panda() -> np.ndarray:
    import pinocchio as pin

    from latentoc.robots.catalog import load_robot

    model = load_robot("panda")
    data = model.createData()
    Q = resampled(np.loadtxt(PANDA, delimiter=",", skiprows=1)[:, 1:], N)
    links = [model.getFrameId(name) for name in PANDA_LINKS]
    tool = model.getFrameId("panda_hand_tcp")
    rows = []
    for q in Q:
        pin.framesForwardKinematics(model, data, np.r_[q, 0.02, 0.02])  # the fingers held as the README's learn
        rows.append(np.concatenate([q, *(data.oMf[i].translation for i in links), data.oMf[tool].rotation.ravel()]))
    return np.array(rows)


def _loops() -> np.ndarray:
    rng = np.random.default_rng(0)
    th = np.linspace(0.0, 4.0 * np.pi, N)
    r = 0.5 + np.cos(th)  # a limacon: a loop inside a loop
    Z = np.stack([r * np.cos(th), r * np.sin(th), 0.3 * np.sin(th)], axis=1)
    A, b = rng.standard_normal((3, D)), 0.3 * rng.standard_normal(D)
    return np.tanh(Z @ A + b) + 0.05 * rng.standard_normal((N, D))


def _walk() -> np.ndarray:
    return np.cumsum(0.03 * np.random.default_rng(0).standard_normal((N, D)), axis=0)


#: the benchmark's motions by name (module doc), each N x D
MOTIONS: dict[str, Callable[[], np.ndarray]] = {
    "synthetic": lambda: synthetic_motion(N, D), "jump": _jump, "panda": _panda, "loops": _loops, "walk": _walk}


#: Eq. 16 where the saddle-free learner ends on each motion (commit f403ce1; numpy 2.4.6, scipy 1.17.1, one BLAS
#: thread): a faster learner has to end in the same minimum, :func:`same_minimum`
MINIMA = {"synthetic": -128052.931856500, "jump": -185778.536748996, "panda": -179544.038854470,
          "loops": -109894.254462249, "walk": -115610.586224990}
#: how far apart (relative) two values of Eq. 16 may be and still be one minimum: the saddle-free learner's own
#: values scatter by up to 6.7e-10 from starts perturbed by 1e-10, the closest different minima measured are
#: 1.2e-5 apart (docs/gpdm.md, "Motions it was not tuned on")
SAME_RTOL = 1e-8


def same_minimum(value: float, reference: float, rtol: float = SAME_RTOL) -> bool:
    """Whether Eq. 16 = ``value`` is the ``reference`` minimum: within rtol max(|L|, 1) of it."""
    return abs(value - reference) <= rtol * max(abs(reference), 1.0)


def benchmark_motion(name: str) -> np.ndarray:
    """The motion ``name`` of :data:`MOTIONS` (350 x 37)."""
    Y = MOTIONS[name]()
    assert Y.shape == (N, D), (name, Y.shape)
    return Y
