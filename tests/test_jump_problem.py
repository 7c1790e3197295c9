"""The broad-jump solve layer (latentoc.jump.problem.solve_jump_problem): warm starts."""
import dataclasses

import numpy as np
import pytest

import latentoc.jump.problem as jp
import latentoc.jump.verify
from latentoc.problem import load_problem


class _GP:
    latent_dim, beta, X = 3, np.ones(3), np.zeros((5, 3))

    def tube_size(self):
        return 1e-4


class _JS:
    gpdm, model = _GP(), None


def _fake_solve(calls, outcome, starts=None):
    """solve_broad_jump stand-in: ``outcome(warm, tube)`` gives (success, distance)."""
    def solve(js, s, x0=None, duals=None):
        warm = x0 is not None
        calls.append(warm)
        if starts is not None:
            starts.append((x0, duals))
        ok, dist = outcome(warm, s.tube)
        return {"result": {"success": ok, "warm_start": warm, "status": "Solve_Succeeded" if ok else "Maximum_Iterations_Exceeded",
                           "iterations": 7 if warm else 9, "solve_time_s": 1.0 if warm else 3.0, "distance": dist,
                           "distance_initial": 0.73},
                "w": np.full(3, s.tube + (0.0 if warm else 1.0)),
                "duals": (np.full(2, -s.tube), np.full(3, 2 * s.tube + (0.0 if warm else 1.0))),
                "nlp": type("N", (), {"x0": np.zeros(3), "lbg": np.zeros(2)})()}
    return solve


def _patched(monkeypatch, calls, outcome, starts=None, sweep_starts=None):
    monkeypatch.setattr(jp, "_SETUP_CACHE", {})
    monkeypatch.setattr(jp, "_WARM", {})
    monkeypatch.setattr(jp, "setup", lambda *a, **k: _JS())
    monkeypatch.setattr(jp, "solve_broad_jump", _fake_solve(calls, outcome, starts))
    monkeypatch.setattr(jp, "trajectory", lambda js, out: {"sigma2": np.zeros(2)})
    monkeypatch.setattr(latentoc.jump.verify, "verify", lambda *a, **k: {})
    problem = load_problem("broad-jump")
    if sweep_starts is not None:
        problem = dataclasses.replace(problem, options={**problem.options, "sweep_starts": sweep_starts})
    return problem


def test_sweep_keeps_the_better_of_the_warm_and_the_cold_start(monkeypatch):
    """After a solved smaller tube, a tube is solved from that optimum (its point and multipliers)
    and from the training fit; the better jump (converged first, then farther) is kept, the other
    reported, and the kept one seeds the next warm start."""
    calls, starts = [], []
    # warm: 0.08 fails, 0.16 converges short of the cold optimum; 0.32 warm is the better
    table = {(True, 0.08): (False, 0.4), (False, 0.08): (True, 0.9), (True, 0.16): (True, 0.85),
             (False, 0.16): (True, 0.95), (True, 0.32): (True, 0.99), (False, 0.32): (True, 0.97)}
    problem = _patched(monkeypatch, calls, lambda warm, tube: table.get((warm, tube), (True, 0.8)), starts)
    first = jp.solve_jump_problem(problem, tube=0.04).result
    assert calls == [False] and first["success"] and "other_start" not in first
    second = jp.solve_jump_problem(problem, tube=0.08).result
    assert calls == [False, True, False] and second["success"] and not second["warm_start"]
    assert second["other_start"] == {"warm_start": True, "status": "Maximum_Iterations_Exceeded", "iterations": 7,
                                     "solve_time_s": 1.0, "distance": 0.4}
    third = jp.solve_jump_problem(problem, tube=0.16).result
    assert calls[3:] == [True, False] and not third["warm_start"] and third["distance"] == 0.95
    assert third["other_start"]["warm_start"] and third["other_start"]["distance"] == 0.85
    fourth = jp.solve_jump_problem(problem, tube=0.32).result
    assert calls[5:] == [True, False] and fourth["warm_start"] and fourth["distance"] == 0.99
    assert fourth["other_start"] == {"warm_start": False, "status": "Solve_Succeeded", "iterations": 9,
                                     "solve_time_s": 3.0, "distance": 0.97}
    # each warm start gets the primal point and the multipliers (lam_g, lam_x) of the kept solve
    (x1, d1), (x2, d2), (x3, d3), (x4, _), (x5, d5), (x6, _), (x7, d7) = starts
    assert all(v is None for v in (x1, d1, x3, d3, x5, d5, x7, d7))
    np.testing.assert_array_equal(x2, np.full(3, 0.04 + 1.0))  # the cold 0.04 solve's point
    np.testing.assert_array_equal(d2[0], np.full(2, -0.04))
    np.testing.assert_array_equal(d2[1], np.full(3, 0.08 + 1.0))
    np.testing.assert_array_equal(x4, np.full(3, 0.08 + 1.0))  # the cold 0.08 solve's point
    np.testing.assert_array_equal(x6, np.full(3, 0.16 + 1.0))  # the cold 0.16 solve's point


