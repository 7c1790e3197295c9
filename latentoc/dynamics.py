"""Symbolic rigid-body dynamics: Pinocchio's own algorithms evaluated on ``casadi.SX``.

Two backends give the same ``casadi.Function``s:

* ``"pinocchio.casadi"``: Pinocchio's CasADi bindings, where ``import pinocchio.casadi``
  works (conda-forge installs);
* ``"bridge"``: latentoc's compiled extension ``latentoc._bridge``, which instantiates
  Pinocchio's templated algorithms on ``casadi::SX`` from the pip wheels and hands the
  Functions back serialized. The model crosses the boundary as
  ``pinocchio.Model.saveToString()``.

Every Function is built once per model and cached. Spatial quantities follow the paper's
Eq. (1)-(3): ``tau = M(q) a + C(q, v) v + V(q)`` is ``rnea(q, v, a)``.
"""

from __future__ import annotations

import casadi
import numpy as np
import pinocchio

from latentoc.errors import LatentocError

__all__ = ["SymbolicModel", "available_backends", "DynamicsInputError"]

BACKENDS = ("pinocchio.casadi", "bridge")


class DynamicsInputError(LatentocError, ValueError):
    """A model, frame name or argument the symbolic dynamics cannot take."""


def _import_pinocchio_casadi():
    try:
        import pinocchio.casadi as cpin  # type: ignore[import-not-found]
    except ImportError:
        return None
    return cpin


def _import_bridge():
    try:
        from latentoc import _bridge  # type: ignore[attr-defined]
    except ImportError:
        return None
    return _bridge


def available_backends() -> list[str]:
    """The backends that import on this machine, preferred first."""
    found = []
    if _import_pinocchio_casadi() is not None:
        found.append("pinocchio.casadi")
    if _import_bridge() is not None:
        found.append("bridge")
    return found


class _BridgeBackend:
    """Functions from the compiled extension, deserialized on the Python side."""

    def __init__(self, model: pinocchio.Model) -> None:
        bridge = _import_bridge()
        if bridge is None:
            raise DynamicsInputError(
                "the 'bridge' backend is not available: latentoc._bridge did not import "
                "(reinstall latentoc with a C++ compiler present: pip install -e .)"
            )
        try:
            self._handle = bridge.BridgeModel(model.saveToString())
        except ValueError as exc:
            raise DynamicsInputError(str(exc)) from None

    def build(self, name: str, *args: str) -> casadi.Function:
        return casadi.Function.deserialize(getattr(self._handle, name)(*args))


class _PinocchioCasadiBackend:
    """Functions traced through Pinocchio's own CasADi bindings."""

    def __init__(self, model: pinocchio.Model) -> None:
        cpin = _import_pinocchio_casadi()
        if cpin is None:
            raise DynamicsInputError("the 'pinocchio.casadi' backend is not available here")
        self._cpin = cpin
        self._model = model
        self._cmodel = cpin.Model(model)

    def build(self, name: str, *args: str) -> casadi.Function:
        cpin, cmodel, model = self._cpin, self._cmodel, self._model
        cdata = cmodel.createData()
        q = casadi.SX.sym("q", model.nq)
        v = casadi.SX.sym("v", model.nv)
        a = casadi.SX.sym("a", model.nv)
        if name == "rnea":
            return casadi.Function("rnea", [q, v, a], [cpin.rnea(cmodel, cdata, q, v, a)], ["q", "v", "a"], ["tau"])
        if name == "com":
            return casadi.Function("com", [q], [cpin.centerOfMass(cmodel, cdata, q, False)], ["q"], ["com"])
        if name == "centroidal_momentum":
            h = cpin.computeCentroidalMomentum(cmodel, cdata, q, v).vector
            return casadi.Function(name, [q, v], [h], ["q", "v"], ["h"])
        if name == "centroidal_momentum_rate":
            dh = cpin.computeCentroidalMomentumTimeVariation(cmodel, cdata, q, v, a).vector
            return casadi.Function(name, [q, v, a], [dh], ["q", "v", "a"], ["dh"])
        if name == "mass_matrix":
            M = cpin.crba(cmodel, cdata, q)
            M = casadi.triu(M) + casadi.triu(M, False).T
            return casadi.Function(name, [q], [M], ["q"], ["M"])
        if name == "integrate":
            dv = casadi.SX.sym("dv", model.nv)
            return casadi.Function(name, [q, dv], [cpin.integrate(cmodel, q, dv)], ["q", "dv"], ["q_next"])
        if name == "difference":
            q0, q1 = casadi.SX.sym("q0", model.nq), casadi.SX.sym("q1", model.nq)
            return casadi.Function(name, [q0, q1], [cpin.difference(cmodel, q0, q1)], ["q0", "q1"], ["dv"])
        frame = args[0]
        fid = model.getFrameId(frame)
        if name == "frame_placement":
            cpin.framesForwardKinematics(cmodel, cdata, q)
            oMf = cdata.oMf[fid]
            return casadi.Function(
                f"frame_placement_{frame}", [q], [oMf.translation, oMf.rotation], ["q"], ["translation", "rotation"]
            )
        if name == "frame_velocity":
            cpin.forwardKinematics(cmodel, cdata, q, v)
            vel = cpin.getFrameVelocity(cmodel, cdata, fid, pinocchio.LOCAL_WORLD_ALIGNED).vector
            return casadi.Function(f"frame_velocity_{frame}", [q, v], [vel], ["q", "v"], ["velocity"])
        if name == "frame_jacobian":
            J = cpin.computeFrameJacobian(cmodel, cdata, q, fid, pinocchio.LOCAL_WORLD_ALIGNED)
            return casadi.Function(f"frame_jacobian_{frame}", [q], [J], ["q"], ["J"])
        raise KeyError(name)


