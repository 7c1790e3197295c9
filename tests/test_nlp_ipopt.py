"""The one Ipopt path (latentoc.nlp.ipopt.solve) on small problems with known optima."""
import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp

from latentoc.latent import IdentityLayer
from latentoc.nlp import ipopt
from latentoc.nlp.assemble import Family, SparseNLP
from latentoc.nlp.blocks import RobotBlock, block_inputs
from latentoc.nlp.evaluators import BlockEvaluator
from latentoc.nlp.inputs import NodeInputs

N = 4


def _qp():
    """min 1/2 |w - a|^2 s.t. A w = b and w_3 <= u (active): a linear family, objective terms."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal(N)
    A = rng.standard_normal((2, N))
    b = rng.standard_normal(2)
    w = ca.SX.sym("w", N)
    terms = ca.Function("terms", [w], [0.5 * ca.sumsqr(w - a)])
    lin = Family("equalities", None, sp.csr_matrix((0, N)), np.zeros(0), Cg=sp.csr_matrix((2, 0)),
                 L=sp.csr_matrix(A), c=-b)
    nlp = SparseNLP(N, [lin], objective_terms=terms)
    # the optimum with w_3 fixed at its bound u, below the unconstrained optimum's w_3
    w_free = a - A.T @ np.linalg.solve(A @ A.T, A @ a - b)
    u = w_free[3] - 0.5
    B = np.vstack([A, np.eye(N)[3]])  # active constraints: A w = b, w_3 = u
    nu = np.linalg.solve(B @ B.T, B @ a - np.r_[b, u])
    w_opt = a - B.T @ nu
    ubx = np.full(N, np.inf)
    ubx[3] = u
    bounds = {"lbx": np.full(N, -np.inf), "ubx": ubx, "lbg": np.zeros(2), "ubg": np.zeros(2)}
    return nlp, bounds, w_opt, nu


def _circle(monkeypatch, tmp_path):
    """min c . w s.t. |w|^2 <= 1 through a robot block at one node with the identity layer:
    w* = -c / |c|, multiplier |c| / 2."""
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path / "jit"))
    y, yd, ydd, r = block_inputs(N, 0)
    block = RobotBlock.from_parts("circle", (y, yd, ydd, r), {"r2": ca.sumsqr(y)}, N)
    ni = NodeInputs(1, N)
    ni.variables(np.arange(N)[None, :])
    ni.constant(np.zeros((1, 2 * N)))
    S, s0 = ni.build()
    fam = Family("circle", BlockEvaluator(block, IdentityLayer(N)), S, s0, Cg=sp.identity(1, format="csr"))
    c = np.array([1.0, -2.0, 0.5, 2.0])
    w = ca.SX.sym("w", N)
    nlp = SparseNLP(N, [fam], objective_terms=ca.Function("terms", [w], [ca.dot(ca.DM(c), w)]))
    bounds = {"lbx": np.full(N, -np.inf), "ubx": np.full(N, np.inf), "lbg": np.array([-np.inf]), "ubg": np.array([1.0])}
    return nlp, bounds, -c / np.linalg.norm(c), np.linalg.norm(c) / 2


def test_qp_optimum_and_multipliers():
    nlp, bounds, w_opt, nu = _qp()
    res = ipopt.solve(nlp, np.zeros(N), **bounds)
    assert res.success and res.status == "Solve_Succeeded"
    assert isinstance(res.iterations, int) and 0 < res.iterations < 50
    np.testing.assert_allclose(res.x, w_opt, rtol=0, atol=1e-7)
    B = np.vstack([nlp.families[0].L.toarray(), np.eye(N)[3]])
    assert res.f == pytest.approx(0.5 * np.sum((B.T @ nu) ** 2), rel=1e-7)  # w* - a = -B^T nu
    np.testing.assert_allclose(res.g, 0.0, atol=1e-8)
    np.testing.assert_allclose(res.lam_g, nu[:2], rtol=0, atol=1e-6)
    np.testing.assert_allclose(res.lam_x, np.r_[0, 0, 0, nu[2]], rtol=0, atol=1e-6)
    assert set(res.timings) >= {"nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l"}


def test_nonlinear_constraint_through_a_block(monkeypatch, tmp_path):
    nlp, bounds, w_opt, lam = _circle(monkeypatch, tmp_path)
    res = ipopt.solve(nlp, np.full(N, 0.1), **bounds)
    assert res.success, res.status
    np.testing.assert_allclose(res.x, w_opt, rtol=0, atol=1e-7)
    np.testing.assert_allclose(res.lam_g, [lam], rtol=1e-6)
    lb = ipopt.solve(nlp, np.full(N, 0.1), **bounds, hessian="lbfgs")
    assert lb.success and "nlp_hess_l" not in lb.timings
    np.testing.assert_allclose(lb.x, w_opt, rtol=0, atol=1e-6)


@pytest.mark.parametrize("case", ["qp", "circle"])
def test_warm_start_from_own_multipliers(case, monkeypatch, tmp_path):
    """Started at its own optimum and multipliers Ipopt stops in very few iterations."""
    nlp, bounds, w_opt, _ = _qp() if case == "qp" else _circle(monkeypatch, tmp_path)
    cold = ipopt.solve(nlp, np.full(N, 0.1), **bounds)
    assert cold.success
    warm = ipopt.solve(nlp, cold.x, **bounds, warm=cold.multipliers())
    assert warm.success, warm.status
    assert warm.iterations <= 2 and warm.iterations < cold.iterations
    np.testing.assert_allclose(warm.x, w_opt, rtol=0, atol=1e-6)


def test_iteration_limit_is_reported():
    nlp, bounds, _, _ = _qp()
    res = ipopt.solve(nlp, np.zeros(N), **bounds, options={"max_iter": 1})
    assert not res.success
    assert res.status == "Maximum_Iterations_Exceeded" and res.iterations == 1


def test_unknown_hessian_is_refused():
    nlp, bounds, _, _ = _qp()
    with pytest.raises(ValueError, match="hessian"):
        ipopt.solve(nlp, np.zeros(N), **bounds, hessian="newton")


def test_callbacks_are_counted_and_timed_and_options_reach_ipopt(capfd):
    """IpoptResult.calls and .timings have the same callbacks; Ipopt prints nothing by default;
    an option Ipopt does not know is an error from Ipopt (the options are passed on)."""
    nlp, bounds, _, _ = _qp()
    res = ipopt.solve(nlp, np.zeros(N), **bounds)
    assert set(res.calls) == set(res.timings) and all(n > 0 for n in res.calls.values())
    assert res.calls["nlp_hess_l"] == res.iterations  # one Hessian per iteration
    assert "Ipopt" not in capfd.readouterr().out
    with pytest.raises(RuntimeError):
        ipopt.solve(nlp, np.zeros(N), **bounds, options={"no_such_ipopt_option": 1.0})


def _interrupting(nlp, after: int):
    """``nlp`` whose Hessian sends this process SIGINT (Ctrl-C) at its ``after``-th call."""
    import signal

    calls = {"n": 0}
    hessian = nlp.hessian

    def hess(w, sigma, lam):
        calls["n"] += 1
        if calls["n"] == after:
            signal.raise_signal(signal.SIGINT)
        return hessian(w, sigma, lam)

    nlp.hessian = hess
    return calls


@pytest.mark.usefixtures("sigint_default")
def test_ctrl_c_inside_ipopt_raises_instead_of_a_result(monkeypatch, tmp_path, capfd):
    """CasADi turns an exception inside a callback into the status NonIpopt_Exception_Thrown and
    returns a point; the solve must raise KeyboardInterrupt instead, stop at once, and print no
    traceback from inside CasADi."""
    nlp, bounds, _, _ = _circle(monkeypatch, tmp_path)
    calls = _interrupting(nlp, after=2)
    with pytest.raises(KeyboardInterrupt):
        ipopt.solve(nlp, np.zeros(N), **bounds)
    assert calls["n"] == 2  # no iteration after the interrupt
    assert "Traceback" not in capfd.readouterr().err


def test_a_failing_callback_raises_its_error(monkeypatch, tmp_path, capfd):
    nlp, bounds, _, _ = _circle(monkeypatch, tmp_path)

    def broken(w):
        raise ZeroDivisionError("in the constraints")

    nlp.constraints = broken
    with pytest.raises(ZeroDivisionError, match="in the constraints"):
        ipopt.solve(nlp, np.zeros(N), **bounds)
    assert "Traceback" not in capfd.readouterr().err  # raised once, by the solve, not printed by CasADi


def test_history_is_ipopts_log():
    """One entry per iteration (0 = the start) with the objective at the returned point last."""
    nlp, bounds, w_opt, _ = _qp()
    res = ipopt.solve(nlp, np.zeros(N), **bounds)
    h = res.history
    assert len(h["objective"]) == res.iterations + 1 == len(h["inf_pr"]) == len(h["mu"]) == len(h["iter"])
    assert h["objective"][-1] == pytest.approx(res.f, rel=1e-9)
    assert h["inf_pr"][0] > 1e-3 and h["inf_pr"][-1] < 1e-8  # the start violates A w = b; the end does not
