"""Minimum-torque motion of a fixed-base robot (nq = nv = D): the NLP of Eq. 22 on the derivative layer.

The objective is J = int_0^T |tau|^2 dt (Eq. 22 with the minimum-torque L of Sect. 4.1) by
Gauss-Legendre quadrature, J = sum_k w_k |tau_k|^2, where tau_k = RNEA(y, yd, ydd) (Eq. 1-2) of
the joint motion at node k; or another running cost L of :mod:`.objectives`
(mechanical energy, acceleration). Two methods give the joint motion along a spline path
(:mod:`latentoc.latent.spline_path`):

* ``"latent"``: the path is the latent spline x(t) (Eq. 20, 23-25) and the joint motion the
  GPDM mean through it (Eq. 18, 26-28, :class:`~latentoc.latent.GPLayer`); the tube
  sigma^2(x) <= delta (Eq. 19, 29) holds on the constraint grid;
* ``"joint-range"``: the path is the joint spline itself (Eq. 5, :class:`~latentoc.latent.IdentityLayer`),
  the full configuration-space baseline of Sect. 4.1.1; each free control point stays within
  +-k degrees of its value in the fit of the training motion (Table 2, "joint range").

Both hold the joint limits (and, if switched on, the velocity limits) on the constraint grid
and, if the problem gives torque limits, |tau| <= limit at the quadrature nodes
(:mod:`.limits`); an end-effector goal (:mod:`.goal`) frees the
end point and holds a frame's position at t = T. Each nonlinear row family is one robot block
(:mod:`latentoc.nlp.blocks`); with torque limits a single block gives (|tau|^2, tau), feeding
both the objective and the torque rows, so RNEA runs once per node. The joint-range joint
limits are linear in the decision vector (q = B0 P) and need no block.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from latentoc.dynamics import SymbolicModel
from latentoc.gpdm import GPDM
from latentoc.latent import GPLayer, IdentityLayer, Layer
from latentoc.nlp.assemble import Family, SparseNLP
from latentoc.nlp.blocks import RobotBlock
from latentoc.nlp.evaluators import BlockEvaluator, MeanEvaluator, VarianceEvaluator
from latentoc.nlp.inputs import NodeInputs
from latentoc.latent.spline_path import SplinePath, constraint_times, gauss_legendre_nodes
from latentoc.min_torque.goal import FreeEndPath, goal_family
from latentoc.min_torque.limits import Limits
from latentoc.min_torque.objectives import Objective, velocity_block
from latentoc.min_torque.settings import MinTorqueSettings

__all__ = ["MinTorqueNLP", "Samples", "latent_nlp", "joint_range_nlp", "torque_block", "ipopt_options",
           "CONSTRAINT_TOL"]

# The latent rows scaled to a largest gradient of 1 (Ipopt scales only rows above 100 by default):
# the sigma^2 rows' gradients are ~1e-3. The joint-range NLP keeps Ipopt's default.
LATENT_ROW_SCALING = {"nlp_scaling_constr_target_gradient": 1.0}
CONSTRAINT_TOL = 1e-8  # Ipopt's (unscaled) row violation at a solution, also when "acceptable"


@dataclass
class Samples:
    """Times the exchange (:mod:`.exchange`) adds: to the constraint grid (tube, joint limits) and
    to the torque-limit rows."""

    grid: np.ndarray = field(default_factory=lambda: np.zeros(0))
    torque: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def merged(self, other: "Samples") -> "Samples":
        return Samples(np.union1d(self.grid, other.grid), np.union1d(self.torque, other.torque))

    def __bool__(self) -> bool:
        return bool(len(self.grid) or len(self.torque))


@dataclass
class MinTorqueNLP:
    """The assembled NLP over the free control points, its bounds and its nodes."""

    method: str
    nlp: SparseNLP
    path: SplinePath
    layer: Layer
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    quad_t: np.ndarray
    quad_w: np.ndarray
    grid_t: np.ndarray
    rows: dict[str, slice] = field(default_factory=dict)  # constraint rows of each family
    extra: Samples = field(default_factory=lambda: Samples())  # the exchange's added times
    tube: float | None = None
    limits: Limits = field(default_factory=Limits)
    objective: Objective = field(default_factory=Objective)

    @property
    def w0(self) -> np.ndarray:
        return self.path.w0

    def control_points(self, w: np.ndarray) -> np.ndarray:
        return self.path.control_points(w)

    def cost(self, w: np.ndarray) -> float:
        """J (Eq. 22, quadrature) at the decision vector w."""
        return self.nlp.objective(np.asarray(w, dtype=float))


def torque_block(model: SymbolicModel, latent_dim: int, with_torques: bool = False) -> RobotBlock:
    """The block L = |tau|^2 (Eq. 22, tau = RNEA, Eq. 1-2); ``with_torques``: rows (L, tau)."""
    return Objective("torque").block(model, latent_dim, with_torques)


def _spline_inputs(path: SplinePath, t: np.ndarray, orders: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """(S, s0) of the path's value and first ``orders`` - 1 derivatives at times t (Eq. 23-25)."""
    ni = NodeInputs(len(t), path.n_w)
    ni.spline([path.spline.basis(t, r) for r in range(orders)], path.index, path.P_init)
    return ni.build()