def _cached(kind: str, doc: str) -> property:
    """A Function built by the backend on first use and kept on the instance."""

    def get(self: "SymbolicModel") -> casadi.Function:
        if kind not in self._cache:
            self._cache[kind] = self._impl.build(kind)
        return self._cache[kind]

    return property(get, doc=doc)


class SymbolicModel:
    """CasADi Functions of a ``pinocchio.Model``'s dynamics and kinematics.

    ``backend`` is ``None`` (the first of :func:`available_backends`), ``"pinocchio.casadi"``
    or ``"bridge"``.
    """

    def __init__(self, model: pinocchio.Model, backend: str | None = None) -> None:
        if not isinstance(model, pinocchio.Model):
            raise DynamicsInputError(f"model must be a pinocchio.Model, got {type(model).__name__}")
        if backend is None:
            found = available_backends()
            if not found:
                raise DynamicsInputError(
                    "no symbolic dynamics backend: neither pinocchio.casadi nor latentoc._bridge imports"
                )
            backend = found[0]
        if backend not in BACKENDS:
            raise DynamicsInputError(f"unknown backend {backend!r}; choose one of {BACKENDS}")
        self.model = model
        self.backend = backend
        self._impl = _BridgeBackend(model) if backend == "bridge" else _PinocchioCasadiBackend(model)
        self._cache: dict = {}

    @property
    def nq(self) -> int:
        return self.model.nq

    @property
    def nv(self) -> int:
        return self.model.nv

    @property
    def has_free_flyer(self) -> bool:
        """True when the first joint is a free-flyer (the floating base of Eq. 3)."""
        return self.model.njoints > 1 and self.model.joints[1].shortname() == "JointModelFreeFlyer"

    rnea = _cached("rnea", "(q, v, a) -> tau [nv], inverse dynamics, Eq. (1).")
    com = _cached("com", "(q) -> centre of mass [3] in the world frame.")
    centroidal_momentum = _cached("centroidal_momentum", "(q, v) -> [6]: linear momentum, angular momentum about the COM.")
    centroidal_momentum_rate = _cached("centroidal_momentum_rate", "(q, v, a) -> [6]: time derivative of the centroidal momentum.")
    mass_matrix = _cached("mass_matrix", "(q) -> M [nv x nv], full symmetric.")
    integrate = _cached("integrate", "(q, dv) -> q (+) dv on the configuration Lie group.")
    difference = _cached("difference", "(q0, q1) -> dv with q0 (+) dv = q1.")

    def _frame_function(self, kind: str, name: str) -> casadi.Function:
        if not isinstance(name, str) or not self.model.existFrame(name):
            raise DynamicsInputError(
                f"unknown frame name {name!r} for model {self.model.name!r}"
                f" (it has {self.model.nframes} frames, e.g. {[f.name for f in self.model.frames][-3:]})"
            )
        key = (kind, name)
        if key not in self._cache:
            self._cache[key] = self._impl.build(kind, name)
        return self._cache[key]

    def frame_placement(self, name: str) -> casadi.Function:
        """(q) -> (translation [3], rotation [3x3]) of frame ``name`` in the world frame."""
        return self._frame_function("frame_placement", name)

    def frame_velocity(self, name: str) -> casadi.Function:
        """(q, v) -> [6] spatial velocity of frame ``name``, LOCAL_WORLD_ALIGNED, linear first."""
        return self._frame_function("frame_velocity", name)

    def frame_jacobian(self, name: str) -> casadi.Function:
        """(q) -> [6 x nv] Jacobian of frame ``name``, LOCAL_WORLD_ALIGNED, linear rows first."""
        return self._frame_function("frame_jacobian", name)

    def check_arguments(self, q=None, v=None, a=None) -> None:
        """Raise :class:`DynamicsInputError` naming an argument of the wrong size."""
        for label, value, size in (("q", q, self.nq), ("v", v, self.nv), ("a", a, self.nv)):
            if value is None:
                continue
            n = value.numel() if hasattr(value, "numel") else np.asarray(value).size
            if n != size:
                raise DynamicsInputError(f"argument {label} has {n} entries, the model needs {size}")
