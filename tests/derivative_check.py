"""Custom NLP derivatives against CasADi's automatic ones, shared by the latent and joint-space tests."""
import casadi as ca
import numpy as np


def check_custom_derivatives(nlp_dict: dict, w_centre: np.ndarray, seed: int,
                             tol: dict[str, tuple[float, float, float]]) -> None:
    """Compare ``nlp_dict["derivatives"]`` (grad_f, jac_g, hess_lag) with CasADi's derivatives of
    ``f`` and ``g`` at a random point near ``w_centre``.

    ``tol[k] = (rtol, atol, atol_rel)`` for k in grad_f, g, jac_g, hess: the absolute
    tolerance is ``atol + atol_rel * max|reference|``; f itself must match to 1e-12.
    """
    der = nlp_dict["derivatives"]
    w, f, g = nlp_dict["x"], nlp_dict["f"], nlp_dict["g"]
    rng = np.random.default_rng(seed)
    w0 = w_centre + 0.05 * rng.standard_normal(w_centre.size)
    lam_f, lam_g = 0.7, rng.standard_normal(g.shape[0])
    lf, lg = ca.MX.sym("lf"), ca.MX.sym("lg", g.shape[0])
    ref = ca.Function("ref", [w, lf, lg], [f, ca.gradient(f, w), g, ca.jacobian(g, w),
                                          ca.hessian(lf * f + ca.dot(lg, g), w)[0]])
    f_r, gf_r, g_r, jg_r, h_r = (np.asarray(ca.DM(v)) for v in ref(w0, lam_f, lam_g))
    f_c, gf_c = der["grad_f"](w0, [])
    g_c, jg_c = der["jac_g"](w0, [])
    h_c = np.asarray(ca.DM(der["hess_lag"](w0, [], lam_f, lam_g)))
    assert np.isclose(float(f_c), f_r.item(), rtol=1e-12)
    for key, got, want in (("grad_f", np.asarray(gf_c), gf_r), ("g", np.asarray(g_c), g_r),
                           ("jac_g", np.asarray(ca.DM(jg_c)), jg_r), ("hess", h_c, np.triu(h_r))):
        rtol, atol, atol_rel = tol[key]
        scale = np.abs(h_r).max() if key == "hess" else np.abs(want).max()
        assert np.allclose(got, want, rtol=rtol, atol=atol + atol_rel * scale), key
