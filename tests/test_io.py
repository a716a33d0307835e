"""Saving and loading models."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import sysid
import sysid.models.io


def full_model() -> sysid.StateSpaceModel:
    rng = np.random.default_rng(0)
    n, m, l = 3, 2, 2
    return sysid.StateSpaceModel(
        rng.standard_normal((n, n)) * 0.3, rng.standard_normal((n, m)),
        rng.standard_normal((l, n)), rng.standard_normal((l, m)), rng.standard_normal((n, l)),
        dt=0.004, noise_cov=np.eye(l) * 0.1 + 0.01, x0=rng.standard_normal(n),
        input_names=["elevator", "aileron"], output_names=["pitch", "roll"],
        info={
            "method": "moesp", "order": 3, "singular_values": rng.random(6),
            "Q": rng.standard_normal((n, n)), "poles": np.array([0.5 + 0.1j, 0.5 - 0.1j]),
            "units": {"inputs": ["deg", "deg"], "outputs": ["rad", "rad"]},
            "preprocessing": {"detrend": "mean", "removed_means": [0.1, -0.2],
                              "samples": [0, 500]},
            "settings": {"horizon": 15, "stable": False, "missing": None},
            "nan_value": float("nan"), "count": np.int64(3),
        },
    )


def assert_same(a: sysid.StateSpaceModel, b: sysid.StateSpaceModel) -> None:
    for k in ("A", "B", "C", "D", "K", "noise_cov", "x0"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))
    assert a.dt == b.dt
    assert a.input_names == b.input_names and a.output_names == b.output_names
    assert b.info["units"] == a.info["units"]
    assert b.info["preprocessing"] == a.info["preprocessing"]
    assert b.info["settings"] == a.info["settings"]
    np.testing.assert_array_equal(b.info["singular_values"], a.info["singular_values"])
    np.testing.assert_array_equal(b.info["Q"], a.info["Q"])
    np.testing.assert_array_equal(b.info["poles"], a.info["poles"])
    assert np.isnan(b.info["nan_value"]) and b.info["count"] == 3


@pytest.mark.parametrize("ext", ["json", "npz"])
def test_round_trip_is_exact(tmp_path, ext):
    m = full_model()
    path = tmp_path / f"model.{ext}"
    sysid.save_model(m, path)
    back = sysid.load_model(path)
    assert_same(m, back)
    u = np.random.default_rng(1).standard_normal((50, 2))
    np.testing.assert_array_equal(back.simulate(u), m.simulate(u))


def test_json_is_readable_and_tagged(tmp_path):
    path = tmp_path / "m.json"
    sysid.save_model(full_model(), path)
    d = json.loads(path.read_text())
    assert d["format"] == "sysid-model" and d["version"] == 2 and d["dt"] == 0.004
    assert d["family"] == "StateSpaceModel"
    assert d["input_names"] == ["elevator", "aileron"]


def test_model_without_optional_parts(tmp_path):
    m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
    for ext in ("json", "npz"):
        back = sysid.load_model(_save(m, tmp_path / f"m.{ext}"))
        assert back.K is None and back.x0 is None and back.noise_cov is None
        assert back.info == {}


def _save(m, path):
    sysid.save_model(m, path)
    return path


def test_format_override(tmp_path):
    path = tmp_path / "model.dat"
    sysid.save_model(full_model(), path, format="npz")
    assert_same(full_model(), sysid.load_model(path, format="npz"))


def test_bad_files(tmp_path):
    with pytest.raises(sysid.DataError, match="json"):
        sysid.save_model(full_model(), tmp_path / "m.txt")
    with pytest.raises(FileNotFoundError):
        sysid.load_model(tmp_path / "missing.json")
    (tmp_path / "junk.json").write_text("{not json")
    with pytest.raises(sysid.DataError, match="not valid JSON"):
        sysid.load_model(tmp_path / "junk.json")
    (tmp_path / "other.json").write_text('{"format": "something else"}')
    with pytest.raises(sysid.DataError, match="not a sysid model"):
        sysid.load_model(tmp_path / "other.json")
    np.savez(tmp_path / "plain.npz", A=np.eye(2))
    with pytest.raises(sysid.DataError, match="not a sysid model"):
        sysid.load_model(tmp_path / "plain.npz")
    with pytest.raises(sysid.DataError, match="StateSpaceModel"):
        sysid.save_model(np.eye(2), tmp_path / "m.json")
    d = sysid.models.io.model_to_dict(full_model())
    d["version"] = 99
    with pytest.raises(sysid.DataError, match="newer"):
        sysid.models.io.model_from_dict(d)


@pytest.mark.parametrize("ext", ["json", "npz"])
def test_every_wrapper_model_saves_and_loads(tmp_path, ext):
    """Models that wrap another (a trend, offsets, basis functions, a NARX model's state
    form) had no to_dict: ``TrendedModel`` (what ``Trend.attach`` gives, MATLAB's retrend),
    ``AugmentedInputModel`` and ``NARXStateSpace`` raised "cannot be saved", and
    ``identify``'s model had no ``.save``. Each now round-trips exactly, the inner model's
    parameter uncertainty with it."""
    rng = np.random.default_rng(3)
    u = rng.standard_normal(500)
    y = np.convolve(u, [0.0, 0.5, 0.3], "full")[:500] + 0.01 * rng.standard_normal(500)
    raw = sysid.IOData(u=2.0 + u, y=7.0 + y + 0.002 * np.arange(500), dt=0.1)
    d, tr = sysid.detrend(raw, "linear", return_trend=True)
    inner = [sysid.oe(d, 2, 2, 1), sysid.ssest(d, 2, focus="simulation")]
    lin = sysid.StateSpaceModel([[0.5]], [[1.0, 0.5]], [[1.0]])
    narx = sysid.NARXModel([1], [1], [1], sysid.PolynomialBasis(2), [[[0], [1], [1, 1]]],
                           [[0.5, 1.0, -0.2]], dt=1.0)
    ident = sysid.identify(raw, progress=False).model
    models = [tr.attach(m) for m in inner] + [
        sysid.AugmentedInputModel(lin, ["tanh"], 1), narx.to_nlss(), ident]
    for k, m in enumerate(models):
        path = tmp_path / f"m{k}.{ext}"
        m.save(path)
        back = sysid.load_model(path)
        assert type(back) is type(m)
        np.testing.assert_array_equal(back.simulate(raw.u), m.simulate(raw.u))
        if getattr(m, "poles", None) and type(m).__name__ != "NARXStateSpace":
            with warnings.catch_warnings():  # poles that coincide: the Monte Carlo value
                warnings.simplefilter("ignore", sysid.UncertaintyWarning)
                try:
                    _, sd = m.poles(std=True)
                except sysid.DataError:  # no uncertainty to carry
                    continue
                np.testing.assert_allclose(back.poles(std=True)[1], sd, rtol=1e-9)
    # a loaded trend applies to other data; the fitted record's own values are not kept
    back = sysid.load_model(tmp_path / f"m0.{ext}").trend
    np.testing.assert_allclose(back.apply(raw).y, tr.apply(raw).y)
    with pytest.raises(sysid.DataError, match="no per-sample values"):
        back.add_outputs(np.zeros((3, 1)))


def test_a_model_with_callable_basis_functions_is_refused_by_name(tmp_path):
    lin = sysid.StateSpaceModel([[0.5]], [[1.0, 0.5]], [[1.0]])
    m = sysid.AugmentedInputModel(lin, [np.sin], 1)
    with pytest.raises(sysid.DataError, match="callables .*sin.*model.linear.save"):
        m.save(tmp_path / "m.json")
