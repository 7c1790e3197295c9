"""The assembled NLP (latentoc.nlp.assemble) against the same NLP written as one CasADi SX graph.

The reference composes, symbolically in w: the affine node inputs s = S w + s0, the GPDM mean
motion of Eq. 18, 26-28 (``gpdm.mean_function()`` and ``ca.jtimes``), the block rows, the
variance of Eq. 19 (``gpdm.variance_function()``), the row maps Cg, L, c, the objective
weights cf and the objective terms, and lets CasADi differentiate the whole.
NodeInputs' segments are checked against their explicit construction.
"""
import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.latent import GPLayer
from latentoc.nlp.assemble import Family, SparseNLP
from latentoc.nlp.blocks import RobotBlock, block_inputs
from latentoc.nlp.evaluators import BlockEvaluator, VarianceEvaluator
from latentoc.nlp.inputs import NodeInputs
from latentoc.latent.spline import BSpline

D, LATENT, M = 3, 2, 7  # joints, latent dimension, control points
FIXED_ROWS = (0, M - 1)
RTOL = 1e-8


def _rows_block() -> RobotBlock:
    y, yd, ydd, r = block_inputs(D, 2)
    parts = {"a": ca.dot(y, yd) * r[0],
             "b": ydd[0] * ca.cos(y[1]) + r[1] * r[0] ** 2,
             "c": ca.sumsqr(ydd) + y[2] * ca.exp(0.3 * r[1]) * yd[1]}
    return RobotBlock.from_parts("assemble_rows", (y, yd, ydd, r), parts, LATENT)


def _cost_block() -> RobotBlock:
    y, yd, ydd, r = block_inputs(D, 0)
    tau = ydd + ca.sin(y) * ca.vertcat(1.0, 2.0, 3.0) + 0.1 * yd * yd[0]
    return RobotBlock.from_parts("assemble_cost", (y, yd, ydd, r), {"L": ca.sumsqr(tau)}, LATENT)


def _random_sparse(rng, shape, density):
    A = rng.standard_normal(shape) * (rng.random(shape) < density)
    return sp.csr_matrix(A)


