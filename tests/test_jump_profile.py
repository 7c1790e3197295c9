"""The jump profile's accounting (``bench jump --profile``): Ipopt's timing statistics read as Ipopt
prints them, and the parts of a real Ipopt run measured by timers that leave the solve unchanged."""
import numpy as np

from latentoc.benchmarks.jump_profile import MUMPS_LINES, PARTS, ipopt_timing, profiled

IPOPT_TIMING = """\
Total seconds in IPOPT (w/o function evaluations)    =      0.008
OverallAlgorithm....................:      0.004 (sys:      0.001 wall:      0.008)
 ComputeSearchDirection.............:      0.002 (sys:      0.000 wall:      0.006)
 LinearSystemSymbolicFactorization..:      0.000 (sys:      0.000 wall:      0.002)
 LinearSystemFactorization..........:      0.010 (sys:      0.000 wall:      0.125)
 LinearSystemBackSolve..............:      0.001 (sys:      0.000 wall:      0.031)
  LinearSystemStructureConverterInit:      0.000 (sys:      0.000 wall:      0.000)
 Objective function gradient........:      0.000 (sys:      0.000 wall:      0.004)
"""


def test_ipopt_timing_reads_each_line_wall_seconds():
    t = ipopt_timing(IPOPT_TIMING)
    assert t["OverallAlgorithm"] == 0.008 and t["ComputeSearchDirection"] == 0.006
    assert [t[k] for k in MUMPS_LINES] == [0.002, 0.125, 0.031]
    assert t["LinearSystemStructureConverterInit"] == 0.0 and t["Objective function gradient"] == 0.004


def test_profiled_ipopt_run_splits_its_time_and_leaves_the_solve_unchanged(small_jump):
    """Three Ipopt iterations of the small jump NLP, with and without the timers: the same iterates;
    the parts add up to the run's wall time, the blocks and the layer fit inside the NLP callbacks
    and MUMPS inside Ipopt's own time; the timers are gone afterwards."""
    from latentoc.nlp import evaluators, ipopt

    sj = small_jump
    nlp = sj.nlp
    opts = {"max_iter": 3, "print_level": 0}
    plain = ipopt.solve(nlp.nlp, sj.x0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg, opts, desc="plain")
    methods = dict(evaluators.BlockEvaluator.__dict__)
    with profiled() as profile:
        run = ipopt.solve(nlp.nlp, sj.x0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg, opts, desc="timed")
    np.testing.assert_array_equal(run.x, plain.x)
    runs = profile.runs
    assert [r.desc for r in runs] == ["timed"] and runs[0].iterations == run.iterations == 3
    parts = runs[0].parts
    assert set(parts) == set(PARTS)
    assert np.isclose(sum(parts.values()), run.time_s, rtol=1e-12)
    blocks = parts["block values"] + parts["block Jacobians"] + parts["block Hessians"]
    assert blocks > 0 and parts["latent layer"] > 0 and parts["chain rule & assembly"] > 0
    assert blocks + parts["latent layer"] <= sum(run.timings.values())
    assert 0 < parts["MUMPS"] <= run.time_s - sum(run.timings.values())
    for kind, part in (("values", "block values"), ("jacobian", "block Jacobians"), ("hessian", "block Hessians")):
        by_block = [v for (_, k), v in runs[0].blocks.items() if k == kind]
        assert len(by_block) > 3 and np.isclose(sum(by_block), parts[part], rtol=1e-9)  # each block's share
    assert ipopt.solve.__name__ == "solve" and dict(evaluators.BlockEvaluator.__dict__) == methods
