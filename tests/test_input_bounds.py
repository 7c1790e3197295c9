"""Inputs beyond what the package can take are refused up front with the input named, before the
parser or allocation that would crash on them (issue 36): problem files (size, nesting, dotted keys,
byte-order mark, not a file), URDF trees (duplicate names, undeclared or double parents, depth,
no mass), the viewer's frame rate and the CLI's positive numbers."""
from __future__ import annotations

import os
import tomllib

import numpy as np
import pytest

from latentoc.cli.parser import main
from latentoc.errors import ArgumentError, ProblemError
from latentoc.problem.toml_files import load_problem
from latentoc.robots.urdf import RobotFileError, load_urdf
from latentoc.problem.toml_limits import MAX_DEPTH, MAX_KEY_PARTS, toml_bounds_problem
from latentoc.viewer.scene import sample_indices


@pytest.mark.parametrize("text, match", [
    ("x = " + "[" * 100_000 + "]" * 100_000, "nested deeper than"),
    ("a" + ".a" * 50_000 + " = 1", "dotted parts"),
    ("x = { " + "a." * 40 + "b = 1 }", "dotted parts"),
    ("x = 1\n" * 200_000, "bytes; a problem file needs a few kB"),
])
def test_hostile_toml_is_refused_before_parsing(tmp_path, text, match):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(path)
    assert str(path) in str(info.value)


def test_bounds_scan_agrees_with_the_parser_on_real_files():
    """The scan passes what tomllib reads and counts its nesting and keys as tomllib does: strings,
    comments and numbers with dots do not count."""
    from latentoc.problem.toml_files import problems_dir

    for path in sorted(problems_dir().glob("*.toml")):
        assert toml_bounds_problem(path.read_text()) is None, path
    ok = ('s = "[[[ a.b.c.d ]]] \\" ["\nt = \'\'\'[ { .\n.\'\'\'  # [[[[ a.b.c\n'
          f'x = {"[" * MAX_DEPTH}1.5{"]" * MAX_DEPTH}\n' + "k" + ".k" * (MAX_KEY_PARTS - 1) + " = [1.0, 2.5]\n")
    assert toml_bounds_problem(ok) is None
    tomllib.loads(ok)
    assert toml_bounds_problem("x = " + "[" * (MAX_DEPTH + 1)) is not None
    assert toml_bounds_problem("k" + ".k" * MAX_KEY_PARTS + " = 1") is not None


def test_problem_files_that_are_not_files(tmp_path):
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + b'kind = "arm"\n')
    with pytest.raises(ProblemError, match="byte-order mark"):
        load_problem(bom)
    (tmp_path / "d.toml").mkdir()
    with pytest.raises(ProblemError, match="is a folder"):
        load_problem(tmp_path / "d.toml")
    os.mkfifo(tmp_path / "f.toml")
    with pytest.raises(ProblemError, match="not a regular file"):
        load_problem(tmp_path / "f.toml")
    with pytest.raises(ProblemError, match=r"did you mean 'arm-raise'\?.*or the path of a .toml file"):
        load_problem("arm-rase")
    with pytest.raises(ProblemError, match=r"\(1000000 characters\)") as info:
        load_problem("x" * 1_000_000)
    assert len(str(info.value)) < 2000


def _urdf(tmp_path, links: int, extra: str = "", mass: bool = True):
    inertial = ('<inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>'
                '</inertial>') if mass else ""
    body = "".join(f'<link name="l{i}">{inertial}</link>' for i in range(links + 1))
    body += "".join(f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
                    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
                    for i in range(links))
    path = tmp_path / "r.urdf"
    path.write_text(f'<robot name="r">{body}{extra}</robot>')
    return path


