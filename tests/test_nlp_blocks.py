"""Robot blocks (latentoc.nlp.blocks): rows, local Jacobian and local Hessian of F(u(s)) for the
linearised joint motion u(s) of the module doc, against the chain rule through CasADi's own
derivatives of F with respect to u = (y, yd, ydd, r); compiled and uncompiled; the disk cache.
"""
import json
import os
import subprocess
import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.nlp import jit
from latentoc.nlp.blocks import RobotBlock, block_inputs, compile_blocks, stack_tangents

D, LATENT, N_EXTRA = 3, 2, 2  # joints, latent dimension, extra inputs r


def planar_arm() -> pin.Model:
    """Three links hinged about y, hanging along z under gravity."""
    model = pin.Model()
    parent = 0
    for i in range(D):
        joint = model.addJoint(parent, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.3 if i else 0.0])),
                               f"joint{i}")
        model.appendBodyToJoint(joint, pin.Inertia(1.0 - 0.2 * i, np.array([0.02, 0.0, 0.15]),
                                                   np.diag([0.01, 0.012, 0.002])), pin.SE3.Identity())
        parent = joint
    return model


def make_block(name: str = "arm_rows") -> RobotBlock:
    """Torques (RNEA on SX) and two rows nonlinear in the extra inputs r."""
    y, yd, ydd, r = block_inputs(D, N_EXTRA)
    tau = SymbolicModel(planar_arm()).rnea(y, yd, ydd)
    parts = {"tau": tau * (1 + r[0] ** 2) + r[1],
             "power": ca.dot(tau, yd) * ca.sin(r[0]),
             "reach": ca.cos(y[0]) * y[1] * r[1] * ydd[2]}
    return RobotBlock.from_parts(name, (y, yd, ydd, r), parts, LATENT)


def _nodes(K: int, seed: int):
    rng = np.random.default_rng(seed)
    u = [rng.uniform(-1, 1, (K, D)), rng.uniform(-2, 2, (K, D)), rng.uniform(-5, 5, (K, D)),
         rng.uniform(-0.5, 0.5, (K, N_EXTRA))]
    G = [rng.standard_normal((K, D, LATENT)) for _ in range(3)]
    return u, G


def _tangent_map(G0, G1, G2) -> np.ndarray:
    """du/ds for u = (y, yd, ydd, r) and s = (dx, dxd, dxdd, dr) (module doc), one node."""
    d, Z, I = LATENT, np.zeros((D, LATENT)), np.eye(N_EXTRA)
    T = np.zeros((3 * D + N_EXTRA, 3 * d + N_EXTRA))
    T[:3 * D, :3 * d] = np.block([[G0, Z, Z], [G1, G0, Z], [G2, 2 * G1, G0]])
    T[3 * D:, 3 * d:] = I
    return T


def _reference(block: RobotBlock, u, G, lam):
    """F, dF/ds, d2(l . F)/ds2 and d(l . F)/d(y, yd, ydd) per node by the chain rule: s enters
    u linearly, so dF/ds = dF/du T and d2(l . F)/ds2 = T^T d2(l . F)/du2 T."""
    y, yd, ydd, r = block_inputs(D, N_EXTRA)
    uu = ca.vertcat(y, yd, ydd, r)
    F = block.rows_sx(y, yd, ydd, r)
    ll = ca.SX.sym("l", block.n_out)
    ref = ca.Function("ref", [y, yd, ydd, r, ll], [F, ca.jacobian(F, uu), ca.hessian(ca.dot(ll, F), uu)[0],
                                                   ca.gradient(ca.dot(ll, F), uu)])
    out = {"F": [], "J": [], "H": [], "mu": []}
    for k in range(len(lam)):
        Fk, dF, d2, g = (np.asarray(v) for v in ref(u[0][k], u[1][k], u[2][k], u[3][k], lam[k]))
        T = _tangent_map(G[0][k], G[1][k], G[2][k])
        out["F"].append(Fk.ravel())
        out["J"].append(dF @ T)
        out["H"].append(T.T @ d2 @ T)
        out["mu"].append(g.ravel()[:3 * D])
    return {k: np.array(v) for k, v in out.items()}


