"""Problem declarations: each kind's schema (types, ranges, defaults), messages naming file and key,
overrides, and the resolved settings `latentoc show` prints."""

import dataclasses
import tomllib
from pathlib import Path

import pytest

from latentoc.errors import LatentocError, ProblemError
from latentoc.gpdm import GPDMSettings
from latentoc.problem.kinds import KINDS, kind_of
from latentoc.min_torque.training import training_frames
from latentoc.problem.declaration import describe_problem
from latentoc.problem.toml_files import load_problem, problem_from_dict, problem_names
from latentoc.latent.tube import parse_tube


def test_packaged_problems_load():
    assert {"arm-raise", "arm-raise-small", "broad-jump"} <= set(problem_names())
    p = load_problem("arm-raise")
    assert (p.kind, p.robot, p.duration, p.latent_dim, p.control_points) == \
        ("latent-min-torque", "human-arm", 2.9, 3, 9)  # Table 1
    assert p.name == "arm-raise" and p.source.endswith("arm-raise.toml")
    assert p.gpdm["training_stride"] == 6


def test_load_by_path_and_stride(tmp_path):
    src = Path(load_problem("arm-raise-small").source)
    q = tmp_path / "mine.toml"
    q.write_text(src.read_text().replace('name = "arm-raise-small"\n', ""))
    p = load_problem(str(q))
    assert p.name == "mine"
    t, Q = training_frames(p)
    assert t[0] == 0 and abs(t[-1] - 2.9) < 1e-9 and Q.shape == (len(t), 7) and len(t) == 30


def test_unknown_name_lists_known():
    with pytest.raises(ProblemError, match="known problems: arm-raise"):
        load_problem("no-such-problem")


def _edited(tmp_path, name, old, new):
    src = Path(load_problem(name).source).read_text()
    assert old in src
    f = tmp_path / "bad.toml"
    f.write_text(src.replace(old, new, 1))
    return f


@pytest.mark.parametrize("name, edit, match", [
    ("arm-raise-small", ("[solver]", "[solver]\nbogus = 1"),
     r"unknown key 'solver.bogus'; \[solver\] of a latent-min-torque problem allows: hessian, max_iter, tol"),
    ("arm-raise-small", ("duration = 2.9", 'duration = "long"'), "key 'duration' must be a number > 0, or none, got 'long'"),
    ("arm-raise-small", ("duration = 2.9", "duration = 0"), "key 'duration' must be a number > 0, or none, got 0"),
    ("arm-raise-small", ('robot = "human-arm"', 'robot = "r2d2"'), "key 'robot' must be one of .*'panda'.*got 'r2d2'"),
    ("arm-raise-small", ('training = "human-arm-trial"', 'training = "dance"'), "key 'training' must be one of"),
    ("arm-raise-small", ('hessian = "exact"', 'hessian = "bfgs"'), "key 'solver.hessian' must be one of 'exact', "
                                                                    "'lbfgs', got 'bfgs'"),
    ("arm-raise-small", ("control_points = 7", "control_points = 3"), "fewer than spline_degree"),
    ("arm-raise-small", ("control_points = 7", "control_points = 4"), "at least 5 are needed"),
    ("arm-raise-small", ("control_points = 7", "control_points = 7.0"), "latent.control_points' must be an integer"),
    ("arm-raise-small", ('tube = "5x"', "tube = -1.0"), "key 'latent.tube' must be a positive number or a relative"),
    ("arm-raise-small", ("[gpdm]", "[gpdm]\nfoo = 2"), r"unknown key 'gpdm.foo'; \[gpdm\] allows: balanced, "),
    ("arm-raise-small", ("[gpdm]", "[gpdm]\nbalanced = 1"), "key 'gpdm.balanced' must be true or false, got 1"),
    ("arm-raise-small", ("[gpdm]", "[extras]\na = 1\n[gpdm]"), r"unknown table \[extras\]; .* \[baseline\], \[goal\], \[gpdm\]"),
    ("arm-raise-small", ('name = "arm-raise-small"', 'seed = 0'), "unknown key 'seed'; .* top-level keys description, duration, "
                                                       "kind, name, robot, training"),
    ("arm-raise-small", ('kind = "latent-min-torque"', 'kind = "dance"'), "unknown kind 'dance'; known: broad-jump"),
    # the broad jump: keys the kind does not read are errors, [options] typed by JumpSettings
    ("broad-jump", ('kind = "broad-jump"', 'kind = "broad-jump"\nduration = 1.3'),
     "unknown key 'duration'; a broad-jump problem allows the top-level keys description, kind, name"),
    ("broad-jump", ("[solver]", "[gpdm]\nbeta3_max = 1.0\n[solver]"), r"unknown table \[gpdm\]"),
    ("broad-jump", ("dim = 3", "dim = 3\nboundary = \"rest\""), r"unknown key 'latent.boundary'; \[latent\] .* "
                                                                   "allows: control_points, dim, tube"),
    ("broad-jump", ("friction = 0.4", "friction = 0.4\nmass = 63.86"), r"unknown key 'options.mass'; \[options\] "
                                                                       "allows: friction, leg_residual"),
    ("broad-jump", ("friction = 0.4", 'friction = "high"'), "key 'options.friction' must be a number > 0, got 'high'"),
    ("broad-jump", ("n_flight = 80", "n_flight = 80.5"), "key 'options.n_flight' must be an integer >= 2, got 80.5"),
    ("broad-jump", ("plant_training = true", "plant_training = 1"),
     "key 'options.plant_training' must be true or false, got 1"),
    ("broad-jump", ('sweep_starts = "warm"', 'sweep_starts = "cold"'), "key 'options.sweep_starts' must be one of "
                                                                            "'warm\\+cold', 'warm', got 'cold'"),
    ("broad-jump", ("training_stride = 1", "training_stride = 0"), "options.training_stride' must be an integer >= 1"),
])
def test_bad_declarations_name_file_key_and_allowed(tmp_path, name, edit, match):
    f = _edited(tmp_path, name, *edit)
    with pytest.raises(ProblemError, match=match) as err:
        load_problem(f)
    assert str(f) in str(err.value) and isinstance(err.value, LatentocError)


