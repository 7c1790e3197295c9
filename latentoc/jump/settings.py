"""The broad jump's settings (Table 5 and the discretisation), declared once with their defaults."""
from __future__ import annotations

from dataclasses import dataclass

from latentoc.jump.robot.feet import MU


@dataclass
class JumpSettings:
    """What the transcription and the solve need; the problem file sets them (:mod:`.problem`)."""

    tube: float = 0.02  # delta of Eq. 29 (units of sigma^2)
    mu: float = MU  # friction coefficient
    n_control: int = 27  # latent spline control points, a double knot at each contact event
    n_stance: int = 32  # contact nodes every 10 ms
    n_flight: int = 80  # flight nodes every 5 ms
    n_land: int = 62
    sample_spacing: float = 0.005  # s between the contact and flight samples of phase 2 (0: none)
    hessian: str = "exact"  # or "lbfgs"
    max_iter: int = 1500
    tol: float = 1e-5


#: what each field sets, one line each (``latentoc show``); tube, n_control, hessian, max_iter and tol
#: are set by other tables of a problem file and described there
FIELD_DOCS: dict[str, str] = {
    'n_stance': 'contact nodes of the stance, every 10 ms',
    'n_flight': 'flight nodes, every 5 ms',
    'n_land': 'contact nodes of the landing, touchdown to the end',
    'sample_spacing': 's between the contact and flight samples of phase 2 (0: none)',
    'mu': 'friction coefficient mu of the foot points (Table 5)',
}
