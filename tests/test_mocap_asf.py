"""ASF reader: the CMU skeleton, malformed files naming file and line, fuzzing."""
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mocap_fuzz import MUTATIONS, mutate

from latentoc.mocap import MocapFormatError, parse_asf, read_asf

ASF = Path(__file__).resolve().parents[1] / "robots" / "cmu" / "01.asf"
TEXT = ASF.read_bytes().decode()
LINES = TEXT.split("\r\n")


def test_reads_cmu_skeleton():
    s = read_asf(ASF)
    assert "\r\n" in TEXT  # CRLF as distributed
    assert len(s.bones) == 30 and s.n_dof == 62
    assert np.isclose(s.unit_to_m, 0.0254 / 0.45) and np.isclose(s.unit_to_m, 0.05644, atol=1e-5)
    assert s.angle_unit == "deg" and s.root.order == ["TX", "TY", "TZ", "RX", "RY", "RZ"]
    assert s.root.axis == "XYZ"
    f = s.bones["lfemur"]
    assert f.id == 2 and f.dof == ["rx", "ry", "rz"] and f.limits[0] == (-160.0, 20.0)
    assert np.allclose(f.axis, [0, 0, 20]) and f.axis_order == "XYZ"
    assert np.isclose(f.length, 7.1578) and np.isclose(np.linalg.norm(f.direction), 1)
    assert f.parent == "lhipjoint" and f.children == ["ltibia"]
    assert s.bones["lhipjoint"].dof == [] and s.bones["lhipjoint"].parent == "root"
    assert s.hierarchy["thorax"] == ["lowerneck", "lclavicle", "rclavicle"]
    assert s.bones["lwrist"].children == ["lhand", "lthumb"]


def _replace(old: str, new: str, count: int = 1) -> str:
    assert old in TEXT
    return TEXT.replace(old, new, count)


def _line_of(text: str, fragment: str) -> int:
    return next(i for i, l in enumerate(text.splitlines(), 1) if fragment in l)


@pytest.mark.parametrize("old,new,fragment,word", [
    ("    lfemur ltibia", "    lfemur lshin", "lfemur lshin", "lshin"),          # missing bone
    ("    dof rx ry rz\r\n    limits (-160.0 20.0)", "    dof rx ry rw\r\n    limits (-160.0 20.0)",
     "dof rx ry rw", "rw"),                                                     # unknown dof
    ("direction 0.34202 -0.939693 0  ", "direction 0.34202 -0.93x9693 0  ",
     "-0.93x9693", "0.93x9693"),                                               # non-number
    ("length 7.1578", "length nan", "length nan", "nan"),                      # NaN
    ("axis 0 0 20  XYZ", "axis 0 0  XYZ", "axis 0 0  XYZ", "axis"),            # wrong count
    ("    limits (-160.0 20.0)", "    limits (-160.0 20.0 5)", "(-160.0 20.0 5)", "limits"),
])
def test_malformed_names_file_and_line(tmp_path, old, new, fragment, word):
    bad = _replace(old, new)
    p = tmp_path / "bad.asf"
    p.write_bytes(bad.encode())
    with pytest.raises(MocapFormatError) as e:
        read_asf(p)
    line = _line_of(bad, fragment)
    assert e.value.path == str(p) and e.value.line == line
    assert f"bad.asf, line {line}" in str(e.value) and word in str(e.value)
    assert isinstance(e.value, ValueError)


def test_bone_missing_from_hierarchy():
    bad = _replace("    lhand lfingers\r\n", "")
    with pytest.raises(MocapFormatError) as e:
        parse_asf(bad, "x.asf")
    assert "lfingers" in str(e.value) and e.value.line == _line_of(bad, "name lfingers")


def test_truncated_file():
    with pytest.raises(MocapFormatError):
        parse_asf("\r\n".join(LINES[:40]), "t.asf")


def _check(text: str) -> None:
    try:
        parse_asf(text, "fuzz.asf")
    except MocapFormatError as e:
        assert "fuzz.asf" in str(e)


_token = st.one_of(st.sampled_from(["nan", "inf", "-", "(", ")", "1e999", "XYZ", "rq", "begin",
                                    "end", ":root", "lfemur", "root", "0", "1.5", "(1 2)", ""]),
                   st.text(max_size=8))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(i=st.integers(0, len(LINES) - 1), op=st.sampled_from(MUTATIONS), tok=_token, j=st.integers(0, 7))
def test_fuzz_mutated_lines(i, op, tok, j):
    _check(mutate(LINES, i, op, tok, j))


@settings(max_examples=100, deadline=None)
@given(st.text(max_size=300))
def test_fuzz_random_text(text):
    _check(text)


def test_data_readme_keeps_cmu_attribution():
    text = (ASF.parent / "README.md").read_text()
    assert ('"The data used in this project was obtained from mocap.cs.cmu.edu. The database was '
            'created with funding from NSF EIA-0196217."') in text
