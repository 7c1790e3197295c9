"""AMC reader: take 01_01, malformed files naming file and line, fuzzing."""
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mocap_fuzz import MUTATIONS, mutate

from latentoc.mocap import MocapFormatError, parse_amc, read_amc, read_asf

DIR = Path(__file__).resolve().parents[1] / "robots" / "cmu"
SKEL = read_asf(DIR / "01.asf")
LINES = (DIR / "01_01.amc").read_bytes().decode().split("\r\n")
SHORT = LINES[:3 + 30 * 5]  # header + 5 frames (fast to fuzz)
SHORT_TEXT = "\r\n".join(SHORT) + "\r\n"


def test_reads_take():
    m = read_amc(DIR / "01_01.amc", SKEL)
    assert m.n_frames == 2751 and m.fps == 120 and m.degrees
    assert np.isclose(m.duration, 2750 / 120)
    assert m["root"].shape == (2751, 6) and m["lfemur"].shape == (2751, 3)
    assert m["lhipjoint"].shape == (2751, 0)
    assert np.allclose(m["root"][0], [9.37216, 17.8693, -17.3198, -2.01677, -7.59696, -3.23164])
    assert np.isclose(m["lradius"][0, 0], 136.231) and np.isclose(m["ltoes"][0, 0], -4.61789)
    assert m.frame_numbers[0] == 1 and m.frame_numbers[-1] == 2751


def test_bones_in_any_order():
    lines = list(SHORT)
    lines[4], lines[5] = lines[5], lines[4]  # root <-> lowerback in frame 1
    m = parse_amc("\n".join(lines), SKEL)
    assert np.isclose(m["root"][0, 0], 9.37216) and np.isclose(m["lowerback"][0, 0], 2.30193)


def _bad(tmp_path, idx, new):
    lines = list(SHORT)
    lines[idx] = new
    p = tmp_path / "bad.amc"
    p.write_bytes("\r\n".join(lines).encode())
    with pytest.raises(MocapFormatError) as e:
        read_amc(p, SKEL)
    return p, e.value


@pytest.mark.parametrize("idx,new,word", [
    (35, "lshin 1 2 3", "lshin"),                 # bone not in ASF
    (35, "lowerback 2.3 -0.39", "3 values"),      # wrong count
    (35, "lowerback 2.3 -0.39 abc", "abc"),       # non-number
    (35, "lowerback 2.3 nan 1.0", "nan"),         # NaN
    (34, "root 1 2 3 4 5", "6 values"),           # root line of frame 2
    (35, "root 1 2 3 4 5 6", "twice"),            # bone repeated in a frame
])
def test_malformed_names_file_and_line(tmp_path, idx, new, word):
    p, e = _bad(tmp_path, idx, new)
    assert e.path == str(p) and e.line == idx + 1
    assert f"bad.amc, line {idx + 1}" in str(e) and word in str(e)


def test_missing_bone_in_frame(tmp_path):
    lines = list(SHORT)
    del lines[36]
    with pytest.raises(MocapFormatError) as e:
        parse_amc("\n".join(lines), SKEL, "m.amc")
    assert "m.amc" in str(e.value) and "lacks" in str(e.value)


def _check(text):
    try:
        parse_amc(text, SKEL, "fuzz.amc")
    except MocapFormatError as e:
        assert "fuzz.amc" in str(e)


_token = st.one_of(st.sampled_from(["nan", "inf", "-1e999", "root", "lfemur", "lhipjoint", "7",
                                    ":FULLY-SPECIFIED", ":RADIANS", "1 2 3", "", "#"]),
                   st.text(max_size=8))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(i=st.integers(0, len(SHORT) - 1), op=st.sampled_from(MUTATIONS), tok=_token, j=st.integers(0, 7))
def test_fuzz_mutated_lines(i, op, tok, j):
    _check(mutate(SHORT, i, op, tok, j))


@settings(max_examples=100, deadline=None)
@given(st.text(max_size=300))
def test_fuzz_random_text(text):
    _check(text)
