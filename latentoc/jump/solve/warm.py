"""A point and its multipliers carried from one jump NLP into another with more rows or samples.

The exchange (:mod:`.exchange`) and a sweep's warm start resume from a solution of an NLP whose
selection is a subset of the new one's. Variables are matched by block and, for the samples, by
time (a new sample's variables follow from the rest of the point, :func:`.initial_point.sample_values`);
rows by their family, name, time and component. New variables and rows start with zero
multipliers.
"""
from __future__ import annotations

import numpy as np

from latentoc.jump.transcription.nlp import JumpNLP
from latentoc.jump.solve.initial_point import sample_values

__all__ = ["carried_point", "carried_multipliers", "row_keys"]

_SAMPLES = {"lam_sample": "contact", "flight_sample": "flight"}  # variable block -> its Selection times


def _key(t: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(t, float), 9)


def _variable_map(old: JumpNLP, new: JumpNLP) -> tuple[np.ndarray, np.ndarray]:
    """Positions (in new, in old) of the variables both NLPs share."""
    dst, src = [], []
    for name in new.variables.shapes:
        a, b = new.variables.index(name), old.variables.index(name)
        if name in _SAMPLES:
            ta, tb = (_key(getattr(n.selection, _SAMPLES[name])) for n in (new, old))
            common, ia, ib = np.intersect1d(ta, tb, return_indices=True)
            a, b = a[ia], b[ib]
        elif a.shape != b.shape:
            raise ValueError(f"variable block {name!r} has shape {b.shape} in the old NLP, {a.shape} in the new")
        dst.append(a.ravel())
        src.append(b.ravel())
    return np.concatenate(dst), np.concatenate(src)


def carried_point(old: JumpNLP, new: JumpNLP, w: np.ndarray, lam_x: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """``w`` (a point of ``old``) in ``new``'s variables, the new samples' variables following from
    the rest; and the bound multipliers ``lam_x`` carried (zero for new variables)."""
    dst, src = _variable_map(old, new)
    x = np.zeros(new.variables.n)
    x[dst] = np.asarray(w, float)[src]
    lx = np.zeros(new.variables.n)
    if lam_x is not None:
        lx[dst] = np.asarray(lam_x, float)[src]
    fresh = np.ones(new.variables.n, bool)
    fresh[dst] = False
    if fresh.any():
        x = np.where(fresh, sample_values(new, np.clip(x, new.lbx, new.ubx)), x)
    return x, lx


def row_keys(nlp: JumpNLP) -> list[tuple[str, str, float, int]]:
    """A key per constraint row: (family, name, time, component), the same for the same row in NLPs
    with other selections."""
    fam = np.empty(nlp.nlp.m, object)
    for f in nlp.nlp.families:
        sl = nlp.family_rows(f.name)
        fam[sl] = f.name
    return list(zip(fam.tolist(), nlp.row_names.tolist(), _key(nlp.row_times).tolist(), nlp.row_components.tolist()))


def carried_multipliers(old: JumpNLP, new: JumpNLP, lam_g: np.ndarray) -> np.ndarray:
    """``old``'s row multipliers on ``new``'s rows (zero for the new rows)."""
    index = {k: i for i, k in enumerate(row_keys(old))}
    lam_g = np.asarray(lam_g, float)
    return np.array([lam_g[index[k]] if k in index else 0.0 for k in row_keys(new)])