def _torque_family(model: SymbolicModel, layer: Layer, path: SplinePath, t: np.ndarray, w: np.ndarray,
                   tmax: np.ndarray | None, objective: Objective) -> tuple[Family, np.ndarray, np.ndarray]:
    """The objective's family (cf = quadrature weights on L) and, with limits, the torque rows."""
    nv, K = model.nv, len(t)
    block = objective.block(model, layer.latent_dim, with_torques=tmax is not None)
    n_out = block.n_out
    cf = np.zeros((K, n_out))
    cf[:, 0] = w
    Cg, lb, ub = None, np.zeros(0), np.zeros(0)
    if tmax is not None:  # rows tau_k (node-major), outputs 1..nv of each node
        rows = np.arange(K * nv)
        cols = (rows // nv) * n_out + 1 + rows % nv
        Cg = sp.csr_matrix((np.ones(K * nv), (rows, cols)), shape=(K * nv, K * n_out))
        lb, ub = np.tile(-tmax, K), np.tile(tmax, K)
    S, s0 = _spline_inputs(path, t, 3)
    return Family("torque", BlockEvaluator(block, layer), S, s0, Cg=Cg, cf=cf.ravel()), lb, ub


def _joint_limit_family(layer: Layer, path: SplinePath, t: np.ndarray) -> Family:
    """Rows y(t_j) (node-major): the GP mean of the latent points, or, when the path is the joint
    path itself (identity layer), linear in w: y = B0 P."""
    if isinstance(layer, IdentityLayer):
        S, s0 = _spline_inputs(path, t, 1)  # no node evaluator: the rows are L w + c
        return Family("joint_limits", None, sp.csr_matrix((0, path.n_w)), np.zeros(0), L=S, c=s0)
    S, s0 = _spline_inputs(path, t, 1)
    assert isinstance(layer, GPLayer)  # the arm's paths: the GP layer or the identity
    return Family("joint_limits", MeanEvaluator(layer), S, s0, Cg=sp.identity(len(t) * layer.output_dim, format="csr"))


def _velocity_family(model: SymbolicModel, layer: Layer, path: SplinePath, t: np.ndarray) -> Family:
    """Rows yd(t_j) (node-major) for the velocity limits."""
    S, s0 = _spline_inputs(path, t, 3)
    block = velocity_block(model.nv, layer.latent_dim)
    return Family("velocity_limits", BlockEvaluator(block, layer), S, s0,
                  Cg=sp.identity(len(t) * model.nv, format="csr"))


def _build(method: str, model: SymbolicModel, layer: Layer, settings: MinTorqueSettings,
           path: SplinePath, lbx: np.ndarray, ubx: np.ndarray, tube: float | None,
           extra: Samples | None = None) -> MinTorqueNLP:
    if model.nq != model.nv or model.nv != layer.output_dim:
        raise ValueError(f"the motion has {layer.output_dim} joint angles but the model has nq = {model.nq}, "
                         f"nv = {model.nv}; the minimum-torque NLP needs nq = nv = D")
    spline = path.spline
    quad_t, quad_w = gauss_legendre_nodes(spline, settings.quadrature_points)
    grid_t = constraint_times(spline, settings.constraint_points)
    if isinstance(path, FreeEndPath):  # the end point is free: the limits and the tube hold there too
        grid_t = np.append(grid_t, spline.duration)
    extra = extra or Samples()
    grid_t = np.union1d(grid_t, extra.grid)
    limits = settings.limits(model.model)
    Kg = len(grid_t)
    families, lbg, ubg = [], [], []
    if tube is not None:  # sigma^2(x(t_j)) / delta <= 1 (Eq. 29), relative: Ipopt's tolerances in units of delta
        if not layer.has_tube:
            raise TypeError("a tube needs the GP layer: sigma^2 is the GPDM's")
        S, s0 = _spline_inputs(path, grid_t, 1)
        families.append(Family("tube", VarianceEvaluator(layer), S, s0, Cg=sp.identity(Kg, format="csr") / tube))
        lbg.append(np.full(Kg, -np.inf))
        ubg.append(np.ones(Kg))
    if limits.q_lo is not None and limits.q_hi is not None:
        families.append(_joint_limit_family(layer, path, grid_t))
        lbg.append(np.tile(limits.q_lo, Kg))
        ubg.append(np.tile(limits.q_hi, Kg))
    if limits.v_max is not None:
        families.append(_velocity_family(model, layer, path, grid_t))
        lbg.append(np.tile(-limits.v_max, Kg))
        ubg.append(np.tile(limits.v_max, Kg))
    tmax = limits.tau_max
    # torque rows also at the exchange's times, with no weight in the objective
    torque_t = np.concatenate([quad_t, extra.torque]) if tmax is not None else quad_t
    torque_w = np.concatenate([quad_w, np.zeros(len(torque_t) - len(quad_t))])
    torque, lb, ub = _torque_family(model, layer, path, torque_t, torque_w, tmax, settings.objective)
    families.append(torque)
    lbg.append(lb)
    ubg.append(ub)
    if settings.goal is not None:
        goal, lb, ub = goal_family(model, layer, path, settings.goal)
        families.append(goal)
        lbg.append(lb)
        ubg.append(ub)
    nlp = SparseNLP(path.n_w, families)
    rows = {f.name: slice(nlp.row_offset[f.name], nlp.row_offset[f.name] + f.n_rows)
            for f in nlp.families if f.n_rows}
    return MinTorqueNLP(method=method, nlp=nlp, path=path, layer=layer, lbx=lbx, ubx=ubx,
                        lbg=np.concatenate(lbg), ubg=np.concatenate(ubg), quad_t=quad_t, quad_w=quad_w,
                        grid_t=grid_t, rows=rows, extra=extra, tube=tube, limits=limits, objective=settings.objective)


def _goal_path(path: SplinePath, settings: MinTorqueSettings) -> SplinePath:
    """``path`` with its end point free when the settings have a goal."""
    if settings.goal is None or isinstance(path, FreeEndPath):
        return path
    return FreeEndPath.release_end(path, settings.boundary)


def latent_nlp(gpdm: GPDM, model: SymbolicModel, settings: MinTorqueSettings, tube: float,
               path: SplinePath | None = None, t_train: np.ndarray | None = None,
               extra: Samples | None = None) -> MinTorqueNLP:
    """Eq. 22 over the latent control points, subject to the tube sigma^2 <= ``tube`` (Eq. 29).

    ``path``: the latent spline with its initial control points; else the fit of the GPDM's
    training latent path at the training times ``t_train``."""
    if path is None:
        if t_train is None:
            raise ValueError("latent_nlp needs the initial path or the training times t_train to fit it")
        path = SplinePath.fit(settings.spline(), t_train, gpdm.latent_trajectories()[0], settings.boundary)
    path = _goal_path(path, settings)
    n = path.n_w
    return _build("latent", model, GPLayer(gpdm), settings, path, np.full(n, -np.inf), np.full(n, np.inf),
                  float(tube), extra)


def joint_range_nlp(model: SymbolicModel, settings: MinTorqueSettings, t_train: np.ndarray, Q_train: np.ndarray,
                    joint_range_deg: float, extra: Samples | None = None) -> MinTorqueNLP:
    """Eq. 4 (= Eq. 22 with q = x) over joint-space control points, each within
    +-``joint_range_deg`` of the training motion's spline fit (Sect. 4.1.1)."""
    path = _goal_path(SplinePath.fit(settings.spline(), t_train, Q_train, settings.boundary), settings)
    k = np.radians(float(joint_range_deg))
    return _build("joint-range", model, IdentityLayer(model.nq), settings, path, path.w0 - k, path.w0 + k, None,
                  extra)


def ipopt_options(nlp: MinTorqueNLP, *, tol: float, max_iter: int, verbose: bool = False) -> dict:
    """Ipopt's options for this NLP: monotone barrier (Fiacco-McCormick), an acceptable level of
    max(1e-6, 100 tol) for 10 iterations, rows held to CONSTRAINT_TOL (the tube relative to delta,
    limits in rad and N m), and the latent row scaling."""
    options = {"tol": float(tol), "max_iter": int(max_iter), "mu_strategy": "monotone",
               "acceptable_tol": max(1e-6, 100.0 * float(tol)), "acceptable_iter": 10,
               "constr_viol_tol": CONSTRAINT_TOL, "acceptable_constr_viol_tol": CONSTRAINT_TOL,
               "print_level": 5 if verbose else 0}
    if nlp.method == "latent":
        options.update(LATENT_ROW_SCALING)
    return options
