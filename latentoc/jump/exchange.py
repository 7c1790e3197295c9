"""Rows only where they can bind: an exchange of the sampled rows against the 1 kHz grid.

The wrench samples in contact and the flight's torque rows are not tied to variables, so they
can sit at any time. The solve starts with the packaged samples
(:func:`latentoc.jump.nlp.default_samples`); after each converged solve every sampled row is evaluated on the 1 kHz grid (:func:`candidates`), the worst
time of each violated stretch is added (:func:`binding_times`), and
the solve resumes from its point and multipliers. It stops when no 1 kHz time is violated by
more than ``tol``, so these rows hold on the exported grid, not only at the samples.
"""
from __future__ import annotations

import numpy as np

from .nlp import JumpNLP, Samples
from .phases import Phases

__all__ = ["candidates", "binding_times", "EXCHANGED", "NEIGHBOURS"]

EXCHANGED = {"wrench": "wrench", "flight_torque": "flight_torque", "tube": "tube"}  # Samples field -> family
NEIGHBOURS = (-0.002, 0.002)  # s: added with each violated stretch's worst time


def candidates(phases: Phases, rate_hz: float = 1000.0) -> Samples:
    """The 1 kHz grid's times in contact (wrench rows), in flight (torque rows) and inside (tube)."""
    t = np.linspace(0.0, phases.duration, int(round(phases.duration * rate_hz)) + 1)
    contact = (t < phases.takeoff) | (t > phases.touchdown)
    flight = (t >= phases.takeoff) & (t <= phases.touchdown)
    inside = (t > 0) & (t < phases.duration)
    return Samples(t[contact & inside], t[flight], t[inside])


def binding_times(probe: JumpNLP, w: np.ndarray, tol: dict[str, float]) -> tuple[Samples, dict[str, float]]:
    """Where the sampled rows, evaluated at ``w`` in ``probe`` (an NLP whose samples are the
    :func:`candidates`), are violated by more than ``tol[family]``: each violated stretch of the 1 kHz
    grid gives its worst time, a local minimum of the slack. Also the largest violation of each
    exchanged family (in the rows' units: body weights, torque limit ranges)."""
    g = probe.nlp.constraints(w)
    slack = np.minimum(g - probe.lbg, probe.ubg - g)  # < 0: violated
    times = probe.meta["row_times"]
    out, worst = {}, {}
    for field, fam in EXCHANGED.items():
        off = probe.nlp.row_offset.get(fam)
        if off is None:
            out[field], worst[fam] = np.zeros(0), 0.0
            continue
        n = next(f.n_rows for f in probe.nlp.families if f.name == fam)
        tt, inv = np.unique(times[off:off + n], return_inverse=True)
        per_time = np.full(len(tt), np.inf)
        np.minimum.at(per_time, inv, slack[off:off + n])
        worst[fam] = float(max(0.0, -per_time.min(initial=np.inf)))
        left = np.concatenate([[np.inf], per_time[:-1]])
        right = np.concatenate([per_time[1:], [np.inf]])
        worst_t = tt[(per_time < -tol[fam]) & (per_time <= left) & (per_time <= right)]
        near = np.concatenate([worst_t] + [worst_t + dt for dt in NEIGHBOURS])
        out[field] = np.unique(tt[np.isin(np.round(tt, 6), np.round(near, 6))])
    return Samples(out["wrench"], out["flight_torque"], out["tube"]), worst
