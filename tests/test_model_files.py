"""Corrupt and foreign model files: every one refused before a model is built, with a message
naming the field, what was found and what was expected; save-load-save gives the same bytes."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest

import sysid
from sysid.errors import DataError
from sysid.models.serialize import VERSION


def _ss() -> dict:
    m = sysid.StateSpaceModel([[0.5, 0.1], [0.0, 0.3]], [[1.0], [0.5]], [[1.0, 0.0]],
                              K=[[0.2], [0.1]], dt=0.1, noise_cov=[[0.01]])
    return json.loads(json.dumps(sysid.model_to_dict(m)))


def _set(path: str, value):
    def mutate(d):
        *head, last = path.split("/")
        for k in head:
            d = d[int(k)] if isinstance(d, list) else d[k]
        d[last] = value
    return mutate


def _drop(key: str):
    def mutate(d):
        del d[key]
    return mutate


def _arr(values, shape, **extra):
    return {"__ndarray__": values, "dtype": "float64", "shape": shape, **extra}


# (name, mutation of a valid state-space file, expected message as a regex)
JSON_CASES = [
    ("no format", _drop("format"), r"field 'format': found None, expected 'sysid-model'"),
    ("other format", _set("format", "matlab-idss"), r"field 'format': found 'matlab-idss'"),
    ("no version", _drop("version"), r"field 'version': found None, expected an integer 1\.\.2"),
    ("string version", _set("version", "2"), r"field 'version': found '2', expected an integer"),
    ("bool version", _set("version", True), r"field 'version': found True"),
    ("zero version", _set("version", 0), r"field 'version': found 0, expected an integer 1"),
    ("future version", _set("version", VERSION + 1),
     rf"field 'version': found {VERSION + 1}, expected at most {VERSION} .*upgrade sysid"),
    ("no family", _drop("family"), r"field 'family': found None, expected the name"),
    ("numeric family", _set("family", 3), r"field 'family': found 3"),
    ("unknown family", _set("family", "Nope"), r"unknown model family 'Nope'"),
    ("no nstates", _drop("nstates"), r"field 'nstates': found None, expected a non-negative"),
    ("negative nstates", _set("nstates", -1), r"field 'nstates': found -1"),
    ("float ninputs", _set("ninputs", 1.5), r"field 'ninputs': found 1\.5"),
    ("string noutputs", _set("noutputs", "1"), r"field 'noutputs': found '1'"),
    ("nstates disagrees with A", _set("nstates", 3),
     r"field 'A': found 'shape \(2, 2\)', expected shape \(3, 3\)"),
    ("no A", _drop("A"), r"field 'A' is missing \(expected A of a model with nstates=2"),
    ("A a string", _set("A", "eye(2)"), r"field 'A': found 'a str'"),
    ("A with a string entry", _set("A", _arr([[0.5, "x"], [0.0, 0.3]], [2, 2])),
     r"field 'A': found 'x', expected numbers only"),
    ("A with NaN", _set("A", _arr([[0.5, float("nan")], [0.0, 0.3]], [2, 2])),
     r"field 'A': found 'NaN or infinite entries', expected finite numbers"),
    ("A too few values", _set("A", _arr([0.5, 0.1, 0.0], [2, 2])),
     r"field 'A': found '3 values', expected 4 \(shape \[2, 2\]\)"),
    ("A negative shape", _set("A", _arr([], [-1, 2])),
     r"field 'A.shape': found \[-1, 2\], expected a list of non-negative integers"),
    ("A unknown dtype", _set("A", {**_arr([[1.0]], [1, 1]), "dtype": "object"}),
     r"field 'A.dtype': found 'object'"),
    ("A complex", _set("A", _arr([[0.5, 0.1], [0.0, 0.3]], [2, 2], imag=[[0, 0], [0, 0]])),
     r"field 'A': found 'complex or boolean values', expected real numbers"),
    ("B wrong shape", _set("B", _arr([1.0, 0.5], [1, 2])),
     r"field 'B': found 'shape \(1, 2\)', expected shape \(2, 1\)"),
    ("C infinite", _set("C", _arr([1e400, 0.0], [1, 2])), r"field 'C': found 'NaN or infinite"),
    ("K wrong shape", _set("K", _arr([0.2, 0.1], [1, 2])), r"field 'K': found 'shape \(1, 2\)'"),
    ("noise_cov wrong shape", _set("noise_cov", _arr([0.01, 0, 0, 0.01], [2, 2])),
     r"field 'noise_cov': found 'shape \(2, 2\)', expected shape \(1, 1\)"),
    ("negative dt", _set("dt", -0.1), r"field 'dt': found -0\.1, expected a finite number > 0"),
    ("zero dt", _set("dt", 0.0), r"field 'dt': found 0\.0"),
    ("string dt", _set("dt", "0.1"), r"field 'dt': found '0\.1'"),
    ("missing dt", _drop("dt"), r"field 'dt': found None"),
    ("too many input names", _set("input_names", ["u0", "u1"]),
     r"field 'input_names': found '2 names', expected 1 \(one per channel\)"),
    ("numeric output name", _set("output_names", [3]),
     r"field 'output_names': found \[3\], expected a list of 1 strings"),
    ("info a list", _set("info", [1, 2]), r"field 'info': found 'a list', expected a dict"),
    ("malformed array in info", _set("info", {"Q": _arr([1.0, 2.0, 3.0], [2, 2])}),
     r"field 'info.Q': found '3 values', expected 4 \(shape \[2, 2\]\)"),
    ("string in an info array", _set("info", {"sv": [_arr(["a"], [1])]}),
     r"field 'info.sv\[0\]': found 'a', expected numbers only"),
]


@pytest.mark.parametrize("name,mutate,expected", JSON_CASES, ids=[c[0] for c in JSON_CASES])
def test_corrupt_json_model_file(tmp_path, name, mutate, expected):
    d = _ss()
    mutate(d)
    path = tmp_path / "m.json"
    path.write_text(json.dumps(d))
    with pytest.raises(DataError, match=expected) as info:
        sysid.load_model(path)
    assert str(info.value).startswith("not a sysid model file") or "unknown model" in str(
        info.value)


def _npz(tmp_path, meta: dict | None, arrays: dict) -> str:
    path = tmp_path / "m.npz"
    payload = dict(arrays)
    if meta is not None:
        payload["__meta__"] = np.array(json.dumps(meta))
    np.savez(path, **payload)
    return str(path)


def _split_npz():
    d = _ss()
    arrays = {k: np.asarray(v["__ndarray__"], float).reshape(v["shape"]) for k, v in d.items()
              if isinstance(v, dict) and "__ndarray__" in v}
    meta = {k: v for k, v in d.items() if k not in arrays}
    return meta, arrays


def _npz_case(change):
    def build(tmp_path):
        meta, arrays = _split_npz()
        change(meta, arrays)
        return _npz(tmp_path, meta, arrays)
    return build


NPZ_CASES = [
    ("no A", _npz_case(lambda m, a: a.pop("A")), r"field 'A' is missing"),
    ("A wrong shape", _npz_case(lambda m, a: a.update(A=np.eye(3))),
     r"field 'A': found 'shape \(3, 3\)', expected shape \(2, 2\)"),
    ("A with NaN", _npz_case(lambda m, a: a.update(A=np.full((2, 2), np.nan))),
     r"field 'A': found 'NaN or infinite entries'"),
    ("A of strings", _npz_case(lambda m, a: a.update(A=np.array([["a", "b"], ["c", "d"]]))),
     r"field 'A': found 'dtype <U1', expected real numbers"),
    ("future version", _npz_case(lambda m, a: m.update(version=VERSION + 5)),
     rf"found {VERSION + 5}, expected at most {VERSION}"),
    ("negative dt", _npz_case(lambda m, a: m.update(dt=-1.0)), r"field 'dt': found -1\.0"),
    ("nstates disagrees", _npz_case(lambda m, a: m.update(nstates=1)),
     r"field 'A': found 'shape \(2, 2\)', expected shape \(1, 1\)"),
]


@pytest.mark.parametrize("name,build,expected", NPZ_CASES, ids=[c[0] for c in NPZ_CASES])
def test_corrupt_npz_model_file(tmp_path, name, build, expected):
    with pytest.raises(DataError, match=expected):
        sysid.load_model(build(tmp_path))


def test_npz_without_metadata_or_not_a_zip(tmp_path):
    path = tmp_path / "m.npz"
    np.savez(path, A=np.eye(2))
    with pytest.raises(DataError, match="no metadata"):
        sysid.load_model(path)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("__meta__.npy", b"garbage")
    path.write_bytes(buf.getvalue())
    with pytest.raises(DataError, match="not a sysid model file"):
        sysid.load_model(path)


def test_at_least_thirty_corrupt_files():
    assert len(JSON_CASES) + len(NPZ_CASES) + 2 >= 30


def test_nothing_is_built_from_a_refused_file(tmp_path, monkeypatch):
    """The schema runs before from_dict: a refused file never reaches the model's constructor."""
    called = []
    monkeypatch.setattr(sysid.StateSpaceModel, "from_dict",
                        classmethod(lambda cls, d: called.append(d)))
    d = _ss()
    d["A"] = _arr([[0.5, "x"], [0.0, 0.3]], [2, 2])
    path = tmp_path / "m.json"
    path.write_text(json.dumps(d))
    with pytest.raises(DataError):
        sysid.load_model(path)
    assert not called


