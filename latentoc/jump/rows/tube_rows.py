"""The tube sigma^2 <= delta (Eq. 29) at the selection's times: the GP layer's alone, no robot block.

The rows are relative (sigma^2 / delta <= 1) so that Ipopt's tolerances are relative to delta.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from latentoc.nlp.assemble import Family

from latentoc.nlp.evaluators import VarianceEvaluator
from latentoc.jump.transcription.wiring import Wiring

TUBE_SPACING = 0.005  # s between the tube's points (and the joint limits' rows)


def wire(w: Wiring) -> None:
    t = np.asarray(w.selection.tube, float)
    if not len(t):
        return
    assert w.layer.has_tube  # build_nlp puts no tube on a joint path
    ni = w.inputs(len(t))
    w.latent(ni, t, orders=1)
    S, s0 = ni.build()
    w.families.append(Family("tube", VarianceEvaluator(w.layer), S, s0,
                             Cg=sp.identity(len(t), format="csr") / w.settings.tube))
    w.record(["tube"] * len(t), t, [0] * len(t))
