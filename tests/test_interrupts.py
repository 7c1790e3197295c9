"""Ctrl-C stops a solve, a sweep and a learning run at once: nothing that claims a result is
written, "interrupted" is printed and the exit code is 130 (issue 29). The fast tests stand in a
fake solver for Ipopt; the slow ones send SIGINT to a real solve in a subprocess."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from fake_solver import install, solution

import latentoc
from latentoc.cli.parser import main
from latentoc.robots import load_robot

pytestmark = pytest.mark.usefixtures("sigint_default")

REPO = Path(__file__).resolve().parents[1]


def _sigint_swallowed():
    """What CasADi does with a SIGINT it finds in its own code: clears it and carries on."""
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
    except KeyboardInterrupt:
        pass


def test_an_interrupt_the_solver_swallows_is_raised(monkeypatch):
    """The solver returns a point after a swallowed SIGINT (CasADi's NonIpopt_Exception_Thrown with
    cost 0): latentoc.solve raises KeyboardInterrupt instead of returning it as a result."""
    def swallowing(problem, warm):
        _sigint_swallowed()
        return solution(problem, 0.0, success=False, status="NonIpopt_Exception_Thrown")

    install(monkeypatch, swallowing)
    problem = latentoc.load_problem("arm-raise-small", tube=0.5)
    with pytest.raises(KeyboardInterrupt):
        latentoc.solve(problem)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored
    install(monkeypatch, lambda p, w: solution(p, 900.0))
    assert latentoc.solve(problem).cost == 900.0  # no interrupt left over for the next solve


def test_an_error_caused_by_the_interrupt_is_the_interrupt(monkeypatch):
    """A SIGINT inside C code can surface as another error (a SystemError from CasADi's array
    conversion): it is reported as the interrupt, not as a bug."""
    def failing(problem, warm):
        _sigint_swallowed()
        raise SystemError("returned a result with an exception set")

    install(monkeypatch, failing)
    with pytest.raises(KeyboardInterrupt):
        latentoc.solve(latentoc.load_problem("arm-raise-small", tube=0.5))


def _interrupt(problem, warm):
    raise KeyboardInterrupt


@pytest.mark.parametrize("extra", [[], ["--keep-failed"]])
def test_solve_interrupted_exits_130_and_writes_nothing(tmp_path, capsys, monkeypatch, extra):
    install(monkeypatch, _interrupt)
    out = tmp_path / "o"
    assert main(["solve", "arm-raise-small", "--tube", "0.5", "--quiet", "--out", str(out), *extra]) == 130
    captured = capsys.readouterr()
    assert "latentoc: interrupted" in captured.err and "gain" not in captured.out
    assert not out.exists()


def test_sweep_interrupted_stops_at_once(tmp_path, capsys, monkeypatch):
    """Ctrl-C in the second tube: the third is never started, the first (finished) tube's folder
    stays, the second has none, and no sweep.json claims a table."""
    def solver(problem, warm):
        if problem.tube == 0.5:
            raise KeyboardInterrupt
        return solution(problem, 800.0, warm_start=warm is not None)

    calls = install(monkeypatch, solver)
    out = tmp_path / "sweep"
    assert main(["sweep", "arm-raise-small", "--tubes", "0.2", "0.5", "0.9", "--quiet", "--out", str(out)]) == 130
    assert "latentoc: interrupted" in capsys.readouterr().err
    assert [c["tube"] for c in calls] == [0.2, 0.5]
    assert sorted(p.name for p in out.iterdir()) == ["tube-0.2"]
    assert latentoc.load_result(out / "tube-0.2").cost == 800.0


def test_learn_interrupted_exits_130_and_writes_nothing(tmp_path, capsys, monkeypatch):
    import latentoc.cli.learn as learn

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(learn, "learn_gpdm", interrupted)
    csv = tmp_path / "m.csv"
    csv.write_text("t,lhumerus_rz,lhumerus_ry\n" + "".join(f"{i / 10},{0.01 * i},{-0.01 * i}\n" for i in range(8)))
    out = tmp_path / "o"
    held = [a for name in load_robot("human-arm").names[2:] if name != "lhumerus_ry" for a in ("--hold", name)]
    assert main(["learn", str(csv), "--robot", "human-arm", "--latent-dim", "1", "--out", str(out), *held]) == 130
    assert "latentoc: interrupted" in capsys.readouterr().err and not out.exists()


def _run_and_interrupt(args, wait_for, timeout=300):
    """Start ``python -m latentoc ARGS``, send SIGINT once stderr shows ``wait_for`` (Ipopt's
    progress bar), and return (exit code, stdout, stderr)."""
    p = subprocess.Popen([sys.executable, "-m", "latentoc", *args], cwd=REPO, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, env={**os.environ, "LATENTOC_QUIET": "0", "LATENTOC_PROGRESS": "bars"})
    os.set_blocking(p.stderr.fileno(), False)
    err, t0 = b"", time.time()
    while wait_for.encode() not in err and time.time() - t0 < timeout and p.poll() is None:
        err += p.stderr.read() or b""
        time.sleep(0.02)
    p.send_signal(signal.SIGINT)
    out, rest = p.communicate(timeout=120)
    return p.returncode, out.decode(), (err + rest).decode()


@pytest.mark.slow  # subprocesses with real Ipopt runs
@pytest.mark.parametrize("command", ["solve", "sweep"])
def test_sigint_inside_ipopt_exits_130_and_writes_nothing(tmp_path, command):
    """SIGINT while Ipopt iterates (its progress bar shows an iteration): exit 130, "interrupted",
    no result.json of the interrupted solve, no NonIpopt_Exception_Thrown summary."""
    out = tmp_path / "o"
    args = [command, "arm-raise-small", "--out", str(out), "--keep-failed"] if command == "solve" else \
        [command, "arm-raise-small", "--tubes", "5x", "--out", str(out)]
    code, stdout, stderr = _run_and_interrupt(args, "it/s")
    assert code == 130, stdout + stderr
    assert "latentoc: interrupted" in stderr and "Traceback" not in stderr
    assert "NonIpopt" not in stdout and "gain" not in stdout
    assert not list(tmp_path.rglob("result.json")) and not list(tmp_path.rglob("sweep.json"))


def test_an_interrupt_a_library_catches_before_the_solve_is_raised(tmp_path, capsys, monkeypatch):
    """A SIGINT whose KeyboardInterrupt a library catches outside the solver (a bare ``except:`` in an
    import, say) still ends the command: exit 130, nothing written, no result printed."""
    import latentoc.problem.toml_files as files

    load = files.load_problem

    def swallowing_load(*args, **kwargs):
        _sigint_swallowed()
        return load(*args, **kwargs)

    monkeypatch.setattr(files, "load_problem", swallowing_load)
    install(monkeypatch, lambda p, w: solution(p, 900.0))
    out = tmp_path / "o"
    assert main(["solve", "arm-raise-small", "--tube", "0.5", "--quiet", "--out", str(out)]) == 130
    captured = capsys.readouterr()
    assert captured.err.rstrip().endswith("latentoc: interrupted") and not out.exists()


def test_an_interrupt_a_library_catches_in_a_command_that_writes_nothing_is_raised(capsys, monkeypatch):
    import latentoc.problem.toml_files as files

    names = files.problem_names

    def swallowing_names(*args, **kwargs):
        _sigint_swallowed()
        return names(*args, **kwargs)

    monkeypatch.setattr(files, "problem_names", swallowing_names)
    assert main(["list"]) == 130
    assert capsys.readouterr().err.rstrip().endswith("latentoc: interrupted")
