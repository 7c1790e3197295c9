"""The variance tube (Eq. 29): sigma^2(x(t)) <= delta along the latent path, and everything about it.

delta is in units of sigma^2 (Eq. 19), which depend on the learned hyperparameters, so the
paper's values do not transfer. A tube is given as a spec (:func:`parse_tube`, the problem
files' ``latent.tube`` and ``sweep.tubes``, checked by :data:`TUBE`):

* a positive number: delta itself;
* a string ``"<k>x"``: k times the kind's reference, ``tube_training`` (Eq. 30: the largest
  sigma^2 along the GPDM's training path, :meth:`latentoc.gpdm.GPDM.tube_size`), which
  :func:`resolve_tube` asks for only then (it may learn the GPDM).

``tube_relative`` (:func:`relative_tube`) = delta / the GPDM's noise variance 1/beta_3 compares
tubes across problems and models. A result reports its tube as :class:`TubeResult`: the spec,
delta, the relative tube, tube_training and the largest sigma^2 along the solved path.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from latentoc.errors import ProblemError, SolveError
from latentoc.gpdm import GPDM
from latentoc.problem.schema import Check

__all__ = ["parse_tube", "TUBE", "resolve_tube", "tube_delta", "relative_tube", "TubeResult"]


def parse_tube(spec: float | int | str) -> tuple[float, bool]:
    """A tube spec as (value, relative): ``1e-3`` -> (1e-3, False); ``"1.5x"`` -> (1.5, True).

    Raises :class:`ProblemError` (a ValueError) for anything else, zero or negative values.
    """
    if isinstance(spec, bool):
        raise ProblemError(f"tube {spec!r} is not a number")
    if isinstance(spec, (int, float)):
        value, relative = float(spec), False
    elif isinstance(spec, str):
        s = spec.strip().lower()
        relative = s.endswith("x")
        try:
            value = float(s[:-1] if relative else s)
        except ValueError:
            raise ProblemError(f'tube {spec!r} is neither a number nor a relative spec like "1.5x"') from None
    else:
        raise ProblemError(f"tube {spec!r} is not a number")
    if not math.isfinite(value) or value <= 0:
        raise ProblemError(f"tube {spec!r} must be positive (delta bounds sigma^2 >= 0 from above)")
    return value, relative


def _tube_spec(v: Any) -> float | str:
    parse_tube(v)
    return v if isinstance(v, str) else float(v)


#: the check of a tube setting: a positive number (absolute delta) or "<k>x"
TUBE = Check(_tube_spec, 'a positive number or a relative tube like "1.5x"')


def resolve_tube(spec: float | str, reference: float | Callable[[], float]) -> float:
    """delta of a tube spec: the number itself, or k times ``reference`` for ``"<k>x"`` (a
    callable is called only then); a :class:`SolveError` for a spec that is neither."""
    try:
        value, relative = parse_tube(spec)
    except ProblemError as exc:
        raise SolveError(str(exc)) from None
    if not relative:
        return value
    return value * float(reference() if callable(reference) else reference)


def tube_delta(spec: float | str, gpdm: GPDM) -> float:
    """delta of a tube spec for ``gpdm`` (:func:`resolve_tube` against its Eq. 30 tube); a
    :class:`ProblemError` for an absolute delta at or above :attr:`GPDM.prior_variance`, the
    largest sigma^2 anywhere: such a tube bounds nothing, and is mostly a "5x" written as "5"."""
    delta = resolve_tube(spec, gpdm.tube_size)  # the Eq. 30 tube computed only for "<k>x"
    ceiling = gpdm.prior_variance
    if delta >= ceiling and not parse_tube(spec)[1]:
        training = gpdm.tube_size()
        raise ProblemError(
            f"tube delta = {delta:.4g} is at or above {ceiling:.4g}, the largest sigma^2 (Eq. 19) this "
            f"GPDM gives anywhere, so it would bound nothing; \"{delta:g}x\" is {delta:g} times the training "
            f"motion's own tube (delta = {delta * training:.4g}; 1x = {training:.4g})")
    return delta


def relative_tube(delta: float, gpdm: GPDM) -> float:
    """delta in units of the GPDM's noise variance 1/beta_3 (``tube_relative``)."""
    return delta / gpdm.noise_variance


@dataclass(frozen=True)
class TubeResult:
    """The tube of a solved problem: the spec, delta, delta x beta_3 (:func:`relative_tube`),
    tube_training (Eq. 30) and the largest sigma^2 along the optimised path on the 1 kHz grid."""

    spec: float | str
    delta: float
    relative: float
    training: float
    max_sigma2: float

    @classmethod
    def from_result(cls, r: Mapping[str, Any]) -> TubeResult | None:
        """The tube of a kind's result dict (its ``tube_spec``, ``tube``, ``tube_relative``,
        ``tube_training``, ``max_sigma2``); None for a solve without one (a joint-space baseline)."""
        if r.get("tube") is None:
            return None
        return cls(spec=r["tube_spec"], delta=float(r["tube"]), relative=float(r["tube_relative"]),
                   training=float(r["tube_training"]), max_sigma2=float(r["max_sigma2"]))
