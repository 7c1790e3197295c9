"""The broad jump in the full configuration space (method "joint-range", latentoc.jump.schedule.path): the
same NLP with the 37 learned joints as the spline (the identity layer), on a jump with few nodes.

Its exact Jacobian and Hessian against central differences along random directions and along
each variable block's first coordinate (the blocks' derivatives taken in the joints directly,
RobotBlock.identity); the identity blocks against the generic ones fed the tangents (I, 0, 0); the
start on the training joints' fit, the control points' bounds, no tube; bad input refused by name.
"""
from types import SimpleNamespace

import numpy as np
import pytest
from finite_differences import central4, dense


@pytest.fixture(scope="module")
def full_jump(jump_parts):
    """The small jump's NLP (tests/conftest.py's small_jump settings) along the joint spline within
    +-30 deg of the training joints' fit, and its training start."""
    from latentoc.jump.schedule.phases import contact_sample_grid
    from latentoc.jump.transcription.nlp import build_nlp
    from latentoc.jump.schedule.path import joint_range_path
    from latentoc.jump.transcription.selection import Selection
    from latentoc.jump.settings import JumpSettings
    from latentoc.jump.solve.initial_point import initial_point
    from latentoc.jump.demonstration.training import antisymmetric_centre

    p = jump_parts
    js, robot = p.js, p.robot
    path = joint_range_path(js.init["P_joint"], 30.0, antisymmetric_centre(js.smap))
    blocks = js.blocks(robot, path.layer)
    settings = JumpSettings(n_stance=6, n_flight=6, n_land=6, sample_spacing=0.05)
    ph, nk = js.phases, robot.unmirrored.size
    tc = contact_sample_grid(settings, ph)[::2]
    tf = np.round(np.arange(ph.takeoff + 0.02, ph.touchdown - 0.01, 0.1), 3)
    selection = Selection(np.ones((12, nk)), np.ones((12, 8)), tc, np.ones((len(tc), nk)), np.ones((len(tc), 8)),
                          tf, np.ones((len(tf), nk)), np.zeros(0))
    nlp = build_nlp(robot, path.layer, blocks, ph, settings, path.P, "distance", selection, path.P_range)
    x0 = initial_point(robot, path.layer, nlp, ph, path.P, js.init["x_L"])
    return SimpleNamespace(p=p, path=path, blocks=blocks, settings=settings, nlp=nlp, x0=x0)


def _directions(nlp, n_random, seed):
    """Random directions and the first coordinate of the path's, the landing point's and the forces' blocks."""
    rng = np.random.default_rng(seed)
    var = nlp.variables
    return [rng.standard_normal(var.n) for _ in range(n_random)] + \
        [np.eye(var.n)[var.slices[name].start] for name in ("P", "x_L", "lam", "L_to")]


@pytest.mark.slow  # ~1 min with LATENTOC_JIT=0: the 37-joint blocks' SX derivatives are built here
def test_full_space_jacobian_and_hessian_match_central_differences(full_jump):
    """At a point near the start (random multipliers): J v against central differences of the
    constraints, row by row relative to the row's size; H v of the Lagrangian against central
    differences of sigma grad f + J^T lam; the objective's gradient against its differences."""
    jn, x0 = full_jump.nlp, full_jump.x0
    nlp = jn.nlp
    rng = np.random.default_rng(21)
    x = x0 + 0.01 * rng.standard_normal(x0.size) * np.maximum(1.0, np.abs(x0))
    sigma, lam = 0.7, rng.standard_normal(nlp.m)
    J = dense(nlp.jac_sparsity, nlp.jacobian(x))
    Hu = dense(nlp.hess_sparsity, nlp.hessian(x, sigma, lam))
    assert np.allclose(np.tril(Hu, -1), 0.0)
    Hl = Hu + Hu.T - np.diag(np.diag(Hu))

    def grad_lagrangian(v):
        return sigma * nlp.gradient(v) + dense(nlp.jac_sparsity, nlp.jacobian(v)).T @ lam

    for dv in _directions(jn, 2, 22):
        scale = np.maximum(1.0, np.abs(J) @ np.abs(dv))
        assert np.max(np.abs(central4(nlp.constraints, x, dv) - J @ dv) / scale) < 1e-7
        assert abs(central4(nlp.objective, x, dv) - nlp.gradient(x) @ dv) < 1e-7
        scale = np.maximum(1.0, np.abs(Hl) @ np.abs(dv))
        assert np.max(np.abs(central4(grad_lagrangian, x, dv) - Hl @ dv) / scale) < 3e-8
    # every row family has entries; the joints' control points enter the rows
    for name in set(jn.row_names):
        assert np.abs(J[jn.row_names == name]).max() > 0, name
    assert np.abs(J[:, jn.variables.slices["P"]]).max() > 0


