"""SymbolicModel's CasADi Functions against Pinocchio's numeric algorithms."""

from __future__ import annotations

import casadi
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import DynamicsInputError, SymbolicModel, available_backends
from latentoc.robots import load_robot

ROBOTS = ["panda", "ur5", "talos", "human", "g1"]  # g1: the legged robot of issue 35
N_STATES = 20
LWA = pin.LOCAL_WORLD_ALIGNED


def _close(actual, expected, rel=1e-9):
    actual = np.asarray(actual, dtype=float).reshape(np.shape(expected))
    scale = max(1.0, float(np.max(np.abs(expected))))
    assert np.max(np.abs(actual - expected)) <= rel * scale, np.max(np.abs(actual - expected))


def _states(model: pin.Model, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    lower = np.maximum(model.lowerPositionLimit, -np.pi)
    upper = np.minimum(model.upperPositionLimit, np.pi)
    for _ in range(n):
        pin.seed(int(rng.integers(1 << 31)))
        q = pin.randomConfiguration(model, lower, upper)
        yield q, rng.normal(size=model.nv), rng.normal(size=model.nv)


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    model = load_robot(request.param)
    return model, SymbolicModel(model)


def test_backend_is_reported(robot):
    _, sym = robot
    assert sym.backend in available_backends()


def test_rnea_com_mass_matrix(robot):
    model, sym = robot
    data = model.createData()
    for q, v, a in _states(model, N_STATES):
        _close(sym.rnea(q, v, a), pin.rnea(model, data, q, v, a))
        _close(sym.com(q), pin.centerOfMass(model, data, q))
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        _close(sym.mass_matrix(q), M)


def test_centroidal_momentum_and_rate(robot):
    model, sym = robot
    data = model.createData()
    for q, v, a in _states(model, N_STATES, seed=1):
        h = pin.computeCentroidalMomentum(model, data, q, v)
        _close(sym.centroidal_momentum(q, v), h.vector)
        dh = pin.computeCentroidalMomentumTimeVariation(model, data, q, v, a)
        _close(sym.centroidal_momentum_rate(q, v, a), dh.vector)


def test_frames(robot):
    model, sym = robot
    data = model.createData()
    names = [model.frames[i].name for i in (1, model.nframes // 2, model.nframes - 1)]
    for q, v, _ in _states(model, N_STATES, seed=2):
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        pin.computeJointJacobians(model, data, q)
        for name in names:
            fid = model.getFrameId(name)
            p, R = sym.frame_placement(name)(q)
            _close(p, data.oMf[fid].translation)
            _close(R, data.oMf[fid].rotation)
            _close(sym.frame_velocity(name)(q, v), pin.getFrameVelocity(model, data, fid, LWA).vector)
            _close(sym.frame_jacobian(name)(q), pin.getFrameJacobian(model, data, fid, LWA))


def test_integrate_and_difference(robot):
    model, sym = robot
    states = list(_states(model, N_STATES + 1, seed=3))
    for (q0, dv, _), (q1, _, _) in zip(states[:-1], states[1:]):
        _close(sym.integrate(q0, dv), pin.integrate(model, q0, dv))
        _close(sym.difference(q0, q1), pin.difference(model, q0, q1), rel=1e-8)


def test_rnea_jacobians_match_rnea_derivatives(robot):
    model, sym = robot
    data = model.createData()
    q, v, a = (casadi.SX.sym(n, k) for n, k in (("q", model.nq), ("v", model.nv), ("a", model.nv)))
    tau = sym.rnea(q, v, a)
    jac = casadi.Function("rnea_jacobians", [q, v, a], [casadi.jacobian(tau, q), casadi.jacobian(tau, v), casadi.jacobian(tau, a)])
    for qn, vn, an in _states(model, 5, seed=4):
        dq, dv, da = pin.computeRNEADerivatives(model, data, qn, vn, an)
        Jq, Jv, Ja = (np.array(x) for x in jac(qn, vn, an))
        if model.nq == model.nv:
            _close(Jq, dq, rel=1e-8)
        else:
            # tangent-space derivative: differentiate tau(integrate(q, dv)) at dv = 0
            dvs = casadi.SX.sym("dvs", model.nv)
            tau_t = sym.rnea(sym.integrate(qn, dvs), vn, an)
            Jt = np.array(casadi.Function("rnea_tangent_jacobian", [dvs], [casadi.jacobian(tau_t, dvs)])(np.zeros(model.nv)))
            _close(Jt, dq, rel=1e-8)
        _close(Jv, dv, rel=1e-8)
        _close(Ja, np.triu(data.M) + np.triu(data.M, 1).T, rel=1e-8)


def test_both_backends_agree_where_present():
    if len(available_backends()) < 2:
        pytest.skip("only one backend on this machine: " + ", ".join(available_backends()))
    model = load_robot("panda")
    a, b = (SymbolicModel(model, backend=name) for name in available_backends())
    for q, v, acc in _states(model, 5):
        _close(a.rnea(q, v, acc), np.array(b.rnea(q, v, acc)).ravel())


def test_functions_are_cached_and_sized():
    model = load_robot("panda")
    sym = SymbolicModel(model)
    assert sym.rnea is sym.rnea
    assert sym.frame_jacobian("panda_hand") is sym.frame_jacobian("panda_hand")
    assert sym.rnea.size_in(0) == (model.nq, 1) and sym.rnea.size_out(0) == (model.nv, 1)
    assert sym.frame_jacobian("panda_hand").size_out(0) == (6, model.nv)


def test_bad_input_errors():
    model = load_robot("panda")
    sym = SymbolicModel(model)
    with pytest.raises(DynamicsInputError, match="unknown frame name 'no_such_frame'"):
        sym.frame_placement("no_such_frame")
    with pytest.raises(DynamicsInputError, match="unknown backend"):
        SymbolicModel(model, backend="cppad")
    with pytest.raises(DynamicsInputError, match="must be a pinocchio.Model"):
        SymbolicModel("panda")  # type: ignore[arg-type]
    with pytest.raises(DynamicsInputError, match="argument v has 3 entries, the model needs 9"):
        sym.check_arguments(q=np.zeros(9), v=np.zeros(3))
    with pytest.raises(RuntimeError, match="rnea"):
        sym.rnea(np.zeros(3), np.zeros(9), np.zeros(9))


def test_unsupported_joint_type_is_named():
    if "bridge" not in available_backends():
        pytest.skip("bridge backend not built")
    model = pin.Model()
    joint = pin.JointModelComposite(2)
    joint.addJoint(pin.JointModelRX())
    joint.addJoint(pin.JointModelRY())
    model.addJoint(0, joint, pin.SE3.Identity(), "shoulder")
    with pytest.raises(DynamicsInputError, match="shoulder.*does not handle"):
        SymbolicModel(model, backend="bridge")
