"""A recording too long for the memory learning needs is refused before anything is computed, with the
numbers and the fix, never a MemoryError: from the library and from `latentoc learn`."""
import re

import numpy as np
import pytest

from latentoc.errors import LatentocError
from latentoc.gpdm import GPDMSettings, GPDMSizeError, learn_gpdm
from latentoc.gpdm.size import check_size, learning_memory

GIB = 2 ** 30


def test_the_memory_grows_with_the_square_of_the_frames():
    m = [learning_memory(N, 37, 3) for N in (1000, 2000, 4000)]
    assert 3.5 < (m[2] - m[1]) / (m[1] - m[0]) < 4.5
    assert learning_memory(1000, 37, 3) < 2 * GIB  # the N = 1000 target


def test_refused_with_the_numbers_and_the_fix():
    """The issue's 10 MB CSV: 103,781 frames of 7 joints at the default stride."""
    with pytest.raises(GPDMSizeError) as exc:
        check_size(103_781, 7, 3, available=16 * GIB)
    msg = str(exc.value)
    assert isinstance(exc.value, LatentocError) and not isinstance(exc.value, MemoryError)
    assert "103781 frames" in msg and "16.0 GiB are available" in msg
    need = float(re.search(r"needs about ([\d.]+) GiB", msg).group(1))
    assert need * GIB == pytest.approx(learning_memory(103_781, 7, 3), rel=1e-3)
    stride = int(re.search(r"--stride (\d+)", msg).group(1))
    assert learning_memory(-(-103_781 // stride), 7, 3) <= 16 * GIB  # the advice fits
    assert learning_memory(-(-103_781 // (stride - 1)), 7, 3) > 16 * GIB  # and is the smallest that does
    assert "--rate" in msg and "--start/--stop" in msg
    check_size(300, 37, 3, available=16 * GIB)  # what fits passes


def test_learn_gpdm_refuses_before_computing(monkeypatch):
    monkeypatch.setattr("latentoc.gpdm.size.available_memory", lambda: 64 * 2 ** 20)
    with pytest.raises(GPDMSizeError, match="1500 frames"):
        learn_gpdm(np.random.default_rng(0).standard_normal((1500, 7)), GPDMSettings())


def test_learn_command_refuses_a_long_recording(tmp_path, capsys, monkeypatch):
    from latentoc.cli.parser import main

    monkeypatch.setattr("latentoc.gpdm.size.available_memory", lambda: 256 * 2 ** 20)
    t = np.arange(3000) / 100.0
    q = 0.3 * np.sin(np.outer(t, [1.0, 0.7, 0.5, 0.3, 0.2, 0.1]))
    f = tmp_path / "long.csv"
    names = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
             "wrist_3_joint"]
    np.savetxt(f, np.column_stack([t, q]), delimiter=",", header="t," + ",".join(names), comments="")
    out = tmp_path / "out"
    assert main(["learn", str(f), "--robot", "ur5", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "latentoc: error: learning a GPDM on 3000 frames" in err and "--stride" in err
    assert not out.exists()
