"""Fuzzing as tests (issue 29): problem files, motion files, result folders and cached models,
damaged at random. Only a LatentocError may escape (the CLI: exit 2 and `latentoc: error`), and a
failed command writes nothing; a damaged cached model is learned again, never raised."""
import copy
import io
import json
import uuid

import numpy as np
import pytest
from fake_solver import install, solution
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from result_factory import make_result

import latentoc
from latentoc.cli.parser import main
from latentoc.errors import ResultFileError
from latentoc.problem.toml_files import problems_dir

FUZZ = settings(max_examples=60, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
SMALL = (problems_dir() / "arm-raise-small.toml").read_text()
KEYS = ["name", "kind", "robot", "training", "duration", "dim", "control_points", "spline_degree", "boundary", "tube",
        "quadrature_points", "constraint_points", "joint_limits", "hessian", "max_iter", "tol", "training_stride",
        "joint_range_deg", "tubes", "ranges", "frame"]
TOML_VALUES = st.one_of(
    st.integers(-10**12, 10**12).map(str), st.floats(allow_nan=True, allow_infinity=True).map(
        lambda f: {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(f), repr(f))),
    st.text(max_size=12).map(json.dumps), st.sampled_from(["true", "false", "[]", "{}", '"5x"', '"-1x"', '"1e308x"',
                                                           '["1x", 2]', '{ urdf = "x.urdf" }', '{ file = "m.csv" }',
                                                           '"../x"', '"human-arm"', "1e308", "0", "-0.0"]))


def _mutated_problem(data: st.DataObject) -> bytes:
    """arm-raise-small.toml with a key's value replaced, a line dropped, or bytes spliced in."""
    lines = SMALL.splitlines()
    op = data.draw(st.sampled_from(["value", "value", "drop", "bytes", "truncate"]))
    if op == "value":
        key = data.draw(st.sampled_from(KEYS))
        i = next((k for k, line in enumerate(lines) if line.split("=")[0].strip() == key), None)
        new = f"{key} = {data.draw(TOML_VALUES)}"
        lines = lines[:i] + [new] + lines[i + 1:] if i is not None else [new] + lines
        return "\n".join(lines).encode()
    if op == "drop":
        del lines[data.draw(st.integers(0, len(lines) - 1))]
        return "\n".join(lines).encode()
    raw = SMALL.encode()
    at = data.draw(st.integers(0, len(raw)))
    if op == "truncate":
        return raw[:at]
    return raw[:at] + data.draw(st.binary(min_size=1, max_size=8)) + raw[at:]


@FUZZ
@given(data=st.data())
def test_fuzzed_problem_files(tmp_path, capsys, monkeypatch, data):
    """`solve FILE` (the solver stood in for): exit 0 and a result folder, or exit 2 naming the file
    and no folder."""
    install(monkeypatch, lambda p, w: solution(p.replace(tube=0.5), 700.0))
    path = tmp_path / f"{uuid.uuid4().hex}.toml"
    path.write_bytes(_mutated_problem(data))
    out = tmp_path / uuid.uuid4().hex
    code = main(["solve", str(path), "--quiet", "--out", str(out)])
    err = capsys.readouterr().err
    if code == 2:
        assert err.startswith("latentoc: error: ") and not out.exists()
        assert str(path) in err or "problem '" in err, err
    else:
        assert code == 0 and (out / "result.json").is_file(), err


NPZ_ARRAYS = st.dictionaries(
    st.sampled_from(["t", "q", "joint_names", "x"]),
    st.one_of(st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=12).map(np.array),
              st.integers(0, 4).flatmap(lambda n: st.lists(st.lists(st.floats(-3, 3), min_size=n, max_size=n),
                                                           max_size=8)).map(np.array),
              st.lists(st.sampled_from(["lhumerus_rz", "lhumerus_ry", "lradius_rx", "nope", ""]), max_size=4)
              .map(np.array), st.just(np.array([1, 2], dtype=object)), st.just(np.zeros((2, 2, 2)))),
    max_size=4)


@FUZZ
@given(arrays=NPZ_ARRAYS, cut=st.integers(0, 400), junk=st.binary(max_size=30))
def test_fuzzed_motion_npz_files(tmp_path, capsys, monkeypatch, arrays, cut, junk):
    """An NPZ motion of random arrays, truncated, or replaced by bytes: `learn` reads it on the arm
    or exits 2 naming the file, writing nothing (learning itself is stood in for)."""
    import latentoc.cli.learn as learn

    class Accepted(Exception):
        pass

    def accepted(*args, **kwargs):
        raise Accepted

    monkeypatch.setattr(learn, "learn_motion", accepted)
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    for content in (buffer.getvalue(), buffer.getvalue()[:cut], junk):
        path = tmp_path / f"{uuid.uuid4().hex}.npz"
        path.write_bytes(content)
        out = tmp_path / uuid.uuid4().hex
        try:
            code = main(["learn", str(path), "--robot", "human-arm", "--latent-dim", "1", "--out", str(out)])
        except Accepted:
            continue
        err = capsys.readouterr().err
        assert code == 2 and err.startswith("latentoc: error: ") and str(path) in err and not out.exists(), err


JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=6),
                    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3),
                    max_leaves=6)
RESULT_KEYS = ["problem", "kind", "method", "status", "success", "iterations", "cost_initial", "cost", "gain_pct",
               "cost_meaning", "times", "tube", "violations", "environment", "settings", "details", "convergence",
               "checksums", "schema_version"]


@pytest.fixture(scope="module")
def folder_files(tmp_path_factory):
    """A result folder's files (with a GPDM), to damage."""
    from latentoc.gpdm import GPDMSettings, learn_gpdm

    Y = np.cumsum(np.random.default_rng(0).standard_normal((10, 3)), axis=0)
    d = tmp_path_factory.mktemp("result")
    make_result(gpdm=learn_gpdm(Y, GPDMSettings(latent_dim=2, max_iterations=2))).save(d)
    return {p.name: p.read_bytes() for p in d.iterdir()}


@FUZZ
@given(data=st.data())
def test_fuzzed_result_folders(tmp_path, folder_files, data):
    """A result folder with a field set to random JSON, a field dropped, or a file truncated or
    flipped: load_result gives a Result whose core fields have their types, or a ResultFileError;
    it writes nothing."""
    files = dict(folder_files)
    op = data.draw(st.sampled_from(["set", "drop", "truncate", "flip", "remove"]))
    if op in ("set", "drop"):
        content = json.loads(files["result.json"])
        key = data.draw(st.sampled_from(RESULT_KEYS))
        if op == "set":
            content[key] = data.draw(JSON)
        else:
            content.pop(key, None)
        files["result.json"] = json.dumps(content).encode()
    else:
        name = data.draw(st.sampled_from(sorted(files)))
        raw = files[name]
        at = data.draw(st.integers(0, len(raw) - 1))
        if op == "truncate":
            files[name] = raw[:at]
        elif op == "flip":
            files[name] = raw[:at] + bytes([raw[at] ^ data.draw(st.integers(1, 255))]) + raw[at + 1:]
        else:
            del files[name]
    d = tmp_path / uuid.uuid4().hex
    d.mkdir()
    for name, content in files.items():
        (d / name).write_bytes(content)
    try:
        r = latentoc.load_result(d)
    except ResultFileError as exc:
        assert str(d) in str(exc)
    else:
        assert isinstance(r.cost, float) and isinstance(r.success, bool) and isinstance(r.iterations, int)
        assert isinstance(r.problem, str) and isinstance(r.details, dict)
        assert np.array_equal(r.trajectory["q"], make_result().trajectory["q"])
    assert sorted(p.name for p in d.iterdir()) == sorted(files)


@pytest.fixture(scope="module")
def learned():
    from latentoc.benchmarks.gpdm_bench import synthetic_motion
    from latentoc.gpdm import GPDMSettings, learn_gpdm

    Y, settings = synthetic_motion(16, 4, seed=2, noise=0.05), GPDMSettings(latent_dim=2)
    return Y, settings, learn_gpdm(Y, settings)


@FUZZ
@given(cut=st.integers(0, 10**6), flips=st.lists(st.tuples(st.integers(0, 10**6), st.integers(1, 255)), max_size=3),
       junk=st.binary(max_size=64), op=st.sampled_from(["truncate", "flip", "junk", "foreign"]),
       side=st.sampled_from(["keep", "drop", "junk"]))
def test_fuzzed_cached_models_are_learned_again(tmp_path, capsys, monkeypatch, learned, cut, flips, junk, op, side):
    """A cached gpdm_*.npz truncated, flipped, replaced by bytes or by another model, with its
    checksum kept, dropped or damaged: cached_gpdm returns the model of the data (learning stood
    in for by the known model) with at most one warning line, never an exception."""
    import latentoc.gpdm.cache as cache

    Y, settings, model = learned
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path / uuid.uuid4().hex))
    monkeypatch.setattr(cache, "learn_gpdm", lambda y, s: model)
    path = cache.model_path(Y, settings)
    cache.cached_gpdm(Y, settings)
    raw = bytearray(path.read_bytes())
    if op == "truncate":
        raw = raw[:cut % len(raw)]
    elif op == "flip":
        for at, bit in flips:
            raw[at % len(raw)] ^= bit
    elif op == "junk":
        raw = bytearray(junk)
    else:  # a valid model of other data
        foreign = copy.copy(model)
        foreign.Y = model.Y + 1.0
        foreign.save(tmp_path / "foreign.npz")
        raw = bytearray((tmp_path / "foreign.npz").read_bytes())
    path.write_bytes(bytes(raw))
    checksum = path.with_name(path.name + ".sha256")
    if side == "drop":
        checksum.unlink()
    elif side == "junk":
        checksum.write_bytes(junk)
    capsys.readouterr()
    got = cache.cached_gpdm(Y, settings)
    assert np.array_equal(got.X, model.X) and capsys.readouterr().err.count("\n") <= 1
    assert np.array_equal(cache.cached_gpdm(Y, settings).X, model.X) and capsys.readouterr().err == ""