def _models():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((300, 1))
    ss = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1,
                               info={"Q": np.eye(2), "sv": [np.arange(3.0)], "z": 1 + 2j})
    y = ss.simulate(u)
    data = sysid.IOData(u=u, y=y + 0.01 * rng.standard_normal(y.shape))
    return {
        "ss": ss,
        "continuous": sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]),
        "polynomial": sysid.arx(data, [[2]], [[2]], [[1]]),
        "narx": sysid.nlarx(data, 1, 1, 1),
    }


@pytest.mark.parametrize("fmt", ["json", "npz"])
@pytest.mark.parametrize("kind", ["ss", "continuous", "polynomial", "narx"])
def test_save_load_save_gives_the_same_bytes(tmp_path, kind, fmt):
    m = _models()[kind]
    a, b = tmp_path / f"a.{fmt}", tmp_path / f"b.{fmt}"
    sysid.save_model(m, a)
    sysid.save_model(sysid.load_model(a), b)
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("fmt", ["json", "npz"])
def test_saving_is_atomic(tmp_path, monkeypatch, fmt):
    """A failure while writing (here: half the archive written, then an error) leaves the
    previous file untouched and no temporary file behind."""
    import sysid.models.serialize as ser

    path = tmp_path / f"m.{fmt}"
    sysid.save_model(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), path)
    before = path.read_bytes()

    def half_then_fail(f, *a, **k):
        f.write(b"PK\x03\x04 half written")
        raise OSError("disk full")

    real_replace = ser.os.replace
    monkeypatch.setattr(ser.np, "savez", half_then_fail)
    monkeypatch.setattr(ser.os, "replace",
                        lambda *a: (_ for _ in ()).throw(OSError("disk full")))
    with pytest.raises(OSError, match="disk full"):
        sysid.save_model(sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]]), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [path.name]
    assert real_replace is not ser.os.replace


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_identify_model_saves_and_loads_predicting_raw_data(tmp_path, suffix):
    # the model of sysid.identify (offsets kept with it) could not be saved: "IdentifiedModel
    # cannot be saved: it has no to_dict()" (issue 26)
    import warnings

    rng = np.random.default_rng(0)
    u = 3.0 + rng.standard_normal(400)
    true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]])
    y = 10.0 + true.simulate(u - 3.0) + 0.01 * rng.standard_normal((400, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(sysid.IOData(u=u, y=y), refine=False)
    path = tmp_path / f"identified{suffix}"
    sysid.save_model(res.model, path)
    back = sysid.load_model(path)
    assert type(back).__name__ == "IdentifiedModel"
    np.testing.assert_allclose(back.simulate(u), res.model.simulate(u), atol=1e-12)
    np.testing.assert_allclose(back.y_offset, res.model.y_offset)
    assert back.info["identify"]["order"] == res.model.nstates