def _mapped(block: RobotBlock, u, G, lam):
    """The block's mapped rows, jac and hess at K nodes, in the evaluators' node-major layout."""
    K, n_in, n_out = len(lam), block.n_local, block.n_out
    args = list(u)  # K x n: the column-major data of the mapped n x K inputs
    tangents = [stack_tangents(g) for g in G]
    F = block.mapped("rows", K)(*args)[0].reshape(K, n_out)
    Fj, J = block.mapped("jac", K)(*args, *tangents)
    H, mu = block.mapped("hess", K)(*args, *tangents, lam)
    return {"F": F, "Fj": Fj.reshape(K, n_out),
            "J": J.reshape(K, n_in, n_out).transpose(0, 2, 1),
            "H": H.reshape(K, n_in, n_in).transpose(0, 2, 1),
            "mu": mu.reshape(K, -1)}


def _close(got, want, rtol=1e-12):
    np.testing.assert_allclose(got, want, rtol=0, atol=rtol * max(np.abs(want).max(), 1.0))


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path / "jit"))
    return tmp_path / "jit"


def _needs_compiler():
    if jit.compiler() is None:
        pytest.skip("no C compiler")


def test_layout_and_sizes():
    block = make_block()
    assert (block.output_dim, block.n_extra, block.latent_dim) == (D, N_EXTRA, LATENT)
    assert block.n_out == D + 2 and block.n_local == 3 * LATENT + N_EXTRA
    assert block.layout == {"tau": slice(0, D), "power": slice(D, D + 1), "reach": slice(D + 1, D + 2)}


@pytest.mark.parametrize("jit_on", [False, True], ids=["sx", "compiled"])
def test_block_against_chain_rule(jit_on, cache, monkeypatch):
    if jit_on:
        _needs_compiler()
    monkeypatch.setenv("LATENTOC_JIT", "1" if jit_on else "0")
    block = compile_blocks([make_block()])[0]
    assert all((f.class_name() == "External") == jit_on for f in block.functions.values())
    K = 5
    u, G = _nodes(K, seed=1)
    lam = np.random.default_rng(2).standard_normal((K, block.n_out))
    got, want = _mapped(block, u, G, lam), _reference(block, u, G, lam)
    _close(got["F"], want["F"])
    _close(got["Fj"], want["F"])
    _close(got["J"], want["J"])
    _close(got["H"], want["H"])
    _close(got["mu"], want["mu"])
    np.testing.assert_allclose(got["H"], np.swapaxes(got["H"], 1, 2), rtol=0, atol=1e-12 * np.abs(got["H"]).max())
    # the torque rows are Pinocchio's: numeric RNEA at r = 0
    model = planar_arm()
    data = model.createData()
    F0 = np.asarray(block.functions["rows"](u[0][0], u[1][0], u[2][0], np.zeros(N_EXTRA))).ravel()
    _close(F0[block.layout["tau"]], pin.rnea(model, data, u[0][0], u[1][0], u[2][0]))


def test_compiled_equals_uncompiled(cache, monkeypatch):
    _needs_compiler()
    K = 4
    u, G = _nodes(K, seed=3)
    lam = np.random.default_rng(4).standard_normal((K, D + 2))
    out = {}
    for flag in ("0", "1"):
        monkeypatch.setenv("LATENTOC_JIT", flag)
        out[flag] = _mapped(compile_blocks([make_block()])[0], u, G, lam)
    for key in out["0"]:
        _close(out["1"][key], out["0"][key], rtol=1e-13)


def _snapshot(directory: Path) -> dict[str, int]:
    return {str(p.relative_to(directory)): p.stat().st_mtime_ns for p in directory.rglob("*")}


_FRESH = """
import json, sys
sys.path.insert(0, {tests!r})
from test_nlp_blocks import make_block
from latentoc.nlp.blocks import compile_blocks
b = compile_blocks([make_block()])[0]
print(json.dumps({{k: f.class_name() for k, f in b.functions.items()}}))
"""


@pytest.mark.slow  # a fresh process
def test_fresh_process_finds_the_cache(cache, monkeypatch):
    """A second compile_blocks in a new process loads the three libraries through the cache
    index and writes nothing (no new or rebuilt file)."""
    _needs_compiler()
    monkeypatch.setenv("LATENTOC_JIT", "1")
    compile_blocks([make_block()])
    index = list(cache.glob("rb_*.json"))
    assert len(index) == 1
    libs = json.loads(index[0].read_text())["libraries"]
    assert len(libs) == 3 and all((cache / name).exists() for parts in libs for name in parts)
    before = _snapshot(cache)
    env = {**os.environ, "LATENTOC_CACHE": str(cache), "LATENTOC_JIT": "1"}
    run = subprocess.run([sys.executable, "-c", _FRESH.format(tests=str(Path(__file__).parent))],
                         env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout.strip().splitlines()[-1]) == {"rows": "External", "jac": "External", "hess": "External"}
    assert _snapshot(cache) == before