class Problem:
    """The NLP's data, its SparseNLP and its one-graph CasADi reference."""

    def __init__(self, gpdm):
        rng = np.random.default_rng(5)
        self.gpdm, layer = gpdm, GPLayer(gpdm)
        spline = BSpline(M, 1.0, 3)
        free = [i for i in range(M) if i not in FIXED_ROWS]
        index = -np.ones((M, LATENT), int)
        for j, i in enumerate(free):
            index[i] = np.arange(j * LATENT, (j + 1) * LATENT)
        n_p = len(free) * LATENT
        ends = gpdm.latent_trajectories()[0]
        P = ends[np.linspace(0, len(ends) - 1, M).astype(int)]
        self.P_fixed = P.copy()
        self.w_centre = np.concatenate([P[free].ravel(), 0.3 * rng.standard_normal(6)])
        # w = (free control points, r0 at the 5 row nodes, one more variable)
        Ka, Kb, Kc = 5, 4, 6
        self.n_w = n_w = n_p + Ka + 1
        self.r0_index = n_p + np.arange(Ka)
        ta, tb, tc = np.linspace(0.05, 0.95, Ka), np.linspace(0.0, 1.0, Kb), np.linspace(0.02, 0.98, Kc)

        ni = NodeInputs(Ka, n_w)
        ni.spline([spline.basis(ta, k) for k in range(3)], index, P)
        ni.variables(self.r0_index[:, None])
        self.r1 = rng.uniform(-0.5, 0.5, (Ka, 1))
        ni.constant(self.r1)
        S, s0 = ni.build()
        self.Ba = [spline.basis(ta, k) for k in range(3)]
        rows = _rows_block()
        self.rows = rows
        n_out = rows.n_out
        self.Cg = _random_sparse(rng, (6, Ka * n_out), 0.4)
        self.L = _random_sparse(rng, (6, n_w), 0.3)
        self.c = rng.standard_normal(6)
        self.cf_a = rng.standard_normal(Ka * n_out)
        fam_a = Family("rows", BlockEvaluator(rows, layer), S, s0, Cg=self.Cg, L=self.L, c=self.c, cf=self.cf_a)

        ni = NodeInputs(Kb, n_w)
        ni.spline([spline.basis(tb, 0)], index, P)
        S, s0 = ni.build()
        self.Bb = spline.basis(tb, 0)
        self.Cg_b = sp.identity(Kb, format="csr") * 2.0
        fam_b = Family("tube", VarianceEvaluator(layer), S, s0, Cg=self.Cg_b)

        ni = NodeInputs(Kc, n_w)
        ni.spline([spline.basis(tc, k) for k in range(3)], index, P)
        S, s0 = ni.build()
        self.Bc = [spline.basis(tc, k) for k in range(3)]
        self.cost = _cost_block()
        self.cf_c = rng.uniform(0.05, 0.2, Kc)
        fam_c = Family("cost", BlockEvaluator(self.cost, layer), S, s0, cf=self.cf_c)

        w = ca.SX.sym("w", n_w)
        self.terms = ca.Function("terms", [w], [0.5 * ca.sumsqr(w - self.w_centre) + ca.sin(w[0]) * w[n_w - 1]])
        self.index, self.free = index, free
        self.nlp = SparseNLP(n_w, [fam_a, fam_b, fam_c], objective_terms=self.terms)

    def reference(self) -> ca.Function:
        gp, d = self.gpdm, LATENT
        x, xd, xdd = (ca.SX.sym(n, d) for n in ("x", "xd", "xdd"))
        y = gp.mean_function()(x)
        yd = ca.jtimes(y, x, xd)
        ydd = ca.jtimes(y, x, xdd) + ca.jtimes(yd, x, xd)
        motion = ca.Function("motion", [x, xd, xdd], [y, yd, ydd])
        w = ca.SX.sym("w", self.n_w)
        P = ca.SX(ca.DM(self.P_fixed))
        for i in self.free:
            P[i, :] = w[self.index[i]].T
        Fa = []
        for k in range(len(self.r1)):
            xs = [ca.mtimes(ca.DM(B[k:k + 1]), P).T for B in self.Ba]
            r = ca.vertcat(w[int(self.r0_index[k])], float(self.r1[k, 0]))
            Fa.append(self.rows.rows_sx(*motion(*xs), r))
        Fa = ca.vertcat(*Fa)
        Fb = ca.vertcat(*[gp.variance_function()(ca.mtimes(ca.DM(self.Bb[k:k + 1]), P).T) for k in range(len(self.Bb))])
        Fc = ca.vertcat(*[self.cost.rows_sx(*motion(*[ca.mtimes(ca.DM(B[k:k + 1]), P).T for B in self.Bc]), ca.SX(0, 1))
                          for k in range(len(self.cf_c))])
        g = ca.vertcat(ca.mtimes(ca.DM(self.Cg), Fa) + ca.mtimes(ca.DM(self.L), w) + ca.DM(self.c),
                       ca.mtimes(ca.DM(self.Cg_b), Fb))
        f = self.terms(w) + ca.dot(ca.DM(self.cf_a), Fa) + ca.dot(ca.DM(self.cf_c), Fc)
        sigma, lam = ca.SX.sym("sigma"), ca.SX.sym("lam", g.numel())
        return ca.Function("reference", [w, sigma, lam], [f, ca.gradient(f, w), g, ca.jacobian(g, w),
                                                           ca.hessian(sigma * f + ca.dot(lam, g), w)[0]])