@pytest.mark.parametrize("links, extra, match", [
    (2, '<link name="l1"/>', "link 'l1' is declared 2 times"),
    (2, '<joint name="j0" type="fixed"><parent link="l0"/><child link="x"/></joint><link name="x"/>',
     "joint 'j0' is declared 2 times"),
    (2, '<joint name="jx" type="fixed"><parent link="nowhere"/><child link="x"/></joint><link name="x"/>',
     "joint 'jx': its parent link 'nowhere' is not declared"),
    (2, '<joint name="jx" type="fixed"><parent link="l0"/><child link="l2"/></joint>',
     "link 'l2' has two parents: joints 'j1' and 'jx'"),
    (2, '<link name="loose"/>', "2 root links"),
    (4000, "", "4001 links"),
    (300, "", "more than 200 joints from the root"),
])
def test_urdf_trees_pinocchio_cannot_take_are_named(tmp_path, links, extra, match):
    with pytest.raises(RobotFileError, match=match):
        load_urdf(_urdf(tmp_path, links, extra))


def test_a_robot_without_mass_is_refused_and_a_chain_within_bounds_loads(tmp_path):
    with pytest.raises(RobotFileError, match="no mass"):
        load_urdf(_urdf(tmp_path, 3, mass=False))
    model = load_urdf(_urdf(tmp_path, 150))  # as deep as allowed reads: Pinocchio's own numbers
    assert model.nv == 150 and np.isclose(sum(i.mass for i in model.inertias), 151.0)  # the root link's too


def test_view_rate_is_checked_before_allocating_frames():
    t = np.arange(1301) * 1e-3
    assert list(sample_indices(t, 1000.0)) == list(range(1301))
    assert list(sample_indices(t, 50.0)) == list(range(0, 1301, 20))
    assert list(sample_indices(t, 1e9)) == list(range(1301))  # never more frames than samples
    for bad in (0.0, -5.0, float("inf"), float("nan"), "fast"):
        with pytest.raises(ArgumentError, match="rate .* Hz: must be a positive, finite number"):
            sample_indices(t, bad)


@pytest.mark.parametrize("args", [["view", "somewhere", "--rate", "inf"], ["view", "somewhere", "--rate", "0"],
                                  ["learn", "x.csv", "--fps", "nan"], ["learn", "x.csv", "--rate", "-1"]])
def test_cli_numbers_must_be_positive_and_finite(capsys, args):
    with pytest.raises(SystemExit) as info:
        main(args)
    assert info.value.code == 2 and "must be a positive, finite number" in capsys.readouterr().err


def test_public_functions_name_a_wrong_argument():
    """Every public function refuses an argument of the wrong type with a LatentocError naming it,
    before any work; settings changed in place on a loaded problem are checked again by solve."""
    import latentoc

    problem = latentoc.load_problem("arm-raise-small")
    calls = [
        (lambda: latentoc.solve("arm-raise-small"), "solve\\(\\): argument 'problem' must be a Problem"),
        (lambda: latentoc.solve(problem, warm_start="x"), "argument 'warm_start' must be the Result"),
        (lambda: latentoc.solve(problem, gpdm=3), "argument 'gpdm' must be a learned GPDM"),
        (lambda: latentoc.load_result(42), "load_result\\(\\): argument 'out_dir'"),
        (lambda: latentoc.sweep(problem, "5x"), "argument 'tubes' must be a list of tubes"),
        (lambda: latentoc.sweep(problem, ["5x"], executor=1), "argument 'executor' must be a dask"),
        (lambda: latentoc.learn_gpdm(np.zeros((20, 3)), 1), "argument 'settings' must be a GPDMSettings"),
        (lambda: latentoc.SymbolicModel("panda"), "model must be a pinocchio.Model"),
    ]
    for call, match in calls:
        with pytest.raises(latentoc.LatentocError, match=match):
            call()
    changed = latentoc.load_problem("arm-raise-small")
    changed.settings["control_points"] = -3
    with pytest.raises(ProblemError, match="'control_points' .* must be an integer >= 2, got -3"):
        latentoc.solve(changed)


def test_every_command_argument_has_help_text():
    import argparse

    from latentoc.cli.parser import _parser

    commands = [a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction)][0].choices
    missing = [f"{name} {a.dest}" for name, sub in commands.items() for a in sub._actions
               if not a.help and not isinstance(a, argparse._HelpAction)]
    assert not missing
