"""The broad-jump problem kind (latentoc.jump.problem): [options], warm and cold starts, set-up."""
from types import SimpleNamespace
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID

import numpy as np
import pytest

import latentoc.jump.problem as jp
from latentoc.jump.settings import JumpSettings
from latentoc.jump.solve.solve import JumpSolution, solve_jump
from latentoc.nlp.ipopt import IpoptResult
from latentoc.problem.toml_files import load_problem
from latentoc.errors import SolveError


def _with_options(**options):
    return load_problem("broad-jump").replace(options=options)


def _refused_by_name(key: str, **options) -> None:
    """The option is refused, naming ``key``: by the problem's schema when it is set, else by the
    jump's solve before any set-up."""
    from latentoc.errors import LatentocError

    n_setups = len(jp._SETUP_CACHE)
    try:
        bad = _with_options(**options)
    except LatentocError as exc:
        assert key in str(exc)
        return
    with pytest.raises(LatentocError, match=key):
        jp.solve_jump_problem(bad, tube=0.02, control_points=17)
    assert len(jp._SETUP_CACHE) == n_setups  # refused before the set-up


class _Solves:
    """A stand-in for solve_jump at one tube: ``outcome[warm]`` = (success, distance); records the
    warm start each call gets."""

    def __init__(self, tube, outcome):
        self.tube, self.outcome, self.calls = tube, outcome, []

    def __call__(self, warm):
        self.calls.append(warm)
        ok, dist = self.outcome[warm is not None]
        result = {"tube": self.tube, "success": ok, "warm_start": warm is not None, "distance": dist,
                  "status": "Solve_Succeeded" if ok else "Maximum_Iterations_Exceeded",
                  "iterations": 7 if warm is not None else 9,
                  "times": {"solve_s": 1.0 if warm is not None else 3.0}}
        return SimpleNamespace(result=result, warm={"tube": self.tube, "x0": np.full(3, dist)})


def test_warm_and_cold_starts_keep_the_better_jump():
    """With a warm start and sweep_starts "warm+cold", the tube is solved from the warm start and
    from the training fit; the better jump (converged first, then farther) is kept and the other
    reported in other_start. Without a warm start only the cold solve runs."""
    warm = {"tube": 0.04, "x0": np.zeros(3)}
    cold_only = _Solves(0.04, {False: (True, 0.9)})
    sol = jp.solve_from_starts(cold_only, None, "warm+cold")
    assert cold_only.calls == [None] and "other_start" not in sol.result
    # the warm start fails: the cold one is kept
    s = _Solves(0.08, {True: (False, 0.99), False: (True, 0.9)})
    sol = jp.solve_from_starts(s, warm, "warm+cold")
    assert s.calls == [warm, None] and not sol.result["warm_start"] and sol.result["distance"] == 0.9
    assert sol.result["other_start"] == {"warm_start": True, "status": "Maximum_Iterations_Exceeded",
                                         "iterations": 7, "solve_time_s": 1.0, "distance": 0.99}
    # both converge: the farther is kept, whichever start it came from
    for outcome, kept_warm in (({True: (True, 0.85), False: (True, 0.95)}, False),
                               ({True: (True, 0.99), False: (True, 0.97)}, True)):
        s = _Solves(0.16, outcome)
        sol = jp.solve_from_starts(s, warm, "warm+cold")
        assert s.calls == [warm, None] and sol.result["warm_start"] is kept_warm
        assert sol.result["distance"] == outcome[kept_warm][1]
        assert sol.result["other_start"]["warm_start"] is not kept_warm
        assert sol.result["other_start"]["distance"] == outcome[not kept_warm][1]
    # neither converges: still the farther
    s = _Solves(0.32, {True: (False, 0.5), False: (False, 0.6)})
    assert not jp.solve_from_starts(s, warm, "warm+cold").result["warm_start"]