def test_warm_sweep_starts_solve_cold_only_after_a_failed_warm_start(monkeypatch):
    """[options] sweep_starts = "warm": a converged warm start is kept without a cold solve; a
    failed one is solved again from the training fit; an unknown value is refused by name."""
    from latentoc.solve import SolveError

    calls = []
    problem = _patched(monkeypatch, calls, lambda warm, tube: (not (warm and tube == 0.08), 0.8), sweep_starts="warm")
    jp.solve_jump_problem(problem, tube=0.04)
    second = jp.solve_jump_problem(problem, tube=0.08).result
    third = jp.solve_jump_problem(problem, tube=0.16).result
    assert calls == [False, True, False, True]
    assert not second["warm_start"] and second["other_start"]["status"] == "Maximum_Iterations_Exceeded"
    assert third["warm_start"] and "other_start" not in third
    bad_calls = []
    bad = _patched(monkeypatch, bad_calls, lambda warm, tube: (True, 0.8), sweep_starts="cold")
    with pytest.raises(SolveError, match="sweep_starts must be one of"):
        jp.solve_jump_problem(bad, tube=0.04)
    assert bad_calls == [] and jp._SETUP_CACHE == {}  # refused before set-up and solve


def test_multipliers_of_another_layout_are_refused_by_name(monkeypatch):
    """Warm-start multipliers (or their x0) whose sizes do not fit the built NLP are an error
    naming ``duals`` and the sizes, before any solve."""
    built = []
    nlp = type("N", (), {"x0": np.zeros(3), "lbg": np.zeros(2)})()
    monkeypatch.setattr(jp, "initial_guess", lambda js, s: {})
    monkeypatch.setattr(jp, "build_nlp", lambda *a, warm_start=False: built.append(warm_start) or nlp)
    js = type("JS", (), {k: None for k in ("model", "smap", "gpdm", "geom", "phases", "limits", "sym")})()
    for x0, duals in [(np.zeros(3), (np.zeros(5), np.zeros(3))), (np.zeros(3), (np.zeros(2), np.zeros(4))),
                      (np.zeros(4), (np.zeros(2), np.zeros(3))), (None, (np.zeros(2), np.zeros(3)))]:
        with pytest.raises(ValueError, match=r"duals: \(lam_g, lam_x\) of sizes .* \(2 rows, 3 variables\)"):
            jp.solve_broad_jump(js, jp.JumpSettings(), x0=x0, duals=duals)
    assert built == [True] * 4


def test_unknown_option_is_refused_by_name():
    """A typo in [options] is an error naming the key, before any set-up or solve."""
    from latentoc.solve import SolveError

    problem = load_problem("broad-jump")
    jp.check_options(problem)  # the packaged problem uses known keys only
    bad = dataclasses.replace(problem, options={**problem.options, "n_flihgt": 80})
    with pytest.raises(SolveError, match=r"unknown \[options\] key\(s\) \['n_flihgt'\]"):
        jp.solve_jump_problem(bad, tube=0.02)
    with pytest.raises(SolveError, match="n_flihgt"):
        jp.settings_from_problem(bad, 0.02, None)


@pytest.mark.parametrize("training, stride, n_points", [(0, 3, 53), ("all", 10, 160)])
def test_training_stride_learns_every_kth_frame(training, stride, n_points):
    """The GPDM learns every stride-th frame of each jump: its mean at the learned latent points
    gives back those captured frames (to a few % of their range), and the Eq. 30 tube of the
    ten jumps holds every jump's latent points."""
    from latentoc.jump.training import training_jumps

    js = jp.setup(training, stride=stride)
    gp = js.gpdm
    Y = np.vstack([t.Y[::stride] for t in training_jumps(training)])
    assert gp.X.shape == (n_points, 3) and len(gp.latent_trajectories()) == (10 if training == "all" else 1)
    assert np.max(np.abs(gp.mean(gp.X) - Y)) < 0.03 * np.ptp(Y)
    tube = gp.tube_size()
    assert all(np.max(gp.variance(T)) <= tube for T in gp.latent_trajectories())
    assert js.init["P"].shape == (21, 3) and np.all(np.isfinite(js.init["P"]))


@pytest.mark.parametrize("stride", [0, 2.5, 100, "2"])
def test_bad_training_stride_is_refused_by_name(stride):
    from latentoc.solve import SolveError

    problem = load_problem("broad-jump")
    bad = dataclasses.replace(problem, options={**problem.options, "training_stride": stride})
    with pytest.raises(SolveError, match=r"training_stride: training stride must be an integer from 1 to 39"):
        jp.solve_jump_problem(bad, tube=0.02)
