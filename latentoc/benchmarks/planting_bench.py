"""How much leg freedom plants the broad jump's feet: a measurement for issue 34's design.

The jump's start (the GP mean along the start latent path, the training base) lets its loaded
points slide and hover by about a centimetre. This fits, by Gauss-Newton least squares over the
stance (0 .. takeoff) on the 1 kHz grid, the smallest change that plants them: a (x, z, pitch)
base spline of ``--base`` control points and a joint-space residual spline of ``--res`` control
points on the left leg's learned joints (the right leg mirrors them), added to the GP mean, with
every loaded point on one ground point (z = 0) per stretch of the contact modes: flat foot (heel,
ball, toe tip, pad) until heel off, on the ball (ball, toe tip, pad) until ball off, rolling on
the toe tip alone until takeoff.

Printed per fit: the largest distance of a loaded point from its ground point on the 1 kHz grid,
the largest residual, and the fitted motion's torques against Eq. 34's limits (contact forces by
non-negative least squares on the loaded points, as :mod:`latentoc.jump.robot.torque_limits` makes the
limits): the largest excess, the joint it is at and the share of samples over a limit.

Run: ``python -m latentoc bench planting [--res 0 8 16 32] [--base 12 24]``.
"""
from __future__ import annotations

import argparse
import itertools
import time

import numpy as np
import pinocchio as pin

from latentoc.jump.robot.sagittal_base import base_to_freeflyer
from latentoc.jump.demonstration.planted import learned_leg
from latentoc.jump.robot.feet import POINTS, foot_points, joint_embedding
from latentoc.jump.problem import setup
from latentoc.jump.robot.torque_limits import contact_torques
from latentoc.robots.point_kinematics import point_jacobian
from latentoc.latent.gp_layer import GPLayer
from latentoc.latent.spline import BSpline

RATE = 1000.0
PLANT_WEIGHT = 1e3  # per m of planting error, per point and 1 kHz sample
CHANGE_WEIGHT = 1e2  # per rad of residual and per m or rad of base change, per control point
ACC_WEIGHT = 1e-1  # per m/s^2 or rad/s^2 of changed base and leg acceleration, per 1 kHz sample


def _modes(ph, t: np.ndarray) -> dict[str, np.ndarray]:
    """Loaded samples per point in the stance (module doc)."""
    return {"heel": t <= ph.heel_off, "ball": t <= ph.ball_off, "toe": np.ones(t.shape, bool), "pad": t <= ph.ball_off}


def _gp_motion(js, t: np.ndarray) -> list[np.ndarray]:
    """The GP mean's learned coordinates and their first two time derivatives (Eq. 18, 26-28)
    along the start latent path at times t."""
    P = js.init["P"]
    sp = BSpline(P.shape[0], js.training.duration)
    m = GPLayer(js.gpdm).motion(np.hstack([sp.evaluate(P, t, k) for k in range(3)]))
    return [m.y, m.yd, m.ydd]


def plant_stance(js, n_base: int, n_res: int, iterations: int = 30, plant_weight: float = PLANT_WEIGHT,
                 acc_weight: float = ACC_WEIGHT) -> dict:
    """The least-squares planted stance (module doc) and what it measures."""
    model, tr, ph, geom = js.model, js.training, js.phases, js.geom
    E, leg = joint_embedding(js.smap), np.array(sorted(learned_leg(model, js.smap, geom)), int)
    t = np.arange(0.0, ph.takeoff + 0.5 / RATE, 1.0 / RATE)
    loaded = _modes(ph, t)
    Y_mu = _gp_motion(js, t)
    sb = BSpline(n_base, ph.takeoff)
    Bb = sb.basis(t)
    stance = ph.standing(tr.t)
    Pb = sb.fit(tr.t[stance], tr.base[stance])
    Pb0 = Pb.copy()
    Br = BSpline(n_res, ph.takeoff).basis(t) if n_res > 0 else np.zeros((len(t), 0))
    Bb2 = sb.basis(t, 2)
    Br2 = BSpline(n_res, ph.takeoff).basis(t, 2) if n_res > 0 else np.zeros((len(t), 0))
    smooth = acc_weight * np.block([[np.kron(np.eye(3), Bb2), np.zeros((3 * len(t), n_res * len(leg)))],
                                    [np.zeros((len(leg) * len(t), 3 * n_base)), np.kron(np.eye(len(leg)), Br2)]])
    Pr = np.zeros((n_res, len(leg)))
    stretches = [(k, name) for k, name in enumerate(POINTS)]
    d = model.createData()

    def configurations(Pb, Pr):
        Y = Y_mu[0].copy()
        Y[:, leg] += Br @ Pr
        return np.column_stack([base_to_freeflyer(Bb @ Pb)[0], Y @ E.T])

    def points(Q):
        out = np.zeros((len(Q), len(POINTS), 3))
        for i, q in enumerate(Q):
            pin.framesForwardKinematics(model, d, q)
            out[i] = foot_points(model, d, geom).T
        return out

    n_b, n_r = Pb.size, Pr.size

    def residuals(Pb, Pr, jacobian: bool):
        Q = configurations(Pb, Pr)
        pts = points(Q)
        ground = {name: pts[loaded[name], k, :2].mean(axis=0) for k, name in stretches}
        rows, J = [], []
        for i, q in enumerate(Q):
            if jacobian:
                pin.computeJointJacobians(model, d, q)
                pin.framesForwardKinematics(model, d, q)
            for k, name in stretches:
                if not loaded[name][i]:
                    continue
                p = pts[i, k]
                rows.append(plant_weight * (p - np.r_[ground[name], 0.0]))
                if jacobian:
                    Jp = point_jacobian(model, d, model.getFrameId(geom.points[k].frame), p)
                    dp_base = np.column_stack([[1, 0, 0], [0, 0, 1], np.cross([0, 1, 0], p - q[:3])])
                    dp_leg = (Jp[:, 6:] @ E)[:, leg]
                    J.append(plant_weight * np.hstack([np.kron(dp_base, Bb[i]), np.kron(dp_leg, Br[i])]))
        change = np.concatenate([(Pb - Pb0).T.ravel(), Pr.T.ravel()])
        r = np.concatenate(rows + [CHANGE_WEIGHT * change, smooth @ change])
        return r, (np.vstack(J + [CHANGE_WEIGHT * np.eye(n_b + n_r), smooth]) if jacobian else None)

    lam = 1e-3  # Levenberg-Marquardt damping, relative to the diagonal of J^T J
    r, J = residuals(Pb, Pr, True)
    for _ in range(iterations):
        JTJ, g = J.T @ J, J.T @ r
        while True:
            step = np.linalg.solve(JTJ + lam * np.diag(np.diag(JTJ) + 1e-12), -g)
            Pb1 = Pb + step[:n_b].reshape(3, n_base).T
            Pr1 = Pr + step[n_b:].reshape(len(leg), n_res).T if n_res else Pr
            r1, _ = residuals(Pb1, Pr1, False)
            if r1 @ r1 < r @ r or lam > 1e8:
                break
            lam *= 10
        if r1 @ r1 >= r @ r:
            break
        Pb, Pr, lam = Pb1, Pr1, lam / 10
        r, J = residuals(Pb, Pr, True)
        if np.max(np.abs(step)) < 1e-8:
            break
    Q = configurations(Pb, Pr)
    pts = points(Q)
    err = max(float(np.max(np.linalg.norm(pts[loaded[name], k] - np.r_[pts[loaded[name], k, :2].mean(0), 0.0], axis=1)))
              for k, name in stretches)
    residual = np.degrees(np.max(np.abs(Br @ Pr), axis=0)) if n_res else np.zeros(len(leg))
    return {"Q": Q, "t": t, "loaded": loaded, "planting_mm": 1e3 * err, "residual_deg": residual,
            "leg": leg, "Pb": Pb, "Pr": Pr,
            "torques": _torques(js, t, Y_mu, Pb, Pr, leg, loaded)}