@pytest.fixture(scope="module")
def problem(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("LATENTOC_CACHE", str(tmp_path_factory.mktemp("jit")))
        gpdm = learn_gpdm(synthetic_motion(24, D, seed=31, cycles=1.0, noise=0.02),
                          GPDMSettings(latent_dim=LATENT, max_iterations=40))
        pb = Problem(gpdm)
        yield pb, pb.reference()


def _close(got, want, what):
    got, want = np.asarray(got, float), np.asarray(want, float)
    assert got.shape == want.shape, what
    err = np.abs(got - want).max() / max(np.abs(want).max(), 1e-300)
    assert err <= RTOL, f"{what}: relative error {err:.2e}"


def test_sizes(problem):
    pb, _ = problem
    nlp = pb.nlp
    assert nlp.m == 6 + 4 and nlp.n_w == pb.n_w
    assert nlp.row_offset == {"rows": 0, "tube": 6, "cost": 10}
    assert [f.name for f in nlp.families] == ["rows", "tube", "cost"]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_against_one_casadi_graph(problem, seed):
    """Objective, gradient, constraints, Jacobian and the upper triangle of the Lagrangian's
    Hessian at a random point, sigma and multipliers, relative 1e-8: each family's rows and
    each part of the Lagrangian (objective, one family's multipliers) on its own scale."""
    pb, ref = problem
    nlp = pb.nlp
    rng = np.random.default_rng(seed)
    w = pb.w_centre + 0.1 * rng.standard_normal(pb.n_w)
    sigma, lam = float(rng.uniform(0.5, 2.0)), rng.standard_normal(nlp.m)
    f, gf, g, J, H = (np.asarray(v) for v in ref(w, sigma, lam))
    _close(nlp.objective(w), f.item(), "objective")
    _close(nlp.gradient(w), gf.ravel(), "gradient")
    Jn = ca.DM(nlp.jac_sparsity, nlp.jacobian(w)).full()
    gn = nlp.constraints(w)
    for name, rows in (("rows", slice(0, 6)), ("tube", slice(6, 10))):
        _close(gn[rows], g.ravel()[rows], f"constraints {name}")
        _close(Jn[rows], J[rows], f"jacobian {name}")
    _close(ca.DM(nlp.hess_sparsity, nlp.hessian(w, sigma, lam)).full(), np.triu(H), "hessian")
    parts = {"objective": (sigma, np.zeros(nlp.m)), "rows": (0.0, np.r_[lam[:6], np.zeros(4)]),
             "tube": (0.0, np.r_[np.zeros(6), lam[6:]])}
    for name, (s, l) in parts.items():
        want = np.triu(np.asarray(ref(w, s, l)[4]))
        assert np.abs(want).max() > 0, name
        _close(ca.DM(nlp.hess_sparsity, nlp.hessian(w, s, l)).full(), want, f"hessian, {name} part")


def test_evaluation_order_and_points(problem):
    """Values at one point do not leak into another: the Hessian at w1 after everything at w2."""
    pb, ref = problem
    nlp = pb.nlp
    rng = np.random.default_rng(9)
    w1, w2 = (pb.w_centre + 0.1 * rng.standard_normal(pb.n_w) for _ in range(2))
    lam = rng.standard_normal(nlp.m)
    nlp.jacobian(w1)
    for fn in (nlp.constraints, nlp.objective, nlp.gradient, nlp.jacobian):
        fn(w2)
    nlp.hessian(w2, 1.0, lam)
    H1 = ca.DM(nlp.hess_sparsity, nlp.hessian(w1, 1.0, lam)).full()
    _close(H1, np.triu(np.asarray(ref(w1, 1.0, lam)[4])), "hessian after another point")
    _close(nlp.constraints(w1), np.asarray(ref(w1, 1.0, lam)[2]).ravel(), "constraints after the hessian")
    assert not np.any(nlp.hessian(w1, 0.0, np.zeros(nlp.m)))


# ------------------------------------------------------------------------ NodeInputs
def _explicit(K, segments, w):
    """Node inputs built entry by entry from their definitions."""
    out = []
    for k in range(K):
        row = []
        for kind, data in segments:
            if kind == "spline":
                bases, index, fixed = data
                P = np.where(index >= 0, w[np.maximum(index, 0)], fixed)
                for B in bases:
                    row.extend(B[k] @ P)
            elif kind == "variables":
                index, const = data
                row.extend(np.where(index[k] >= 0, w[np.maximum(index[k], 0)], 0.0) + const[k])
            else:
                row.extend(data[k])
        out.append(row)
    return np.array(out)


def test_node_inputs_against_explicit_construction():
    rng = np.random.default_rng(3)
    K, m, n, n_w = 4, 5, 2, 12
    bases = [rng.standard_normal((K, m)) * (rng.random((K, m)) < 0.6) for _ in range(3)]
    index = rng.permutation(n_w)[:m * n].reshape(m, n)
    index[0] = -1  # a fixed row
    index[2, 1] = -1  # a fixed entry
    fixed = rng.standard_normal((m, n))
    var_index = np.array([[10, -1], [11, 3], [-1, -1], [0, 0]])  # shared and repeated variables
    var_const = rng.standard_normal((K, 2))
    const = rng.standard_normal((K, 3))
    ni = NodeInputs(K, n_w)
    seg = [ni.spline(bases, index, fixed), ni.variables(var_index, var_const), ni.constant(const),
           ni.variables(var_index[:, :1])]
    assert seg == [slice(0, 6), slice(6, 8), slice(8, 11), slice(11, 12)] and ni.n_in == 12
    S, s0 = ni.build()
    assert S.shape == (K * 12, n_w) and s0.shape == (K * 12,)
    segments = [("spline", (bases, index, fixed)), ("variables", (var_index, var_const)), ("constant", const),
                ("variables", (var_index[:, :1], np.zeros((K, 1))))]
    np.testing.assert_allclose(s0, _explicit(K, segments, np.zeros(n_w)).ravel(), rtol=0, atol=1e-14)
    # affine: every column of S is the explicit construction's response to a unit w
    for j in range(n_w):
        e = np.zeros(n_w)
        e[j] = 1.0
        col = (_explicit(K, segments, e) - _explicit(K, segments, np.zeros(n_w))).ravel()
        np.testing.assert_allclose(S[:, j].toarray().ravel(), col, rtol=0, atol=1e-14)
    w = rng.standard_normal(n_w)
    np.testing.assert_allclose(S @ w + s0, _explicit(K, segments, w).ravel(), rtol=0, atol=1e-13)


def test_node_inputs_constants_only():
    ni = NodeInputs(3, 4)
    ni.constant(np.arange(6.0).reshape(3, 2))
    S, s0 = ni.build()
    assert S.shape == (6, 4) and S.nnz == 0
    np.testing.assert_array_equal(s0, np.arange(6.0))


# ------------------------------------------------------------ linear rows without Cg

def _square_family(name: str, monkeypatch, tmp_path, **kw) -> Family:
    """|w|^2 at one node (identity layer, w = x)."""
    from latentoc.latent import IdentityLayer

    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path / "jit"))
    y, yd, ydd, r = block_inputs(3, 0)
    block = RobotBlock.from_parts("assemble_square", (y, yd, ydd, r), {"s": ca.sumsqr(y)}, 3)
    ni = NodeInputs(1, 3)
    ni.variables(np.arange(3)[None, :])
    ni.constant(np.zeros((1, 6)))
    S, s0 = ni.build()
    return Family(name, BlockEvaluator(block, IdentityLayer(3)), S, s0, **kw)


