"""Lifted row blocks: values, chained Jacobians and Hessians against CasADi's own derivatives."""
import casadi as ca
import numpy as np
import pytest

from latentoc.jump.lifted import NodeRows, compile_node_rows, lifted_hessian, lifted_rows, select_rows
from latentoc.transcription import affine_map


def _block() -> NodeRows:
    u = ca.SX.sym("u", 3)
    return NodeRows.from_expression("toy", u, ca.vertcat(ca.sin(u[0]) * u[1], u[2] ** 3 + u[0] * u[1], ca.exp(u[2])))


@pytest.mark.parametrize("jit", [False, True])
def test_lifted_rows_match_casadi_jacobian(jit):
    block = compile_node_rows({"toy": _block()}, jit=jit)["toy"]
    w = ca.MX.sym("w", 5)
    M = np.random.default_rng(0).standard_normal((3, 5))
    # four nodes, inputs affine in w with different maps and offsets
    U = ca.horzcat(*[ca.mtimes(ca.DM(M * (k + 1)), w) + k for k in range(4)])
    g, J = lifted_rows(block, U, w)
    ref = ca.vec(_block().rows.map(4)(U))
    f = ca.Function("f", [w], [g, J, ref, ca.jacobian(ref, w)])
    x = np.linspace(-0.5, 0.7, 5)
    g1, J1, g2, J2 = (np.array(v) for v in f(x))
    assert np.allclose(g1, g2, atol=1e-12) and np.allclose(J1, J2, atol=1e-10)
    gs, Js = select_rows(g, J, np.array([0, 5, 11]))
    gs1, Js1 = (np.array(v) for v in ca.Function("s", [w], [gs, Js])(x))
    assert np.allclose(gs1.ravel(), g1.ravel()[[0, 5, 11]]) and np.allclose(Js1, J1[[0, 5, 11]])


def test_affine_map_refuses_nonlinear_inputs():
    w = ca.MX.sym("w", 2)
    M, c = affine_map(ca.vertcat(2 * w[0] + 1, w[1] - w[0]), w)
    assert np.allclose(np.array(M), [[2, 0], [-1, 1]]) and np.allclose(np.array(c).ravel(), [1, 0])
    with pytest.raises(ValueError, match="not affine"):
        affine_map(ca.vertcat(w[0] * w[1]), w)


def test_lifted_rows_with_time_scaled_inputs():
    """Inputs not affine in w (the time scale multiplies the spline derivatives): the chain
    rule through CasADi's dU/dw against CasADi's Jacobian of the composed rows."""
    block = compile_node_rows({"toy": _block()}, jit=False)["toy"]
    w = ca.MX.sym("w", 4)
    ik = 1 / w[3]
    U = ca.horzcat(*[ca.vertcat(w[0] + k, ik * w[1], ik ** 2 * w[2] * k) for k in range(3)])
    g, J = lifted_rows(block, U, w, affine=False)
    ref = ca.vec(_block().rows.map(3)(U))
    x = np.array([0.3, -0.2, 0.5, 0.9])
    g1, J1, g2, J2 = (np.array(v) for v in ca.Function("f", [w], [g, J, ref, ca.jacobian(ref, w)])(x))
    assert np.allclose(g1, g2, atol=1e-12) and np.allclose(J1, J2, atol=1e-10)
    with pytest.raises(ValueError, match="not affine"):
        lifted_rows(block, U, w)


@pytest.mark.parametrize("jit", [False, True])
@pytest.mark.parametrize("affine", [True, False])
def test_lifted_hessian_matches_casadi_hessian(jit, affine):
    """The Hessian of lam . g, node Hessians chained through the inputs (and, for time-scaled
    inputs, the inputs' own curvature), against CasADi's Hessian of the composed rows."""
    block = compile_node_rows({"toy": _block().with_hessian()}, jit=jit)["toy"]
    w = ca.MX.sym("w", 4)
    M = np.random.default_rng(1).standard_normal((3, 4))
    if affine:
        U = ca.horzcat(*[ca.mtimes(ca.DM(M * (k + 1)), w) + k for k in range(3)])
    else:
        ik = 1 / w[3]
        U = ca.horzcat(*[ca.vertcat(w[0] + k, ik * w[1], ik ** 2 * w[2] * k) for k in range(3)])
    lam = ca.MX.sym("lam", 9)
    H, grad = lifted_hessian(block, U, w, lam, affine)
    ref, ref_grad = ca.hessian(ca.dot(lam, ca.vec(_block().rows.map(3)(U))), w)
    x = np.array([0.3, -0.2, 0.5, 0.9])
    lv = np.random.default_rng(2).standard_normal(9)
    H1, H2, g1, g2 = (np.array(v) for v in ca.Function("h", [w, lam], [H, ref, grad, ref_grad])(x, lv))
    assert np.allclose(H1, H1.T) and np.allclose(H1, H2, atol=1e-10) and np.allclose(g1, g2, atol=1e-10)
    with pytest.raises(ValueError, match="without its Hessian"):
        lifted_hessian(_block(), U, w, lam, affine)