def test_warm_sweep_starts_solve_cold_only_after_a_failed_warm_start():
    """sweep_starts "warm": a converged warm start is kept without a cold solve; a failed one is
    solved again from the training fit (and the better kept)."""
    warm = {"tube": 0.04, "x0": np.zeros(3)}
    s = _Solves(0.08, {True: (True, 0.8), False: (True, 0.9)})
    sol = jp.solve_from_starts(s, warm, "warm")
    assert s.calls == [warm] and sol.result["warm_start"] and "other_start" not in sol.result
    s = _Solves(0.08, {True: (False, 0.8), False: (True, 0.7)})
    sol = jp.solve_from_starts(s, warm, "warm")
    assert s.calls == [warm, None] and not sol.result["warm_start"]
    assert sol.result["other_start"]["status"] == "Maximum_Iterations_Exceeded"


def test_a_warm_start_is_taken_from_a_smaller_solved_tube_only():
    """A previous Solution's warm start serves a tube at least as large as its own; a failed solve
    (warm None) or a larger tube gives none."""
    prev = SimpleNamespace(warm={"tube": 0.04, "x0": np.zeros(3)})
    assert jp.usable_warm_start(prev, 0.04) is prev.warm and jp.usable_warm_start(prev, 0.08) is prev.warm
    assert jp.usable_warm_start(prev, 0.02) is None
    assert jp.usable_warm_start(SimpleNamespace(warm=None), 0.08) is None
    assert jp.usable_warm_start(None, 0.08) is None


def test_warm_start_carries_the_point_and_multipliers_of_phase_2(small_jump):
    """JumpSolution.warm_start: the tube, the solution's point and its multipliers (lam_g, lam_x)
    with the NLP they belong to (its rows and samples), what the next tube's solve starts from."""
    jn = small_jump.nlp
    rng = np.random.default_rng(0)
    x, lam_g, lam_x = small_jump.x0, rng.standard_normal(jn.nlp.m), rng.standard_normal(jn.variables.n)
    run = IpoptResult(x=x, f=0.0, g=jn.nlp.constraints(x), lam_g=lam_g, lam_x=lam_x, status="Solve_Succeeded",
                      success=True, iterations=3, time_s=0.1)
    warm = JumpSolution(jn, x, run, None, {}, {}, {"tube": 0.02}).warm_start()
    assert warm["tube"] == 0.02 and warm["nlp"] is jn and len(warm["nlp"].selection.contact) > 0
    for key, value in (("x0", x), ("lam_g0", lam_g), ("lam_x0", lam_x)):
        np.testing.assert_array_equal(warm[key], value)


def test_a_warm_start_that_does_not_fit_the_nlp_is_refused_by_name(small_jump):
    """A warm start whose point has another number of variables than its NLP is a ValueError
    naming the warm start and both sizes, before any solve."""
    sj = small_jump
    n, m = sj.nlp.variables.n, sj.nlp.nlp.m
    bad = {"tube": 0.02, "nlp": sj.nlp, "x0": np.zeros(n + 3), "lam_g0": np.zeros(m), "lam_x0": np.zeros(n + 3)}
    with pytest.raises(ValueError, match="warm start: its point") as exc:
        solve_jump(sj.robot, sj.layer, sj.blocks, sj.js.phases, sj.settings, sj.js.init, sj.js.model, warm=bad)
    assert str(n + 3) in str(exc.value) and str(n) in str(exc.value)


def test_packaged_options_set_the_jump_settings():
    """The packaged problem's [options] are all known and set their JumpSettings fields."""
    problem = load_problem("broad-jump")
    jp.check_options(problem)
    s = jp.settings_from_problem(problem, 0.02)
    o = problem.options
    assert isinstance(s, JumpSettings) and s.tube == 0.02 and s.mu == o["friction"]
    for key, field in jp.OPTIONS.items():
        if field is not None and key in o:
            assert getattr(s, field) == o[key], key
    assert s.n_control == problem.control_points and s.hessian == "exact"
    assert jp.settings_from_problem(problem, 0.02, "lbfgs").hessian == "lbfgs"


