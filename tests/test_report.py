"""The report's figures as data: one phase branch for model and estimate, bands, names and
units on the axes, the stabilisation diagram's classes; reports of other model kinds."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import sysid
from sysid.analysis import report_figures as rf

pytest.importorskip("pandas")


def delayed_model() -> sysid.StateSpaceModel:
    """A 6-sample delay behind a resonance: its phase falls far below -360 degrees."""
    n = 8
    A = np.zeros((n, n))
    A[1:6, 0:5] = np.eye(5)  # shift register of the delay
    A[6:8, 6:8] = [[1.6, -0.81], [1.0, 0.0]]
    A[6, 5] = 1.0
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    C = np.zeros((1, n))
    C[0, 6] = 0.3
    return sysid.StateSpaceModel(A, B, C, dt=0.05, input_names=["valve"],
                                 output_names=["flow"])


def test_model_and_estimate_phases_share_one_branch():
    m = delayed_model()
    u = np.random.default_rng(0).standard_normal((20000, 1))
    data = sysid.IOData(u=u, y=m.simulate(u), dt=0.05, input_names=["valve"],
                        output_names=["flow"], input_units=["%"], output_units=["m3/h"])
    frd = sysid.spa(data)
    mag, ph = rf.bode_figures(m, frd, {"valve": "%", "flow": "m3/h"})
    model, est = ph["series"][0], ph["series"][1]
    assert min(v for v in model["y"] if v is not None) < -540  # unwrapped, not folded
    assert -180 < model["y"][0] <= 180
    xm, ym = np.array(model["x"]), np.array(model["y"], dtype=float)
    xe, ye = np.array(est["x"]), np.array(est["y"], dtype=float)
    coh = np.abs(frd.response[frd.omega > 0, 0, 0]) > 0.05  # where the estimate is good
    gap = np.abs(ye - np.interp(xe, xm, ym))[coh]
    assert gap.max() < 30  # the estimate follows the model: no 360-degree offsets
    assert "(|G| in m3/h / %)" in mag["title"] and "valve -> flow" in mag["title"]
    assert [b["name"] for b in mag["bands"]] == [f"estimate {100 * frd.confidence:.0f} %"]


def test_model_band_when_the_model_has_an_uncertainty():
    d = sysid.datasets.load_dryer()
    m = sysid.SubspaceEstimator(d, 15).fit(4, uncertainty="bootstrap", n_boot=20, rng=0)
    mag, ph = rf.bode_figures(m, None, {})
    for fig in (mag, ph):
        b = fig["bands"][0]
        lo, hi = np.array(b["lo"], dtype=float), np.array(b["hi"], dtype=float)
        assert b["name"] == "model 95 %" and np.all(hi >= lo) and np.any(hi > lo)
    (step,) = rf.step_figures(m, {"heater voltage": "V"})
    assert step["bands"] and "heater voltage [V]" in step["y"]["label"]


def test_stabilisation_diagram_classes():
    rng = np.random.default_rng(3)
    blocks = [r * np.array([[np.cos(w), -np.sin(w)], [np.sin(w), np.cos(w)]])
              for r, w in ((0.95, 0.3), (0.9, 1.1))]
    A = np.block([[blocks[0], np.zeros((2, 2))], [np.zeros((2, 2)), blocks[1]]])
    m = sysid.StateSpaceModel(A, rng.standard_normal((4, 1)), rng.standard_normal((1, 4)))
    u = rng.standard_normal((4000, 1))
    d = sysid.IOData(u=u, y=m.simulate(u) + 0.01 * rng.standard_normal((4000, 1)))
    sel = sysid.select_order(sysid.SubspaceEstimator(d, 15), range(1, 9))
    fig = rf.stabilization_figure(sel)
    names = [s["name"] for s in fig["series"]]
    counted = sum(int(n.rsplit("(", 1)[1].rstrip(")")) for n in names)
    expected = sum(int(np.sum(t.poles.imag >= 0)) for _, t in sel.damping())
    assert counted == expected  # every pole of every order (one per conjugate pair)
    assert any(n.startswith("stable in frequency and damping") for n in names)
    assert any(n.startswith("new") for n in names)
    assert fig["y"]["label"] == "model order" and fig["x"]["log"]


def test_time_series_and_continuous_models(tmp_path):
    y = np.zeros((600, 1))
    e = np.random.default_rng(1).standard_normal((600, 1))
    for t in range(1, 600):
        y[t] = 0.7 * y[t - 1] + e[t]
    ar = sysid.StateSpaceModel([[0.7]], np.zeros((1, 0)), [[1.0]], K=[[0.7]])
    files = sysid.report(ar, sysid.IOData(y=y), tmp_path / "ar")
    text = files["html"].read_text()
    assert "time-series model (no inputs)" in text and 'id="bode"' not in text
    c = sysid.ContinuousStateSpace([[-2.0]], [[2.0]], [[1.0]])
    u = np.random.default_rng(2).standard_normal((400, 1))
    y = c.c2d(0.05).simulate(u) + 0.05 * np.random.default_rng(3).standard_normal((400, 1))
    data = sysid.IOData(u=u, y=y, dt=0.05)
    text = sysid.report(c, data, tmp_path / "c")["html"].read_text()
    specs = [json.loads(s.split(">", 1)[1].split("</script>")[0]) for s in text.split(
        '<script type="application/json" id="fig')[1:]]
    assert any(s["title"] == "pole-zero map (s plane)" for s in specs)


def test_residual_advice_fits_a_model_without_a_noise_model(tmp_path):
    # An output-error model's one-step errors are its simulation errors: the report said
    # "the noise model or some dynamics are missing; try a higher order" for them
    rng = np.random.default_rng(61)
    u = rng.standard_normal(800)
    x = np.zeros(800)
    for t in range(1, 800):
        x[t] = 0.8 * x[t - 1] + 0.5 * u[t - 1]
    e = np.convolve(rng.standard_normal(800), [1.0, 0.9, 0.8])[:800]  # coloured noise
    d = sysid.IOData(u, x + 0.1 * e, 1.0)
    oe_text = sysid.report(sysid.oe(d, 1, 1, 1), d, tmp_path / "oe")["html"].read_text()
    assert "as expected: the model has no noise model" in oe_text
    assert "try a higher order or a prediction-error" not in oe_text
    arx_text = sysid.report(sysid.arx(d, 1, 1, 1), d, tmp_path / "arx")["html"].read_text()
    assert "try a higher order or a prediction-error" in arx_text


def test_text_tables_keep_long_channel_names_whole():
    # two outputs "outlet temperature sensor A" / "... B" read as the same truncated row
    rng = np.random.default_rng(62)
    u = rng.standard_normal((400, 1))
    y = np.hstack([np.convolve(u[:, 0], [0, 0.5, 0.2])[:400, None],
                   np.convolve(u[:, 0], [0, 0.3, 0.4])[:400, None]])
    y = y + 0.01 * rng.standard_normal(y.shape)
    names = ["outlet temperature sensor A", "outlet temperature sensor B"]
    d = sysid.IOData(u, y, 1.0, output_names=names)
    m = sysid.arx(d, [[2, 0], [0, 2]], [[2], [2]], [[1], [1]])
    for text in (repr(d.summary()), sysid.compare(m, d).summary(),
                 sysid.residuals(m, d).summary()):
        assert all(n in text for n in names), text


def test_bode_bands_asked_of_a_model_without_uncertainty_are_said_missing():
    # plot_bode(m, confidence=0.95) drew no band for a model without uncertainty and said
    # nothing
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    from sysid.plot.model import plot_bode

    rng = np.random.default_rng(63)
    u = rng.standard_normal(400)
    d = sysid.IOData(u, np.convolve(u, [0, 0.5, 0.3])[:400] + 0.01 * rng.standard_normal(400))
    with pytest.warns(sysid.UncertaintyWarning, match=r"model\(s\) \[0\] carry no parameter"):
        plot_bode(sysid.n4sid(d, 2, uncertainty=None), confidence=0.95)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        plot_bode(sysid.arx(d, 1, 2, 1), confidence=0.95)


def test_compare_plot_keeps_the_records_clock():
    # the second half of a record (t = 40 .. 79.92 s) was plotted from t = 0
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    d = sysid.detrend(sysid.datasets.load_dryer())
    val = d[500:]
    fig = sysid.compare(sysid.arx(d[:500], 2, 2, 3), val).plot()
    x = fig.axes[0].lines[0].get_xdata()
    assert x[0] == pytest.approx(val.times[0][0]) and x[0] > 39


def test_several_models_in_one_plot_are_told_apart():
    # pzmap of two models: legend "poles, zeros, poles, zeros"; bode of an FRD: "model 0"
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    from sysid.plot.model import plot_bode, plot_pzmap

    rng = np.random.default_rng(64)
    u = rng.standard_normal(600)
    d = sysid.IOData(u, np.convolve(u, [0, 0.5, 0.3])[:600] + 0.01 * rng.standard_normal(600))
    a, b = sysid.arx(d, 2, 2, 1), sysid.n4sid(d, 2)
    labels = [t.get_text() for t in plot_pzmap([a, b]).get_legend().get_texts()]
    assert len(set(labels)) == 4
    frd = sysid.spa(d)
    fig = plot_bode([frd, a])
    names = [ln.get_label() for ln in fig.axes[0].lines]
    assert "model 0" not in names and str(frd.method) in names
