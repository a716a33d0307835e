"""Result objects give text and a table, as the house style asks (``.summary()``,
``.to_pandas()``): step and impulse responses had neither, margins, ERA's and SSI's
stabilisation results and the Nyquist curve no table, step information, modes, forecasts
and online-estimation runs no summary."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

import sysid

A = np.array([[1.5, -0.7], [1.0, 0.0]])
TRUE = sysid.StateSpaceModel(A, [[1.0], [0.0]], [[0.3, 0.2]], dt=0.1)


def _data():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(600)
    y = TRUE.simulate(u[:, None]) + 0.02 * rng.standard_normal((600, 1))
    return sysid.IOData(u[:, None], y, 0.1)


NAMES = ["era", "era_stabilization", "forecast", "impulse", "margin", "modal", "nyquist",
         "recursive", "ssi", "step", "stepinfo"]


@pytest.fixture(scope="module")
def results():
    d = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.ssest(d, 2)
        k = np.arange(1, 61)
        rng = np.random.default_rng(1)
        h = (0.9 ** k * np.cos(0.5 * k) + 0.8 ** k * np.cos(1.5 * k)
             + 1e-3 * rng.standard_normal(k.size))[:, None, None]
        e = rng.standard_normal((4000, 1))
        yo = sysid.IOData(y=sysid.StateSpaceModel(A, [[1.0], [0.0]], [[0.3, 0.2]],
                                                  dt=0.1).simulate(e), dt=0.1)
        return {
            "step": sysid.step(m, std=True),
            "impulse": sysid.impulse(m, 30),
            "margin": sysid.margin(sysid.TransferFunction([1.0], [1.0, 2.0, 1.0, 0.0])),
            "era": sysid.era(h, 4),
            "era_stabilization": sysid.era_stabilization(h, [2, 4, 6]),
            "ssi": sysid.ssi(yo, [2, 4, 6]),
            "nyquist": sysid.nyquist(sysid.TransferFunction([1.0], [1.0, 2.0, 1.0, 0.0])),
            "stepinfo": sysid.stepinfo(m),
            "modal": sysid.modal_analysis(m),
            "forecast": sysid.forecast(m, d[:500], 10, future_inputs=d.u[500:510]),
            "recursive": sysid.RecursiveARX(2, 2, 1).run(d),
        }


@pytest.mark.parametrize("name", NAMES)
def test_every_result_has_text_and_a_table(results, name):
    r = results[name]
    text = r.summary()
    assert isinstance(text, str) and text.splitlines()[0] in (repr(r).splitlines()[0],
                                                               "StepInfo")
    assert len(text.splitlines()) >= 2  # more than the repr's line
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame) and len(df) >= 1
    values = df.select_dtypes("float").to_numpy()
    assert not np.isinf(values).any()  # NaN marks a column that does not apply to a row


def test_the_tables_hold_the_numbers(results):
    r = results
    step = r["step"]
    df = step.to_pandas()
    np.testing.assert_array_equal(df["y0 <- u0"].to_numpy(), step.y[:, 0, 0])
    np.testing.assert_array_equal(df["y0 <- u0 std"].to_numpy(), step.std[:, 0, 0])
    np.testing.assert_array_equal(df.index.to_numpy(), step.t)
    mg = r["margin"].to_pandas()
    assert mg["gain margin"].dropna().tolist() == pytest.approx([2.0])
    assert mg["phase margin [deg]"].dropna().tolist() == pytest.approx([21.386], abs=1e-3)
    st = r["era_stabilization"].to_pandas()
    assert set(st["order"]) == {2, 4, 6} and st["order"].is_monotonic_increasing
    assert set(st["status"]) <= {"stable", "frequency", "new"}
    ny = r["nyquist"].to_pandas()
    np.testing.assert_allclose(ny["real"] + 1j * ny["imag"], r["nyquist"].response)
    assert "stable" in r["nyquist"].summary()


def test_an_impulse_response_estimate_reads_as_matlab_s_impulseest_model():
    # impulse_response(data) had neither plot, summary nor to_pandas (impulseplot with
    # showConfidence, present): only the raw array and its std in a dict
    d = sysid.detrend(sysid.datasets.load_dryer(), "mean")  # raw: an OffsetWarning (true)
    est = sysid.impulse_response(d, 40)
    assert (est.input_names, est.output_names) == (d.input_names, d.output_names)
    imp, stp = est.impulse(), est.step()
    np.testing.assert_array_equal(imp.y, est.markov)
    np.testing.assert_array_equal(imp.std, est.info["std"])
    np.testing.assert_allclose(stp.y[:, 0, 0], np.cumsum(est.markov[:, 0, 0]))
    np.testing.assert_allclose(imp.t, 0.08 * np.arange(40))
    table = est.to_pandas()
    pair = "air temperature <- heater voltage"
    assert list(table.columns) == [pair, f"{pair} std"]
    np.testing.assert_array_equal(table[pair].to_numpy(), est.markov[:, 0, 0])
    text = est.summary()
    k = int(np.argmax(np.abs(est.markov[:, 0, 0])))
    assert f"largest {est.markov[k, 0, 0]:.4g}" in text and f"t = {0.08 * k:.4g}" in text
    assert f"sum (the gain) {est.markov[:, 0, 0].sum():.4g}" in text
    fig = est.plot()
    assert len(fig.axes) == 1 and "heater voltage" in fig.axes[0].get_title()
    # OKID's and the FRF's estimates carry the record's names too (no std: none estimated)
    ok = sysid.okid(d, 8, 30)
    assert ok.output_names == d.output_names and ok.impulse().std is None
    assert "std" not in ok.summary()
