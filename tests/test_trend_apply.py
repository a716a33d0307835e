"""detrend returns a trend that applies to other data (MATLAB's getTrend/retrend), and a
model that carries it predicts raw data (issue 26)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid


def _raw(n, seed, offset_u=20.0, offset_y=300.0, slope_y=0.0):
    rng = np.random.default_rng(seed)
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 dt=0.5)
    du = rng.standard_normal(n)
    t = np.arange(n) * 0.5
    y = offset_y + slope_y * t + true.simulate(du)[:, 0] + 0.05 * rng.standard_normal(n)
    return sysid.IOData(u=offset_u + du, y=y, dt=0.5)


def test_apply_removes_the_estimation_offsets_from_validation_data():
    est, val = _raw(800, 0), _raw(400, 1)
    d, tr = sysid.detrend(est, "mean", return_trend=True)
    np.testing.assert_allclose(tr.u_offset, est.u.mean(0))
    np.testing.assert_allclose(tr.y_offset, est.y.mean(0))
    assert tr.kind == "mean" and np.all(tr.y_slope == 0)
    v = tr.apply(val)
    # the estimation record's offsets, not the validation record's own mean
    np.testing.assert_allclose(v.y, val.y - est.y.mean(0), atol=1e-12)
    np.testing.assert_allclose(v.u, val.u - est.u.mean(0), atol=1e-12)
    np.testing.assert_allclose(v.retrend().y, val.y, atol=1e-12)
    np.testing.assert_allclose(tr.restore(v).u, val.u, atol=1e-12)
    assert not v.y.mean() == pytest.approx(0.0, abs=1e-9)  # not detrended on its own
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.OffsetWarning)  # applied: no offset warning
        sysid.n4sid(v, 2)


def test_linear_trend_per_second_applies_from_each_records_start():
    est = _raw(800, 0, slope_y=0.2)
    d, tr = sysid.detrend(est, "linear", return_trend=True)
    assert tr.kind == "linear" and abs(tr.y_slope[0] - 0.2) < 0.01
    assert np.abs(d.y.mean()) < 1e-9
    val = _raw(400, 1, slope_y=0.2)
    v = tr.apply(val)
    # offset + slope t removed, t from the validation record's first sample
    t = np.arange(400) * 0.5
    expect = val.y[:, 0] - tr.y_offset[0] - tr.y_slope[0] * t
    np.testing.assert_allclose(v.y[:, 0], expect, atol=1e-9)
    np.testing.assert_allclose(tr.restore_outputs(v.y), val.y, atol=1e-9)


def test_a_model_carrying_the_trend_predicts_raw_data():
    est, val = _raw(1500, 0), _raw(800, 1)
    d, tr = sysid.detrend(est, "mean", return_trend=True)
    inner = sysid.n4sid(d, 2)
    m = tr.attach(inner)
    assert isinstance(m, sysid.TrendedModel) and m.dt == 0.5 and m.ninputs == 1
    yhat = m.simulate(val.u)
    assert abs(yhat.mean() - val.y.mean()) < 0.5    # raw units: around 300
    raw = sysid.compare(m, val)
    ref = sysid.compare(inner, tr.apply(val))
    np.testing.assert_allclose(raw.fit, ref.fit, rtol=1e-9)
    assert raw.fit[0, 0] > 90
    np.testing.assert_allclose(raw.yhat[0], tr.restore_outputs(ref.yhat[0]), atol=1e-9)
    # the model fitted on raw data instead is far worse (and said so)
    with pytest.warns(sysid.OffsetWarning):
        bad = sysid.arx(est, 2, 2, 1)
    assert sysid.compare(bad, val).fit[0, 0] < raw.fit[0, 0]
    # several records: compare the raw-data model with others on raw validation data
    cs = sysid.compare(val, m, tr.attach(sysid.moesp(d, 2)))
    assert cs.fit.min() > 90


def test_piecewise_and_per_sample_trends_do_not_apply_elsewhere():
    est = _raw(200, 0)
    d, tr = sysid.detrend(est, "piecewise", breakpoints=[100], return_trend=True)
    with pytest.raises(sysid.DataError, match="return_trend"):
        tr.apply(est)
    with pytest.raises(sysid.DataError, match="return_trend"):
        sysid.detrend(est).trend.apply(est)
    _, tr2 = sysid.detrend(est, "mean", return_trend=True)
    with pytest.raises(sysid.ShapeError):
        tr2.apply(sysid.IOData(u=np.ones((10, 2)), y=np.ones(10)))


def test_linear_trend_continues_on_the_later_part_of_the_same_record():
    # split/slice keep the start time: the validation part of a drifting record is on the
    # estimation part's line, not on a line restarted at its own first sample
    raw = _raw(1200, 2, slope_y=0.2)
    parts = raw.split(0.5)
    est, val = parts.estimation, parts.validation
    d, tr = sysid.detrend(est, "linear", return_trend=True)
    v = tr.apply(val)
    t = val.time - est.time[0]
    np.testing.assert_allclose(v.y[:, 0], val.y[:, 0] - tr.y_offset[0] - tr.y_slope[0] * t,
                               atol=1e-9)
    assert abs(v.y.mean()) < 0.5 * raw.y.std()
    np.testing.assert_allclose(v.retrend().y, val.y, atol=1e-9)
    # a model carrying the trend simulates the later part in raw units around its level
    m = tr.attach(sysid.n4sid(d, 2))
    raw_fit = sysid.compare(m, val)
    inner = sysid.compare(m.model, v)
    np.testing.assert_allclose(raw_fit.yhat[0], inner.yhat[0] + (val.y - v.y), atol=1e-9)
    assert abs(raw_fit.yhat[0].mean() - val.y.mean()) < 0.5
    assert raw_fit.fit[0, 0] > 90


def test_residuals_and_criteria_of_a_trended_model_on_the_later_part_of_a_record():
    # TrendedModel.predict evaluates the trend from t = 0 and starts from rest: on the
    # validation part of a drifting record its errors were the slope times the elapsed
    # time (residuals "NOT white p=1e-39", criteria loss 46 x too large); they are the inner
    # model's on tr.apply(val), with its initial state estimated there
    raw = _raw(1500, 3, slope_y=0.2)
    parts = raw.split(2 / 3)
    est, val = parts.estimation, parts.validation
    d, tr = sysid.detrend(est, "linear", return_trend=True)
    inner = sysid.n4sid(d, 2)
    m, v = tr.attach(inner), tr.apply(val)
    r, ref = sysid.residuals(m, val), sysid.residuals(inner, v)
    np.testing.assert_allclose(r.e[0], ref.e[0], atol=1e-9)
    np.testing.assert_allclose(r.ljung_box, ref.ljung_box, rtol=1e-9)
    assert np.abs(r.e[0]).mean() < 0.1       # the noise is 0.05; the slope alone is ~0.2 t
    c, cref = sysid.criteria(m, val), sysid.criteria(inner, v)
    assert c.loss == pytest.approx(cref.loss, rel=1e-9) and c.n_params == cref.n_params
    assert c.loss < 2 * 0.05**2
    # a (u, y) pair is on the estimation record's clock from t = 0, as tr.apply of a record
    # that starts at 0
    r0 = sysid.residuals(m, (est.u, est.y))
    np.testing.assert_allclose(r0.e[0], sysid.residuals(inner, d).e[0], atol=1e-9)


def test_forecast_of_a_trended_model_continues_the_line():
    # forecast refused a TrendedModel ("fit a linear model"): it forecasts the inner model
    # on the record less the trend and adds the trend back at the forecast's instants
    raw = _raw(1500, 4, slope_y=0.2)
    parts = raw.split(2 / 3)
    est, val = parts.estimation, parts.validation
    d, tr = sysid.detrend(est, "linear", return_trend=True)
    inner = sysid.n4sid(d, 2)
    m = tr.attach(inner)
    past = val.slice(0, 300)
    fu = val.u[300:305]
    f = sysid.forecast(m, past, 5, future_inputs=fu)
    np.testing.assert_allclose(f.t, past.time[-1] + 0.5 * np.arange(1, 6), atol=1e-12)
    s = (f.t - est.time[0])[:, None]      # seconds on the estimation record's clock
    ref = sysid.forecast(inner, tr.apply(past), 5,
                         future_inputs=fu - tr.u_offset - tr.u_slope * s)
    np.testing.assert_allclose(f.mean, ref.mean + tr.y_offset + tr.y_slope * s, atol=1e-9)
    np.testing.assert_allclose(f.std, ref.std, atol=1e-12)
    np.testing.assert_allclose(f.mean, val.y[300:305], atol=0.3)   # raw units, near 400


def test_restore_of_model_outputs_takes_the_records_start():
    # a model's simulation of the second half of a drifting record, restored, came back off
    # by the drift over the first half (restore added the trend from t = 0)
    n, dt = 400, 0.5
    t = np.arange(n) * dt
    u = np.random.default_rng(0).standard_normal(n)
    est, val = sysid.IOData(u, 5.0 + 0.1 * t, dt).split(0.5)
    _, tr = sysid.detrend(est, "linear", return_trend=True)
    zero = sysid.StateSpaceModel([[0.0]], [[0.0]], [[0.0]], dt=dt)
    sim = zero.simulate(tr.apply(val).u)
    np.testing.assert_allclose(tr.restore(sim, t0=val.time[0]), val.y, atol=1e-9)
    np.testing.assert_allclose(tr.restore(zero.simulate(est.u)), est.y, atol=1e-9)


def test_a_continuous_model_with_a_trend_compares_on_the_records_clock():
    # tr.attach(continuous model): compare's result had dt = 0 (the inner model's), so a
    # linear trend was restored at the record's start for every sample, error_spectrum and
    # report divided by zero, and the plot put every sample at t = 0
    rng = np.random.default_rng(10)
    mc = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    u = rng.standard_normal(512)
    y = mc.sampled(0.1).simulate(u)[:, 0] + 0.01 * rng.standard_normal(512)
    t = np.arange(512) * 0.1
    raw = sysid.IOData(u=u + 1.0, y=y + 2.0 + 0.3 * t, dt=0.1)
    _, tr = sysid.detrend(raw, "linear", return_trend=True)
    tm = tr.attach(mc)
    c = sysid.compare(tm, raw)
    assert c.dt == 0.1 and float(np.ravel(c.fit)[0]) > 90.0
    spec = sysid.error_spectrum(tm, raw)
    assert spec is not None