@pytest.mark.parametrize("threads", ["1", "2"])
def test_compiled_blocks_on_threads_match_casadi(threads, monkeypatch):
    """Compiled blocks (forced on, also under LATENTOC_JIT=0) mapped serially or on 2 threads:
    rows, Jacobian and Hessian equal CasADi's derivatives of the composed rows."""
    monkeypatch.setenv("LATENTOC_JIT", "1")
    monkeypatch.setenv("LATENTOC_THREADS", threads)
    block = compile_node_rows({"toy": _block().with_hessian()})["toy"]
    if block.rows.class_name() != "External":
        pytest.skip("no C compiler: the blocks stay uncompiled")
    w = ca.MX.sym("w", 4)
    M = np.random.default_rng(3).standard_normal((3, 4))
    U = ca.horzcat(*[ca.mtimes(ca.DM(M * (k + 1)), w) + k for k in range(5)])
    lam = ca.MX.sym("lam", 15)
    g, J = lifted_rows(block, U, w)
    H = lifted_hessian(block, U, w, lam)[0]
    ref = ca.vec(_block().rows.map(5)(U))
    f = ca.Function("f", [w, lam], [g, J, H, ref, ca.jacobian(ref, w), ca.hessian(ca.dot(lam, ref), w)[0]])
    g1, J1, H1, g2, J2, H2 = (np.array(v) for v in f(np.array([0.3, -0.2, 0.5, 0.9]),
                                                        np.random.default_rng(4).standard_normal(15)))
    assert np.allclose(g1, g2, atol=1e-12) and np.allclose(J1, J2, atol=1e-10) and np.allclose(H1, H2, atol=1e-10)


def test_bad_thread_count_is_refused_by_name(monkeypatch):
    from latentoc.jump.lifted import threads

    monkeypatch.setenv("LATENTOC_THREADS", "two")
    with pytest.raises(ValueError, match="LATENTOC_THREADS must be a positive integer, got 'two'"):
        threads()
    monkeypatch.setenv("LATENTOC_THREADS", "3")
    assert threads() == 3


def test_compiled_blocks_are_found_from_their_rows(tmp_path, monkeypatch):
    """A second build of the same rows loads the compiled libraries from the on-disk index
    without building the derivatives (they would raise here), with the same values; other
    rows get their own entry, and an entry whose library is gone is rebuilt."""
    monkeypatch.setenv("LATENTOC_JIT", "1")
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    first = compile_node_rows({"toy": _block()}, hessian=True)["toy"]
    if first.rows.class_name() != "External":
        pytest.skip("no C compiler: the blocks stay uncompiled")
    u = ca.SX.sym("u", 3)
    lazy = NodeRows.from_expression("toy", u, ca.vertcat(ca.sin(u[0]) * u[1], u[2] ** 3 + u[0] * u[1], ca.exp(u[2])),
                                    lazy=True)
    assert lazy.jacobian is None

    def refuse(self):
        raise AssertionError("derivatives built although the block is indexed")

    with monkeypatch.context() as m:
        m.setattr(NodeRows, "with_jacobian", refuse)
        m.setattr(NodeRows, "with_hessian", refuse)
        again = compile_node_rows({"toy": lazy}, hessian=True)["toy"]
    x, lv = np.array([0.3, -0.2, 0.5]), np.array([1.0, -2.0, 0.5])
    ref = _block().with_hessian()
    for a, b in [(again.jacobian(x), ref.jacobian(x)), (again.hessian(x, lv), ref.hessian(x, lv))]:
        assert all(np.allclose(np.array(p), np.array(q), atol=1e-12) for p, q in zip(a, b))
    other = NodeRows.from_expression("toy", u, ca.vertcat(ca.sin(u[0]) * u[1], u[2] ** 3, ca.exp(u[2])), lazy=True)
    assert np.isclose(float(compile_node_rows({"toy": other})["toy"].rows(x)[1]), 0.125)
    assert len(list(tmp_path.glob("nr_*.json"))) == 2  # toy with its Hessian, the variant without
    for lib in tmp_path.glob("lc_*.so"):
        lib.unlink()
    rebuilt = compile_node_rows({"toy": _block()}, hessian=True)["toy"]
    assert np.allclose(np.array(rebuilt.hessian(x, lv)[0]), np.array(ref.hessian(x, lv)[0]), atol=1e-12)


def test_blocks_stay_sx_with_a_warning_without_compiler(tmp_path, monkeypatch):
    import latentoc.solver as solver

    monkeypatch.setenv("LATENTOC_JIT", "1")
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.setattr(solver, "jit_compiler", lambda: None)
    u = ca.SX.sym("u", 3)
    lazy = NodeRows.from_expression("toy", u, ca.vertcat(ca.sin(u[0]) * u[1], u[2] ** 3 + u[0] * u[1], ca.exp(u[2])),
                                    lazy=True)
    with pytest.warns(UserWarning, match="no C compiler"):
        block = compile_node_rows({"toy": lazy}, hessian=True)["toy"]
    assert block.rows.class_name() == "SXFunction" and block.hessian is not None
    x = np.array([0.3, -0.2, 0.5])
    assert np.allclose(np.array(block.jacobian(x)[1]), np.array(_block().jacobian(x)[1]))
    assert not list(tmp_path.glob("nr_*.json"))
