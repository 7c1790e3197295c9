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
    leg_residual: float = 0.0  # deg: a bounded residual on the legs' sagittal joints beside the latent path (0: none)
    flight_substeps: int = 2  # trapezoid steps of the pitch rate per flight node interval
    tube_spacing: float = 0.005  # s between tube points
    sample_spacing: float = 0.005  # s between the contact and flight samples of phase 2 (0: none)
    exchange: bool = True  # sampled rows grow where the 1 kHz grid is violated (:mod:`.solve.exchange`)
    exchange_rounds: int = 8
    torque_limits: bool = True  # Eq. 34
    polygon: bool = True  # Eq. 35-36 in the landing
    two_phase: bool = True  # phase 1: feasible point nearest the training fit; phase 2: distance
    hessian: str = "exact"  # or "lbfgs"
    max_iter: int = 1500
    tol: float = 1e-5


#: what each field sets, one line each (``latentoc show``); tube, n_control, hessian, max_iter and tol
#: are set by other tables of a problem file and described there
FIELD_DOCS: dict[str, str] = {
    'n_stance': 'contact nodes of the stance, every 10 ms',
    'n_flight': 'flight nodes, every 5 ms',
    'n_land': 'contact nodes of the landing, touchdown to the end',
    'leg_residual': "deg: a bounded residual on the legs' sagittal joints beside the latent path (0: none)",
    'flight_substeps': 'trapezoid steps of the pitch rate per flight node interval',
    'tube_spacing': "s between the tube's points",
    'sample_spacing': 's between the contact and flight samples of phase 2 (0: none)',
    'exchange': 'rows grow where the 1 kHz grid is violated (the exchange)',
    'exchange_rounds': 'solves of the exchange at the most',
    'torque_limits': 'the torque limits of Eq. 34',
    'polygon': 'ZMP and COM in the support polygon in the landing (Eq. 35-36)',
    'two_phase': 'phase 1, the feasible point nearest the training fit, before phase 2, the distance',
    'mu': 'friction coefficient mu of the foot points (Table 5)',
}