def test_linear_family_without_evaluator():
    """A family of linear rows only: g = A w + c, dg/dw = A."""
    A, c = np.array([[1.0, 2.0, 0.0], [0.0, 1.0, -1.0]]), np.array([-1.0, -2.0])
    lin = Family("linear", None, sp.csr_matrix((0, 3)), np.zeros(0), L=sp.csr_matrix(A), c=c)
    nlp = SparseNLP(3, [lin])
    w = np.array([0.3, -0.2, 0.5])
    assert nlp.m == 2
    np.testing.assert_allclose(nlp.constraints(w), A @ w + c)
    np.testing.assert_allclose(ca.DM(nlp.jac_sparsity, nlp.jacobian(w)).full(), A)


def test_jacobian_agrees_with_constraints_when_L_has_no_Cg(monkeypatch, tmp_path):
    """An objective family with linear rows (L, c, no Cg) before a constraint family: the
    Jacobian is the derivative of the constraints (it had 2 w + A in the second family's row)."""
    A = np.array([[1.0, 2.0, 0.0]])
    first = _square_family("objective", monkeypatch, tmp_path, L=sp.csr_matrix(A), c=np.array([-1.0]), cf=np.ones(1))
    second = _square_family("square", monkeypatch, tmp_path, Cg=sp.identity(1, format="csr"))
    nlp = SparseNLP(3, [first, second])
    w, h = np.array([0.3, -0.2, 0.5]), 1e-6
    fd = np.column_stack([(nlp.constraints(w + h * e) - nlp.constraints(w - h * e)) / (2 * h) for e in np.eye(3)])
    np.testing.assert_allclose(ca.DM(nlp.jac_sparsity, nlp.jacobian(w)).full(), fd, rtol=0, atol=1e-8)


def test_mismatched_row_counts_are_refused(monkeypatch, tmp_path):
    L = sp.csr_matrix(np.ones((2, 3)))
    with pytest.raises(ValueError, match="square"):
        SparseNLP(3, [_square_family("square", monkeypatch, tmp_path, Cg=sp.identity(1, format="csr"), L=L)])