@pytest.mark.parametrize("key", ["n_flihgt", "time_scale", "base_model", "contact_model", "knot_nodes",
                                 "push_off_nodes", "n_base_stance", "foot_tolerance", "contact_tolerance", "sticking"])
def test_unknown_or_removed_option_is_refused_by_name(key):
    """A typo in [options], or an option of the removed toe-pinned base, contact models, knot or
    push-off nodes, free time scale, base splines and placement tolerances, is an error naming the
    key, before any set-up or solve."""
    _refused_by_name(key, **{key: 1})


def test_bad_sweep_starts_is_refused_by_name():
    _refused_by_name("sweep_starts", sweep_starts="cold")


def test_unsupported_method_and_hessian_are_refused_by_name():
    problem = load_problem("broad-jump")
    with pytest.raises(SolveError, match="method 'sampling'"):
        jp.solve_jump_problem(problem, tube=0.02, method="sampling")
    with pytest.raises(SolveError, match="hessian.*'bfgs'"):
        jp.solve_jump_problem(problem, tube=0.02, hessian="bfgs")


@pytest.mark.parametrize("stride", [0, 2.5, 100, "2"])
def test_bad_training_stride_is_refused_by_name(stride):
    _refused_by_name("training_stride", training_stride=stride)


@pytest.mark.parametrize("training, stride, n_points", [(0, 3, 53), ("all", 20, 80)])
def test_training_stride_learns_every_kth_frame(training, stride, n_points):
    """The GPDM learns every stride-th frame of each jump: its mean at the learned latent points
    gives back those captured frames (RMS within 3 % of their range: the converged model keeps a
    noise level, docs/gpdm.md), and the Eq. 30 tube of the ten jumps holds every jump's latent points."""
    from latentoc.jump.demonstration.training import training_jumps

    js = jp.setup(training, stride=stride)
    gp = js.gpdm
    Y = np.vstack([t.Y[::stride] for t in training_jumps(training)])
    assert gp.X.shape == (n_points, 3) and len(gp.latent_trajectories()) == (10 if training == "all" else 1)
    assert np.sqrt(np.mean((gp.mean(gp.X) - Y) ** 2)) < 0.03 * np.ptp(Y)
    tube = gp.tube_size()
    assert all(np.max(gp.variance(T)) <= tube for T in gp.latent_trajectories())
    assert js.init["P"].shape == (27, 3) and np.all(np.isfinite(js.init["P"]))


def test_plant_training_learns_and_limits_the_planted_jump():
    """plant_training: the GPDM learns the planted jump (latentoc.jump.demonstration.planted, tested in
    test_planting.py), whose largest change per leg joint the set-up keeps, and the Eq. 34 limits
    are the planted jump's own inverse dynamics: every torque of its B-spline fit lies inside them."""
    from latentoc.jump.demonstration.planted import planted_training
    from latentoc.jump.schedule.phases import training_phases
    from latentoc.jump.demonstration.training import training_jumps
    from latentoc.robots.cmu_humanoid import symmetric_model

    js = jp.setup(0, stride=3, plant=True)
    model, smap = symmetric_model()
    tr = training_jumps(0)[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    planted = planted_training(model, smap, tr, training_phases(model, tr, geom), geom)
    np.testing.assert_allclose(js.training.Y, planted.training.Y, atol=0)
    np.testing.assert_allclose(js.gpdm.Y, planted.training.Y[::3], atol=0)
    assert js.planted is not None and js.planted.change_deg == planted.change_deg
    ch = js.planted.change_deg  # the toe joint takes the foot's rise over the flat toes: it changes most
    assert max(ch, key=ch.__getitem__) == "ltoes_rx" and ch["ltoes_rx"] > 10
    lim = js.limits
    assert np.all(lim.tau <= lim.tau_max + 1e-9) and np.all(lim.tau >= lim.tau_min - 1e-9)