def _torques(js, t: np.ndarray, Y_mu: list[np.ndarray], Pb: np.ndarray, Pr: np.ndarray, leg: np.ndarray,
             loaded: dict[str, np.ndarray]) -> dict:
    """Inverse dynamics of the fitted stance with NNLS point forces on the loaded points
    (:func:`latentoc.jump.robot.torque_limits.contact_torques`) against Eq. 34's limits."""
    model = js.model
    sb = BSpline(Pb.shape[0], js.phases.takeoff)
    Ym = [y.copy() for y in Y_mu]
    if Pr.size:
        sr = BSpline(Pr.shape[0], js.phases.takeoff)
        for k in range(3):
            Ym[k][:, leg] += sr.evaluate(Pr, t, k)
    E = joint_embedding(js.smap)
    base = base_to_freeflyer(*(sb.evaluate(Pb, t, k) for k in range(3)))
    Q, V, A = (np.column_stack([b, y @ E.T]) for b, y in zip(base, Ym))
    taus = contact_torques(model, js.geom, Q, V, A, np.ones(len(t), bool),
                           np.column_stack([loaded[name] for name in POINTS]))[0]
    lim = js.limits
    excess = np.maximum(taus - lim.tau_max, lim.tau_min - taus)
    worst = int(np.argmax(excess.max(axis=0)))
    return {"excess_Nm": float(excess.max()), "joint": model.names[int(np.searchsorted(
        [model.joints[j].idx_v for j in range(1, model.njoints)], worst + 6, side="right"))],
            "share_over": float(np.mean(np.any(excess > 1e-6, axis=1)))}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="latentoc bench planting", description=__doc__.splitlines()[0])
    parser.add_argument("--res", type=int, nargs="*", default=[0, 8, 16, 32], help="residual control points")
    parser.add_argument("--base", type=int, nargs="*", default=[12, 24], help="base control points")
    parser.add_argument("--plant-weight", type=float, nargs="*", default=[PLANT_WEIGHT],
                        help="weights per m of planting error (against 100 per rad or m of change)")
    parser.add_argument("--acc-weight", type=float, default=ACC_WEIGHT,
                        help="weight per rad/s^2 or m/s^2 of changed acceleration, per sample")
    args = parser.parse_args(argv)
    js = setup()
    print(f"{'weight':>8}{'base':>5}{'res':>5}{'planting mm':>13}{'max residual deg':>18}{'torque excess N m':>19}"
          f"{'at':>14}{'samples over':>14}{'time s':>8}")
    start = plant_stance(js, 12, 0, iterations=0)  # the start as it is: GP mean legs, training base
    tq = start["torques"]
    print(f"{'start':>8}{'':>10}{start['planting_mm']:>13.3f}{0.0:>18.2f}{tq['excess_Nm']:>19.1f}{tq['joint']:>14}"
          f"{100 * tq['share_over']:>13.0f}%")
    for w, nb, nr in itertools.product(args.plant_weight, args.base, args.res):
        t0 = time.perf_counter()
        fit = plant_stance(js, nb, nr, plant_weight=w, acc_weight=args.acc_weight)
        tq = fit["torques"]
        print(f"{w:>8.0e}{nb:>5}{nr:>5}{fit['planting_mm']:>13.3f}{float(np.max(fit['residual_deg'])):>18.2f}"
              f"{tq['excess_Nm']:>19.1f}{tq['joint']:>14}{100 * tq['share_over']:>13.0f}%"
              f"{time.perf_counter() - t0:>8.1f}", flush=True)
    return 0
