"""A robot's physics, checked when the user's model is read: bad numbers are an error naming the
file and the link or joint, not a model that solves "successfully" with them.

* a link's ``<mass>`` is a finite number >= 0 (pinocchio reads ``nan`` as a mass of 0 and a
  negative mass as it is; 0 is a massless frame);
* a link's ``<inertia>`` is finite, positive semi-definite, and its principal moments satisfy the
  triangle inequality (each at most the sum of the other two), as a rigid body's do;
* a joint's ``<limit>`` has finite numbers, ``lower <= upper``, and no negative velocity or effort
  (pinocchio keeps lower > upper, which latentoc would read as "no limit").

The models of latentoc's registered robot names are not checked here (example-robot-data's
romeo breaks the triangle inequality in two links); an ASF skeleton's de Leva inertias are
(:func:`check_model`).
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pinocchio as pin

__all__ = ["check_urdf", "check_model", "INERTIA_RTOL"]

#: relative tolerance of the inertia checks (rounding in a URDF's printed values)
INERTIA_RTOL = 1e-6
_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def _number(element: ET.Element, key: str, what: str, default: str | None = None) -> float:
    text = element.get(key, default)
    try:
        value = float(text) if text is not None else math.nan
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise ValueError(f"{what} {key}={text!r} is not a finite number")
    return value


def inertia_problem(mass: float, inertia: np.ndarray) -> str | None:
    """What is wrong with a rigid body's mass and rotational inertia (3 x 3), or None."""
    if not math.isfinite(mass) or mass < 0:
        return f"mass {mass:g} is not a finite number >= 0"
    if not np.isfinite(inertia).all():
        return "the inertia has a value that is not finite"
    ev = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
    tol = INERTIA_RTOL * max(float(np.abs(ev).max()), 1e-12)  # kg m^2: rounding of zero inertias
    if ev.min() < -tol:
        return f"the inertia is not positive semi-definite (principal moments {', '.join(f'{e:.4g}' for e in ev)})"
    if ev[0] + ev[1] < ev[2] - tol:
        return (f"the principal moments {', '.join(f'{e:.4g}' for e in ev)} break the triangle inequality "
                f"({ev[0]:.4g} + {ev[1]:.4g} < {ev[2]:.4g}): no rigid body has them")
    return None


def _tagged(root: ET.Element, tag: str, child: str, path: Path) -> Iterator[tuple[str, ET.Element]]:
    """(what, <child>) of every <tag> that has a <child>; ``what`` names the file and the tag."""
    for element in root.iter(tag):
        found = element.find(child)
        if found is not None:
            yield f"URDF {path}: {tag} {element.get('name')!r}:", found


@contextmanager
def _naming(what: str) -> Iterator[None]:
    """A ValueError raised inside, its message after ``what``."""
    try:
        yield
    except ValueError as exc:
        raise ValueError(f"{what} {exc}") from None


def check_urdf(root: ET.Element, path: Path) -> None:
    """A ValueError naming ``path`` and the link or joint whose mass, inertia or limits are wrong."""
    for what, inertial in _tagged(root, "link", "inertial", path):
        with _naming(what):
            mass_el = inertial.find("mass")
            mass = 0.0 if mass_el is None else _number(mass_el, "value", "mass")
            inertia_el = inertial.find("inertia")
            values = {k: 0.0 if inertia_el is None else _number(inertia_el, k, "inertia", "0") for k in _INERTIA_KEYS}
            inertia = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                                [values["ixy"], values["iyy"], values["iyz"]],
                                [values["ixz"], values["iyz"], values["izz"]]])
            problem = inertia_problem(mass, inertia)
            if problem is not None:
                raise ValueError(problem)
    for what, limit in _tagged(root, "joint", "limit", path):
        with _naming(what):
            values = {k: _number(limit, k, "limit") for k in ("lower", "upper", "velocity", "effort") if k in limit.attrib}
            if "lower" in values and "upper" in values and values["lower"] > values["upper"]:
                raise ValueError(f"limit lower={values['lower']:g} is above upper={values['upper']:g}")
            negative = [k for k in ("velocity", "effort") if values.get(k, 0.0) < 0]
            if negative:
                raise ValueError(f"limit {negative[0]}={values[negative[0]]:g} is negative")


def check_model(model: pin.Model, where: str) -> None:
    """A ValueError naming ``where`` and the joint whose body's mass or inertia is wrong, or whose
    position limits are not ordered."""
    for j in range(1, model.njoints):
        body = model.inertias[j]
        problem = inertia_problem(float(body.mass), np.asarray(body.inertia))
        if problem is not None:
            raise ValueError(f"{where}: the body of joint {model.names[j]!r}: {problem}")
    lo, hi = np.asarray(model.lowerPositionLimit), np.asarray(model.upperPositionLimit)
    bad = np.nonzero(lo > hi)[0]
    if len(bad):
        raise ValueError(f"{where}: configuration {int(bad[0])} has its lower limit {lo[bad[0]]:g} above its "
                         f"upper limit {hi[bad[0]]:g}")
