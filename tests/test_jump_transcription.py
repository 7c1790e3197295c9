"""Row blocks of the broad-jump NLP against numeric Pinocchio on the exported motion."""
import numpy as np
import pinocchio as pin
import pytest

from latentoc.jump.contact import TOE_PAD, foot_points
from latentoc.jump.problem import consistent_start, initial_guess, setup, trajectory
from latentoc.jump.transcription import JumpSettings, RowModel, build_nlp, node_rows
from latentoc.jump.verify import sagittal_contact_wrench
from latentoc.jump.zmp import G


def test_wrench_rows_are_the_cone_of_the_needed_wrench():
    """wrench_rows at stance and landing samples: the needed wrench of numeric pinocchio.rnea
    on the exported 1 kHz motion (verify.sagittal_contact_wrench), its cone and its centre of
    pressure rows, in body weights."""
    js = setup()
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False)
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    x = consistent_start(nlp, nlp.x0)
    parts = {k: np.array(v) for k, v in zip(nlp.unpack.name_out(), nlp.unpack(x))}
    tr = trajectory(js, {"settings": s, "parts": parts, "nlp": nlp})
    mass = sum(i.mass for i in js.model.inertias)
    rm = RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, s.mu, mass)
    block, layout = node_rows(rm, jit=False, optional=("wrench_rows",))["wrench_rows"]
    sp, sps, spl = nlp.meta["splines"]
    ph, d = js.phases, js.model.createData()
    ids = [js.model.getFrameId(n) for n in ("ltoes_end", "rtoes_end")]
    checked = 0
    for i in (40, 150, 290, 720, 900, 1250):  # ms: stance (heel, ball, toe loaded), landing
        t = tr["t"][i]
        land = t >= ph.touchdown
        X = [sp.evaluate(parts["P"], np.array([t]), k)[0] for k in range(3)]
        phs, off = (spl, ph.touchdown) if land else (sps, 0.0)
        coef = parts["phi_l"] if land else parts["phi_s"]
        f = [phs.evaluate(coef, np.array([t - off]), k)[0, 0] for k in range(3)]
        u = np.concatenate([*X, f, [float(parts["x_L"].ravel()[0]) if land else 0.0]])
        r = np.array(block.rows(u)).ravel()
        q, v, a = tr["q"][i], tr["v"][i], tr["a"][i]
        tau = pin.rnea(js.model, d, q, v, a)
        pin.computeJointJacobians(js.model, d, q)
        pin.framesForwardKinematics(js.model, d, q)
        J = sum(pin.getFrameJacobian(js.model, d, k, pin.LOCAL_WORLD_ALIGNED) for k in ids)
        fx, _, fz, _, my, _ = sagittal_contact_wrench(J, tau) / (mass * G)
        heel, ball, toe = foot_points(js.model, d, js.geom).T
        expected = {"wrench_normal": [fz], "wrench_friction": [s.mu * fz - fx, s.mu * fz + fx], "cop_front": [my],
                    "cop_heel": [(toe[0] - heel[0]) * fz - my], "cop_ball": [(toe[0] - ball[0]) * fz - my],
                    "cop_pad": [TOE_PAD * fz - my]}
        for name, val in expected.items():
            assert np.allclose(r[layout[name]], val, atol=1e-6 * max(1.0, abs(fz))), (t, name)
        checked += 1
    assert checked == 6


def test_wrench_samples_lie_between_the_nodes_with_the_scheduled_support():
    """With wrench_spacing the NLP gains one sample row set per interval slot, none at a node,
    and the rearmost support follows the contact schedule (heel, then ball, then toe pad)."""
    js = setup()
    base = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False)
    dense = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False, wrench_spacing=0.02)
    n0, n1 = (build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, st, initial_guess(js, st), js.sym)
              for st in (base, dense))
    names = np.array(n1.names)
    assert not any(k.startswith(("wrench_", "cop_")) for k in n0.names)
    n_samples = int((names == "wrench_normal").sum())
    grid = n1.meta["grid"]
    expect = sum(int(np.ceil((b - a) / 0.02 - 1e-9)) - 1 for tn in (grid["stance"], grid["land"])
                 for a, b in zip(tn[:-1], tn[1:]))
    assert n_samples == expect > 0
    assert (names == "wrench_friction").sum() == 2 * n_samples and (names == "cop_front").sum() == n_samples
    n_back = sum(int((names == k).sum()) for k in ("cop_heel", "cop_ball", "cop_pad"))
    assert n_back == n_samples and (names == "cop_pad").sum() > 0 and (names == "cop_heel").sum() > 0
    assert len(n1.names) == len(n0.names) + 5 * n_samples
    mass = sum(i.mass for i in js.model.inertias)
    with pytest.raises(ValueError, match="unknown optional row blocks"):
        node_rows(RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, 0.4, mass), jit=False, optional=("wrench",))
