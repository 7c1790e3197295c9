"""Problem declarations: loading, validation messages naming file and key."""

from pathlib import Path

import pytest

from latentoc.problem import ProblemError, load_problem, parse_tube, problem_names, training_motion


def test_packaged_problems_load():
    assert {"arm-raise", "arm-raise-small"} <= set(problem_names())
    p = load_problem("arm-raise")
    assert (p.kind, p.robot, p.duration, p.latent_dim, p.control_points) == \
        ("latent-min-torque", "human-arm", 2.9, 3, 9)  # Table 1
    assert p.name == "arm-raise" and p.source.endswith("arm-raise.toml")


def test_load_by_path_and_stride(tmp_path):
    src = Path(load_problem("arm-raise-small").source)
    q = tmp_path / "mine.toml"
    q.write_text(src.read_text().replace('name = "arm-raise-small"\n', ""))
    p = load_problem(str(q))
    assert p.name == "mine"
    t, Q = training_motion(p)
    assert t[0] == 0 and abs(t[-1] - 2.9) < 1e-9 and Q.shape == (len(t), 7) and len(t) == 30


def test_unknown_name_lists_known():
    with pytest.raises(ProblemError, match="known problems: arm-raise"):
        load_problem("no-such-problem")


@pytest.mark.parametrize("edit, match", [
    (("[solver]", "[solver]\nbogus = 1"), "unknown key 'solver.bogus'"),
    (("duration = 2.9", 'duration = "long"'), "key 'duration' must be a positive number"),
    (('robot = "human-arm"', 'robot = "r2d2"'), "unknown robot 'r2d2'"),
    (('training = "human-arm-trial"', 'training = "dance"'), "unknown training motion 'dance'"),
    (('hessian = "exact"', 'hessian = "bfgs"'), "solver.hessian"),
    (("control_points = 7", "control_points = 3"), "fewer than spline_degree"),
    (('tube = "5x"', "tube = -1.0"), "latent.tube"),
    (("[gpdm]", "[gpdm]\nfoo = 2"), "unknown key gpdm.foo"),
    (("[gpdm]", "[extras]\na = 1\n[gpdm]"), r"unknown table \[extras\]"),
])
def test_bad_declarations_name_file_and_key(tmp_path, edit, match):
    src = Path(load_problem("arm-raise-small").source).read_text()
    assert edit[0] in src
    f = tmp_path / "bad.toml"
    f.write_text(src.replace(edit[0], edit[1], 1))
    with pytest.raises(ProblemError, match=match) as err:
        load_problem(f)
    assert str(f) in str(err.value)


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(ProblemError, match="does not exist"):
        load_problem(tmp_path / "nope.toml")
    f = tmp_path / "broken.toml"
    f.write_text("name = ")
    with pytest.raises(ProblemError, match="not valid TOML"):
        load_problem(f)


def test_parse_tube():
    assert parse_tube(1e-3) == (1e-3, False)
    assert parse_tube("1.5x") == (1.5, True)
    assert parse_tube("2e-4") == (2e-4, False)
    for bad in (-1.0, 0, "x", "abc", "-2x", True):
        with pytest.raises(ValueError):
            parse_tube(bad)