def test_identity_blocks_are_the_generic_blocks_fed_identity_tangents(full_jump):
    """The flight-clearance block (feet heights of the joint pose, pitch and ballistic COM) built
    for the identity layer gives the values, Jacobian and Hessian of the generic block fed the
    tangents G0 = I, G1 = G2 = 0."""
    from latentoc.jump.rows import flight
    from latentoc.nlp.evaluators import BlockEvaluator

    p, path, blocks = full_jump.p, full_jump.path, full_jump.blocks
    generic = flight.clearance_block(p.robot, path.layer.latent_dim)
    assert not generic.identity and blocks["flight_clearance"].identity
    rng = np.random.default_rng(23)
    K, D = 3, path.layer.latent_dim
    s = np.hstack([0.3 * rng.standard_normal((K, 3 * D)), rng.standard_normal((K, generic.n_extra))])
    lam = rng.standard_normal((K, generic.n_out))
    a, b = BlockEvaluator(blocks["flight_clearance"], path.layer), BlockEvaluator(generic, path.layer)
    np.testing.assert_allclose(a.values(s), b.values(s), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(a.jacobian(s)[1], b.jacobian(s)[1], rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(a.hessian(s, lam), b.hessian(s, lam), rtol=1e-9, atol=1e-9)


def test_full_space_start_is_the_training_joints_fit(full_jump):
    """The start's control points are the least-squares fit of the training jump's 37 joints (the
    normal equations hold on the free points): the spline through them follows the captured joints
    to 2.5 deg RMS each, the antisymmetric centre joints at zero; the free control points are
    bounded to +-30 deg of the fit (the antisymmetric ones fixed), every other variable as in the
    latent NLP; no tube rows."""
    from latentoc.jump.transcription.nlp import build_nlp
    from latentoc.jump.demonstration.training import antisymmetric_centre

    p, path, jn, x0 = full_jump.p, full_jump.path, full_jump.nlp, full_jump.x0
    js = p.js
    P = jn.control_points(x0)
    np.testing.assert_array_equal(P, js.init["P_joint"])
    spline, tr = jn.spline, js.training
    B = spline.basis(tr.t)
    resid = B @ P - tr.Y
    np.testing.assert_allclose(P[[0, -1]], tr.Y[[0, -1]], atol=1e-12)  # through the end poses
    np.testing.assert_allclose((B.T @ resid)[1:-1], 0.0, atol=1e-9)
    assert np.degrees(np.sqrt(np.mean(resid ** 2, axis=0))).max() < 2.5
    fixed = antisymmetric_centre(js.smap)
    assert len(fixed) == 12 and np.all(P[:, fixed] == 0)
    D = path.layer.latent_dim
    lo, hi = (b[jn.variables.slices["P"]].reshape(-1, D) for b in (jn.lbx, jn.ubx))
    half = np.full_like(lo, np.radians(30.0))
    half[:, fixed] = 0.0
    np.testing.assert_allclose(hi - P[1:-1], half, atol=1e-12)
    np.testing.assert_allclose(P[1:-1] - lo, half, atol=1e-12)
    assert np.all(x0 >= jn.lbx) and np.all(x0 <= jn.ubx)
    latent = build_nlp(p.robot, p.layer, p.blocks, js.phases, full_jump.settings, js.init["P"], "distance",
                       jn.selection)
    for name in jn.variables.shapes:
        if name != "P":
            for a, b in ((jn.lbx, latent.lbx), (jn.ubx, latent.ubx)):
                np.testing.assert_array_equal(a[jn.variables.slices[name]], b[latent.variables.slices[name]])
    assert "tube" not in set(jn.row_names) and not path.has_tube and len(jn.selection.tube) == 0


def test_joint_path_refuses_tube_points(full_jump):
    """A selection with tube points cannot be built along the joint path (no sigma^2 there)."""
    from latentoc.jump.transcription.nlp import build_nlp

    from latentoc.jump.transcription.selection import Selection

    f = full_jump
    with_tube = f.nlp.selection.merged(Selection.empty(12, f.p.robot.unmirrored.size, np.array([0.5])))
    with pytest.raises(ValueError, match="tube points"):
        build_nlp(f.p.robot, f.path.layer, f.blocks, f.p.js.phases, f.settings, f.path.P, "distance", with_tube,
                  f.path.P_range)


@pytest.mark.parametrize("kw, match", [
    (dict(method="joint-range", joint_range_deg=-5.0), "joint range .* positive number of degrees, got -5.0"),
    (dict(method="joint-range", joint_range_deg=float("nan")), "joint range"),
    (dict(method="sampling"), "unknown method 'sampling' for broad-jump; choose one of latent, joint-range"),
])
def test_bad_method_or_joint_range_is_refused_by_name(kw, match):
    """Before any set-up or solve: a SolveError (latentoc's root error) naming the input."""
    from latentoc.errors import LatentocError, SolveError
    from latentoc.jump.problem import solve_jump_problem
    from latentoc.problem.toml_files import load_problem

    with pytest.raises(SolveError, match=match) as err:
        solve_jump_problem(load_problem("broad-jump"), **kw)
    assert isinstance(err.value, LatentocError)


def test_cli_negative_joint_range_exits_2_without_files(tmp_path, capsys):
    from latentoc.cli.parser import main

    out = tmp_path / "o"
    code = main(["solve", "broad-jump", "--method", "joint-range", "--joint-range", "-10", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("latentoc: error: ") and "joint range" in err and "Traceback" not in err
    assert not out.exists()


def test_problem_file_has_the_baseline_ranges():
    """broad-jump's [sweep] ranges: what `sweep broad-jump --baseline joint-range` solves."""
    from latentoc.problem.toml_files import load_problem

    problem = load_problem("broad-jump")
    assert problem.sweep_ranges == [10.0, 30.0, 90.0] and problem.joint_range_deg == 30.0
