"""``sysid identify --detrend linear`` saves a model that predicts the raw signals: the lines
taken out of the estimation part are its trend (a ``TrendedModel``), as the means of
``--detrend mean`` are its offsets. The model file held the model of the detrended record
alone: on a record with a trend of 0.01 per sample from 50 it simulated about 0.8 where the
output is 57.5, a fit of -2615 % on the raw validation part."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid import cli
from sysid.models.trended import TrendedModel

PLANT = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])


def _drifting(path, t0: float = 0.0) -> sysid.IOData:
    """The auditor's record: offsets 2 and 50, an output trend of 0.01 per sample, dt 0.1."""
    rng = np.random.default_rng(11)
    n = 1000
    u = rng.standard_normal(n) + 2.0
    y = (PLANT.simulate(u - 2.0)[:, 0] + 50.0 + 0.01 * np.arange(n)
         + 0.05 * rng.standard_normal(n))
    np.savetxt(path, np.c_[t0 + np.arange(n) * 0.1, u, y], delimiter=",",
               header="time,u,y", comments="", fmt="%.10g")
    return sysid.IOData.from_csv(path, inputs=["u"], outputs=["y"])


def _fit(model, data) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return float(sysid.compare(model, data).mean_fit)


@pytest.mark.parametrize("extra", [[], ["--method", "moesp"]])
def test_the_saved_model_predicts_the_raw_record(tmp_path, extra):
    raw = _drifting(tmp_path / "tr.csv")
    out = tmp_path / "rep"
    assert cli.main(["identify", str(tmp_path / "tr.csv"), "--inputs", "u", "--outputs", "y",
                     "--detrend", "linear", "--quiet", "--report", str(out), *extra]) == 0
    model = sysid.load_model(out / "model.json")  # saved and loaded
    assert isinstance(model, TrendedModel)
    assert "removed_lines" in model.info["preprocessing"]
    # the raw record, whole and its validation part (the line continues there)
    assert _fit(model, raw) > 95.0
    assert _fit(model, raw.slice(500, 1000)) > 90.0
    sim = model.simulate(raw.u)
    assert abs(sim.mean() - raw.y.mean()) < 0.2  # raw units: about 55, not about 0
    assert abs(sim[-100:].mean() - raw.y[-100:].mean()) < 0.5  # the trend is in it


def test_the_trend_is_on_the_clock_of_the_time_column(tmp_path):
    # a record whose time column starts at 100 s: read back with IOData.from_csv (its start
    # time 100 s), the saved model evaluates its line from there, not from 0
    raw = _drifting(tmp_path / "tr.csv", t0=100.0)
    out = tmp_path / "rep"
    assert cli.main(["identify", str(tmp_path / "tr.csv"), "--inputs", "u", "--outputs", "y",
                     "--detrend", "linear", "--quiet", "--report", str(out)]) == 0
    model = sysid.load_model(out / "model.json")
    assert model.trend.t0 == pytest.approx(100.0)
    assert _fit(model, raw) > 95.0 and _fit(model, raw.slice(500, 1000)) > 90.0


def test_detrend_mean_still_saves_the_means_as_offsets(tmp_path):
    rng = np.random.default_rng(3)
    u = rng.standard_normal(600) + 2.0
    y = PLANT.simulate(u - 2.0)[:, 0] + 50.0 + 0.05 * rng.standard_normal(600)
    np.savetxt(tmp_path / "d.csv", np.c_[np.arange(600) * 0.1, u, y], delimiter=",",
               header="time,u,y", comments="")
    out = tmp_path / "rep"
    assert cli.main(["identify", str(tmp_path / "d.csv"), "--inputs", "u", "--outputs", "y",
                     "--detrend", "mean", "--quiet", "--report", str(out)]) == 0
    model = sysid.load_model(out / "model.json")
    assert not isinstance(model, TrendedModel)
    assert _fit(model, sysid.IOData(u=u, y=y, dt=0.1)) > 90.0
