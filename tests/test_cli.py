"""`python -m latentoc`: list, show, solve (files + summary); input errors exit 2 with a message and no
files, bugs exit 1 with their traceback."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from latentoc.cli.parser import main
from latentoc.cli.commands import summary

REPO = Path(__file__).resolve().parents[1]


def test_list(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "arm-raise " in out and "arm-raise-small" in out


def test_list_verbose_and_show_print_the_resolved_settings(capsys):
    from latentoc.problem.declaration import describe_problem
    from latentoc.problem.toml_files import load_problem

    assert main(["show", "broad-jump"]) == 0
    assert capsys.readouterr().out == describe_problem(load_problem("broad-jump")) + "\n"
    assert main(["list", "--verbose"]) == 0
    out = capsys.readouterr().out
    assert "options.friction = 0.4" in out and 'latent.tube = "5x"' in out
    assert main(["show", "no-such"]) == 2 and "unknown problem" in capsys.readouterr().err


@pytest.mark.slow
def test_solve_writes_files_and_summary(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["solve", "arm-raise-small", "--quiet", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Solve_Succeeded" in text and "gain" in text and "result.json" in text
    r = json.loads((out / "result.json").read_text())
    assert r["success"] and r["problem"] == "arm-raise-small" and r["schema_version"] == 1
    with np.load(out / "trajectory.npz") as f:
        assert {"t", "q", "v", "a", "tau", "x", "P", "model"} <= set(f.files)
    assert sorted(p.name for p in out.iterdir()) == ["gpdm.npz", "result.json", "trajectory.npz"]


@pytest.mark.parametrize("args, match", [
    (["solve", "no-such"], "unknown problem 'no-such'; known problems"),
    (["solve", "arm-raise-small", "--tube", "-1"], "must be positive"),
    (["solve", "arm-raise-small", "--tube", "1e-12"], "infeasible"),
    (["solve", "arm-raise-small", "--latent-dim", "9"], "latent dimension"),
    (["solve", "arm-raise-small", "--control-points", "2"], "control_points"),
    (["solve", "arm-raise-small", "--hessian", "lbfgs", "--tube", "abc"], "neither a number"),
    (["sweep", "arm-raise-small", "--tubes", "0x"], "must be positive"),
    (["bench", "nothing"], "unknown benchmark"),
])
def test_errors_exit_2_without_files(tmp_path, capsys, args, match):
    out = tmp_path / "o"
    code = main(args + (["--out", str(out)] if args[0] in ("solve", "sweep") else []))
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("latentoc: error: ") and match in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.slow  # a fresh process
def test_module_entry_point_subprocess(tmp_path):
    p = subprocess.run([sys.executable, "-m", "latentoc", "solve", "arm-raise-small", "--tube", "-1",
                        "--out", str(tmp_path / "o")], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert p.returncode == 2 and p.stderr.startswith("latentoc: error:") and "Traceback" not in p.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.slow  # a fresh process
def test_a_bug_exits_1_with_its_traceback(tmp_path):
    """An exception that is not a LatentocError is a bug: its traceback, exit code 1."""
    out = tmp_path / "o"
    code = ("import dataclasses\nimport sys\nfrom latentoc.problem.kinds import KINDS\n"
            "def broken(problem, **kw):\n    return 1 / 0\n"
            "KINDS['latent-min-torque'] = dataclasses.replace(KINDS['latent-min-torque'], solve=broken)\n"
            f"from latentoc.cli.parser import main\nsys.exit(main(['solve', 'arm-raise-small', '--quiet', '--out', {str(out)!r}]))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert not out.exists()
    assert p.returncode == 1 and "Traceback" in p.stderr and "ZeroDivisionError" in p.stderr
    assert "latentoc: error" not in p.stderr


@pytest.mark.slow
def test_unconverged_solve_exits_1_and_writes_only_with_keep_failed(tmp_path, capsys):
    src = (REPO / "problems" / "arm-raise-small.toml").read_text()
    f = tmp_path / "short.toml"
    f.write_text(src.replace("max_iter = 200", "max_iter = 1"))
    out = tmp_path / "o"
    assert main(["solve", str(f), "--quiet", "--out", str(out)]) == 1
    assert "Maximum_Iterations_Exceeded" in capsys.readouterr().out and not out.exists()
    assert main(["solve", str(f), "--quiet", "--keep-failed", "--out", str(out)]) == 1
    assert sorted(p.name for p in out.iterdir()) == ["gpdm.npz", "result.json", "trajectory.npz"]
    assert json.loads((out / "result.json").read_text())["success"] is False


@pytest.mark.slow
def test_solve_plots_writes_png_figures_of_the_solution(tmp_path, capsys):
    from PIL import Image


    out = tmp_path / "arm"
    assert main(["solve", "arm-raise-small", "--quiet", "--out", str(out), "--plots"]) == 0
    pngs = sorted((out / "plots").glob("*.png"))
    assert {"joint_angles.png", "torques.png", "latent_tube.png", "stick_frames.png"} <= {p.name for p in pngs}
    for png in pngs:
        with Image.open(png) as im:
            assert im.size[0] > 200 and im.size[1] > 200
    with Image.open(out / "plots" / "motion.gif") as gif:
        assert gif.n_frames > 10
    assert "plots: " in capsys.readouterr().out


def test_list_robots_prints_every_robot_name(capsys):
    from latentoc.robots import load_robot, robot_names

    assert main(["list", "--robots"]) == 0
    names = capsys.readouterr().out.split()
    assert names == robot_names() and {"panda", "human-arm", "cmu-humanoid"} <= set(names)
    assert load_robot(names[-1]).nv > 0  # a name it lists loads


def test_plot_writes_every_figure_of_a_result_folder(tmp_path, capsys):
    """`plot RESULT --format pdf --out DIR`: the figures from the folder's files alone; a folder
    without result.json is an input error."""
    from result_factory import make_result

    r = make_result()
    r.convergence = [{"phase": "latent", "round": 1, "history": {k: [0.0, 1.0] for k in
                                                               ("iter", "objective", "inf_pr", "inf_du", "mu",
                                                                "alpha_pr", "alpha_du")}}]
    r.save(tmp_path / "r")
    assert main(["plot", str(tmp_path / "r"), "--format", "pdf", "--out", str(tmp_path / "figs"), "--no-gif"]) == 0
    names = sorted(p.name for p in (tmp_path / "figs").iterdir())
    assert names == sorted(f"{k}.pdf" for k in ("joint_angles", "joint_velocities", "torques", "stick_frames",
                                                "convergence"))
    assert all((tmp_path / "figs" / n).read_bytes().startswith(b"%PDF") for n in names)
    assert "wrote 5 figures" in capsys.readouterr().out
    assert main(["plot", str(tmp_path / "figs")]) == 2
    assert "no result.json" in capsys.readouterr().err


def test_solve_summary_reports_the_contact_checks():
    """For a contact problem the summary prints the exported motion's 1 kHz checks, as the
    result's details (here verify's numbers for a static stance, numeric Pinocchio) hold them."""
    from result_factory import make_result
    from test_jump_verify import _static_arrays

    from latentoc.jump.check.verify import verify

    model, arrays = _static_arrays()
    arrays["loaded"] = np.ones((len(arrays["t"]), 4), dtype=int)
    arrays["point_forces"] = np.zeros((len(arrays["t"]), 4, 2))
    arrays["point_forces"][:, 0] = (0.0, 300.0)
    checks = verify(model, arrays)
    r = make_result(tube=0.02, success=False, friction=0.4, **checks)
    text = summary(r)
    assert text.splitlines()[0] == "test (latent): Maximum_Iterations_Exceeded after 7 iterations"
    assert f"min normal force {checks['min_normal_force']:.1f} N" in text
    assert f"friction ratio {checks['max_friction_ratio']:.3f} (mu 0.4)" in text
    assert f"centre-of-pressure margin {1e3 * checks['cop_margin_loaded']:.2f} mm" in text
    assert f"COM margin {1e3 * checks['com_margin']:.2f} mm" in text
    assert f"Eq. 33 feet distance (both toe tips) {checks['eq33_feet_distance']:.3f} m" in text
    assert f"toe tip: forward travel {checks['toe_displacement']:.3f} m" in text
    assert (f"contact: loaded points travel {1e3 * checks['max_loaded_travel']:.2f} mm, height up to "
            f"{1e3 * checks['max_loaded_height']:.2f} mm, unloaded points down to "
            f"{1e3 * checks['min_unloaded_height']:.2f} mm; the ground's work 0 J positive, 0 J net") in text


@pytest.mark.slow  # a fresh process and a solve
def test_an_arm_solve_imports_neither_the_jump_nor_scipy_interpolate(tmp_path):
    """What a fixed-base solve's start pays for: the jump package and scipy.interpolate (with the
    scipy.optimize it brings) are imported only by what uses them."""
    code = ("import sys\nfrom latentoc.cli.parser import main\n"
            f"assert main(['solve', 'arm-raise-small', '--quiet', '--out', {str(tmp_path)!r}]) == 0\n"
            "print(sorted(m for m in sys.modules if m.startswith(('latentoc.jump', 'scipy.interpolate', "
            "'scipy.optimize'))))\n")
    p = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip().splitlines()[-1] == "[]"
