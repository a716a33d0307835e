"""``IOData.resampling`` (what ``resample=`` / ``from_irregular`` did) survives ``to_npz`` and
``to_mat``; a CSV file has no place for it; ``==`` compares samples, not how they were had."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _resampled(method: str = "linear") -> sysid.IOData:
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.08, 0.12, 60))
    u = np.sin(t)
    y = np.c_[np.cos(t), 0.5 * t]
    return sysid.IOData.from_irregular(t, u, y, dt=0.1, method=method, input_units=["V"],
                                       output_units=["m", "s"])


@pytest.mark.parametrize("method", ["linear", "cubic"])
def test_npz_keeps_the_resampling(tmp_path, method):
    rec = _resampled(method)
    assert rec.resampling is not None and rec.resampling.method == method
    rec.to_npz(tmp_path / "r.npz")
    back = sysid.IOData.from_npz(tmp_path / "r.npz")
    assert back == rec
    assert back.resampling == rec.resampling  # every field, the method's name too
    assert back.output_units == rec.output_units


def test_mat_keeps_the_resampling(tmp_path):
    pytest.importorskip("scipy.io")
    rec = _resampled()
    rec.to_mat(tmp_path / "r.mat")
    back = sysid.IOData.from_mat(tmp_path / "r.mat")
    assert back == rec and back.resampling == rec.resampling


def test_several_experiments_keep_the_resampling(tmp_path):
    path = tmp_path / "two.csv"
    rng = np.random.default_rng(4)
    rows = ["time,experiment,u,y"]
    for k in range(2):
        t = np.cumsum(rng.uniform(0.09, 0.11, 40))
        rows += [f"{a:.17g},{k},{np.sin(a):.17g},{np.cos(a):.17g}" for a in t]
    path.write_text("\n".join(rows) + "\n")
    rec = sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"], resample=0.1)
    assert rec.n_experiments == 2 and rec.resampling is not None
    rec.to_npz(tmp_path / "two.npz")
    back = sysid.IOData.from_npz(tmp_path / "two.npz")
    assert back == rec and back.resampling == rec.resampling


@pytest.mark.parametrize("fmt", ["npz", "mat"])
def test_a_record_as_sampled_reads_back_unresampled(tmp_path, fmt):
    rec = sysid.IOData(u=np.arange(5.0), y=np.ones(5), dt=0.5)
    path = tmp_path / f"p.{fmt}"
    getattr(rec, f"to_{fmt}")(path)
    back = getattr(sysid.IOData, f"from_{fmt}")(path)
    assert back == rec and back.resampling is None


def test_csv_has_no_place_for_it_and_reads_back_equal(tmp_path):
    rec = _resampled()
    rec.to_csv(tmp_path / "r.csv")
    back = sysid.IOData.from_csv(tmp_path / "r.csv", inputs=["u0"], outputs=["y0", "y1"])
    assert back.resampling is None
    np.testing.assert_allclose(back.y, rec.y, rtol=0, atol=0)
    assert back.dt == rec.dt and back.output_units == rec.output_units


def test_equality_compares_samples_not_how_they_were_had():
    rec = _resampled()
    plain = sysid.IOData(u=rec.u, y=rec.y, dt=rec.dt)
    assert plain.resampling is None and rec.resampling is not None
    assert plain == rec


def test_a_malformed_note_is_refused(tmp_path):
    rec = _resampled()
    rec.to_npz(tmp_path / "r.npz")
    with np.load(tmp_path / "r.npz") as z:
        arrays = dict(z)
    arrays["resampling"] = arrays["resampling"][:3]
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(DataError, match="resampling is malformed"):
        sysid.IOData.from_npz(tmp_path / "bad.npz")