def test_jump_options_are_the_jump_settings():
    """Every JumpSettings field is a key of the broad jump's file ([options], or the table that sets
    it), with JumpSettings' default where the file leaves it out."""
    from latentoc.jump.problem import OPTIONS, SCHEMA, settings_from_problem
    from latentoc.jump.settings import JumpSettings

    problem = load_problem("broad-jump")
    data = tomllib.loads(Path(problem.source).read_text())["options"]
    defaults = JumpSettings()
    keys = {row[0] for row in SCHEMA.describe(problem.settings)}
    for f in dataclasses.fields(JumpSettings):
        elsewhere = {"tube": "latent.tube", "n_control": "latent.control_points", "hessian": "solver.hessian",
                     "max_iter": "solver.max_iter", "tol": "solver.tol"}
        key = elsewhere.get(f.name, f"options.{'friction' if f.name == 'mu' else f.name}")
        assert key in keys, f.name
        if key.startswith("options.") and key[8:] not in data:
            assert problem.options[key[8:]] == getattr(defaults, f.name), f.name
    s = settings_from_problem(problem, 0.02)
    assert s.mu == data["friction"] and s.n_flight == data["n_flight"] and s.n_control == 27 and s.tube == 0.02
    assert {k for k, v in OPTIONS.items() if v is None} == {"training_jumps", "training_stride", "torque_margin",
                                                            "torque_floor", "plant_training", "sweep_starts",
                                                            "leg_residual"}


def test_overrides_are_checked_like_the_file():
    p = load_problem("arm-raise-small", tube="2x", max_iter=4, gpdm={"seed": 3})
    assert (p.tube, p.max_iter, p.gpdm["seed"], p.gpdm["training_stride"]) == ("2x", 4, 3, 12)
    assert p.replace(latent_dim=2).latent_dim == 2 and p.latent_dim == 3  # a copy
    j = load_problem("broad-jump", options={"friction": 0.5}, hessian="lbfgs")
    assert j.options["friction"] == 0.5 and j.options["n_flight"] == 80 and j.hessian == "lbfgs"
    with pytest.raises(ProblemError, match="setting 'max_iter' .key 'solver.max_iter'. must be an integer >= 1"):
        load_problem("arm-raise-small", max_iter=0)
    with pytest.raises(ProblemError, match="unknown setting 'friction'; a latent-min-torque problem has"):
        load_problem("arm-raise-small", friction=0.3)
    with pytest.raises(ProblemError, match=r"unknown key 'options.frction'; \[options\] allows"):
        load_problem("broad-jump", options={"frction": 0.3})
    with pytest.raises(ProblemError, match="fewer than spline_degree"):
        load_problem("arm-raise-small").replace(control_points=3)


def test_problem_as_data_round_trip():
    """A problem travels to a sweep's worker as data and comes back equal, checked again."""
    for name in ("arm-raise", "broad-jump"):
        p = load_problem(name, tube="3x")
        assert problem_from_dict(p.to_dict()) == p
    bad = load_problem("arm-raise-small").to_dict()
    bad["settings"]["duration"] = -1.0
    with pytest.raises(ProblemError, match="duration"):
        problem_from_dict(bad)


def test_show_prints_every_resolved_setting():
    """`describe_problem` (latentoc show) has one line per key of the schema, with its value:
    the file's, or the default where the file leaves the key out."""
    p = load_problem("arm-raise")
    text = describe_problem(p)
    rows = kind_of(p.kind).schema.describe(p.settings)
    assert len(text.splitlines()) == 2 + len(rows)
    assert 'latent.tube = "5x"' in text and "gpdm.training_stride = 6" in text
    assert f"gpdm.seed = {GPDMSettings().seed}" in text  # not in the file: GPDMSettings' default
    assert "options.torque_margin = 0.1" in describe_problem(load_problem("g1-broad-jump"))  # not in that file


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(ProblemError, match="does not exist"):
        load_problem(tmp_path / "nope.toml")
    f = tmp_path / "broken.toml"
    f.write_text("name = ")
    with pytest.raises(ProblemError, match="not valid TOML"):
        load_problem(f)
    f.write_text('name = "x"\n')
    with pytest.raises(ProblemError, match="missing key 'kind'"):
        load_problem(f)
    f.write_text('kind = "latent-min-torque"\nrobot = "human-arm"\nduration = 1.0\n')
    with pytest.raises(ProblemError, match="missing key 'training'"):
        load_problem(f)


def test_parse_tube():
    assert parse_tube(1e-3) == (1e-3, False)
    assert parse_tube("1.5x") == (1.5, True)
    assert parse_tube("2e-4") == (2e-4, False)
    for bad in (-1.0, 0, "x", "abc", "-2x", True):
        with pytest.raises(ProblemError):
            parse_tube(bad)


def test_every_setting_of_every_kind_is_described():
    """`latentoc show` says what each key of each kind means, not only what its value must be."""
    from latentoc.problem.schema import Table

    for kind in KINDS.values():
        for s in kind.schema.settings:
            for t in (s.settings if isinstance(s, Table) else (s,)):
                assert t.doc and t.doc != t.check.what and not t.doc.startswith("JumpSettings."), (kind.name, t.key)
