"""One model protocol (issue 9 item 1): every function that takes a model takes any
:class:`sysid.Model` -- StateSpaceModel, ContinuousStateSpace, PolynomialModel and a FIR
model class defined only here, in 20 lines, that knows nothing of sysid's internals."""

from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest

import sysid

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


class FIR:
    """y(t) = sum_k h[k] u(t - k) + e(t): the whole protocol, nothing inherited."""

    def __init__(self, h, dt=1.0, info=None):
        self.h, self.dt, self.info = np.asarray(h, dtype=float), float(dt), dict(info or {})
        self.ninputs = self.noutputs = 1
        self.input_names, self.output_names = ["u0"], ["y0"]
        self.n_parameters = self.h.size

    def simulate(self, u, x0=None):
        u = np.asarray(u, dtype=float).reshape(-1)
        return np.convolve(u, self.h)[: u.size, None]

    def predict(self, u, y, horizon=1):
        return self.simulate(u)  # white output noise: the predictor is the simulation

    def freqresp(self, omega):
        z = np.exp(-1j * np.outer(omega, np.arange(self.h.size)) * self.dt)
        return (z @ self.h)[:, None, None]

    def to_dict(self):
        return {"h": self.h, "dt": self.dt, "info": self.info}

    @classmethod
    def from_dict(cls, d):
        return cls(d["h"], d["dt"], d["info"])


DT = 0.1
H_TRUE = np.array([0.0, 1.0, 0.6, 0.3, -0.2])
RNG_SEED = 3


def _data(model, n=600, noise=0.05, seed=RNG_SEED, hold="zoh"):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 1))
    if isinstance(model, sysid.ContinuousStateSpace):
        y = model.simulate(u, dt=DT, method=hold)
    else:
        y = model.simulate(u)
    return sysid.IOData(u, y + noise * rng.standard_normal(y.shape), DT)


def _families():
    A = [[0.7, 0.4], [-0.4, 0.7]]
    cont = sysid.ContinuousStateSpace([[-1.0, 4.0], [-4.0, -1.0]], [[4.0], [2.0]], [[1.0, 0.0]],
                                      info={"method": "physics"})
    # output-error structure: the data's white output noise is its innovation
    poly = sysid.PolynomialModel([[[]]], [[[0.5, 0.3]]], [[1]], DT, f=[[[-1.2, 0.5]]])
    return {
        "fir": FIR(H_TRUE, DT, {"method": "fir"}),
        "statespace": sysid.StateSpaceModel(A, [[1.0], [0.0]], [[1.0, 0.5]], dt=DT),
        "continuous": cont,
        "polynomial": poly,
    }


FAMILIES = sorted(_families())


@pytest.fixture(scope="module", params=FAMILIES)
def case(request):
    model = _families()[request.param]
    return request.param, model, _data(model), _data(model, noise=0.0, seed=9)


def test_every_family_satisfies_the_protocol(case):
    _, model, _, _ = case
    assert isinstance(model, sysid.Model)


def test_compare_is_exact_on_noise_free_data_and_scores_noise(case):
    name, model, noisy, clean = case
    for h in (None, 1):
        r = sysid.compare(model, clean, h)
        assert r.fit.shape == (1, 1)
        np.testing.assert_allclose(r.fit, 100.0, atol=1e-6)  # the model is the system
    noisy_fit = sysid.compare(model, noisy).fit[0, 0]
    assert 80 < noisy_fit < 100 - 1e-3
    # a different model of the same family fits worse: compare sees the model
    worse = sysid.compare(_perturbed(name, model), clean).fit[0, 0]
    assert worse < 99


def _perturbed(name, model):
    if name == "fir":
        return FIR(H_TRUE * [1, 0.5, 1, 1, 1], DT)
    if name == "polynomial":
        return sysid.PolynomialModel([[[]]], [[[0.5, 0.3]]], [[1]], DT, f=[[[-1.0, 0.4]]])
    return type(model)(model.A * 0.8, model.B, model.C, model.D,
                       **({"dt": DT} if name == "statespace" else {}))


def test_residuals_accept_the_true_model_and_reject_a_wrong_one(case):
    name, model, noisy, _ = case
    good = sysid.residuals(model, noisy, max_lag=15)
    assert good.is_white and bool(good.independence[0])
    bad = sysid.residuals(_perturbed(name, model), noisy, max_lag=15)
    assert not bad.independence[0]  # the missing dynamics correlate with past inputs


def test_error_spectrum_is_the_noise_floor_for_the_true_model(case):
    _, model, noisy, _ = case
    s = sysid.error_spectrum(model, noisy)
    # white noise of variance 0.05^2 at fs = 10 Hz: one-sided PSD 2 * 0.0025 / 10
    level = np.median(s.error_psd[1:-1, 0])
    assert 0.5 * 5e-4 < level < 2 * 5e-4
    assert np.all(s.output_psd[1:, 0] > 0)


def test_criteria_count_the_model_parameters(case):
    name, model, noisy, _ = case
    c = sysid.criteria(model, noisy, x0="zero")
    assert c.n_params == model.n_parameters
    if name == "fir":
        assert c.n_params == 5
    # an estimated x0 counts: state-space models, and models compared through their
    # state-space form (the OE polynomial model, whose initial state is now fitted too)
    c_est = sysid.criteria(model, noisy)
    extra = 2 if name in ("statespace", "continuous", "polynomial") else 0
    assert c_est.n_params == model.n_parameters + extra
    assert c.bic < sysid.criteria(_perturbed(name, model), noisy, x0="zero").bic


def test_select_order_ranks_candidate_models_of_any_family():
    data = _data(FIR(H_TRUE, DT))
    cands = [FIR(H_TRUE[:k], DT, {"method": f"fir{k}"}) for k in (2, 3, 5)]
    cands.append(FIR(np.r_[H_TRUE, 0.0, 0.0, 0.0], DT, {"method": "fir8"}))
    sel = sysid.select_order(data, models=cands, criterion="bic")
    assert sel.order == 5 and sel.model() is cands[2]
    assert [r["order"] for r in sel.rows] == [2, 3, 5, 8]
    assert "svd" not in sel.picks and "fir5" in repr(sel)
    # validation data pick too; a mixed list of families works
    fams = _families()
    mixed = [fams["statespace"], FIR(H_TRUE, DT)]
    val = _data(fams["statespace"], seed=11)
    sel = sysid.select_order(_data(fams["statespace"]), models=mixed, validation=val)
    assert sel.criterion == "validation" and sel.model() is fams["statespace"]
    with pytest.raises(sysid.DataError, match="order 5"):
        sysid.select_order(data, models=[FIR(H_TRUE, DT), FIR(H_TRUE, DT)])
    fig = sel.plot()
    ax = sel.stabilization_plot()
    assert len(fig.axes) == 3 and ax.get_ylabel() == "model order"
    plt.close("all")


def test_plots_take_any_model(case):
    name, model, noisy, _ = case
    from sysid.plot.model import plot_bode, plot_pzmap, plot_sigma

    fig = plot_bode([model, model], labels=["a", "b"])
    assert len(fig.axes) == 2
    assert plot_sigma(model).get_ylabel() == "singular values [dB]"
    for obj in (sysid.compare(model, noisy), sysid.residuals(model, noisy, max_lag=10),
                sysid.error_spectrum(model, noisy), sysid.step(model, 30),
                sysid.impulse(model, 30)):
        assert obj.plot().axes
    if name == "fir":
        with pytest.raises(sysid.DataError, match=r"to_statespace\(\)"):
            plot_pzmap(model)
    else:
        ax = plot_pzmap(model)
        assert ax.get_xlabel() == ("Re s" if name == "continuous" else "Re z")
        assert len(ax.lines[-2].get_xdata()) == len(model.poles())
    plt.close("all")


def test_step_and_impulse_of_a_fir_are_its_coefficients():
    r = sysid.impulse(FIR(H_TRUE, DT), 7)
    np.testing.assert_array_equal(r.y[:, 0, 0], np.r_[H_TRUE, 0, 0])
    np.testing.assert_allclose(sysid.step(FIR(H_TRUE, DT), 7).y[:, 0, 0],
                               np.cumsum(np.r_[H_TRUE, 0, 0]))
    np.testing.assert_allclose(r.t, DT * np.arange(7))


def test_report_takes_any_model(case, tmp_path):
    name, model, noisy, _ = case
    if name == "fir":
        sysid.register_model(FIR, name="tests.FIR")
    files = sysid.report(model, noisy, tmp_path, which="estimation")
    page = files["html"].read_text(encoding="utf-8")
    assert "<table id=\"fit\"" in page and "Fit on the estimation data" in page
    for sid in ("fit", "residuals", "spectrum", "bode", "step", "poles"):
        assert f'<details id="{sid}"' in page, sid  # every section, with its charts
    assert page.count('class="sysid-chart"') >= 8
    assert ("\"pole-zero map (" in page) == (name != "fir")
    back = sysid.load_model(files["model"])
    assert type(back) is type(model)
    u = noisy.experiments[0][0]
    kw = {"dt": DT} if name == "continuous" else {}
    np.testing.assert_array_equal(back.simulate(u, **kw), model.simulate(u, **kw))


@pytest.mark.parametrize("ext", ["json", "npz"])
def test_save_load_round_trip_every_family(ext, tmp_path):
    sysid.register_model(FIR, name="tests.FIR")
    u = np.random.default_rng(0).standard_normal((40, 1))
    for name, model in _families().items():
        path = tmp_path / f"{name}.{ext}"
        model.info["note"] = {"units": ["V"], "array": np.arange(3.0)}
        sysid.save_model(model, path)
        back = sysid.load_model(path)
        assert type(back) is type(model) and back.n_parameters == model.n_parameters
        np.testing.assert_array_equal(back.info["note"]["array"], np.arange(3.0))
        kw = {"dt": DT} if name == "continuous" else {}
        np.testing.assert_array_equal(back.simulate(u, **kw), model.simulate(u, **kw))
        np.testing.assert_array_equal(back.freqresp([0.3, 2.0]), model.freqresp([0.3, 2.0]))
    d = json.loads((tmp_path / f"fir.{ext}").read_text()) if ext == "json" else None
    if d is not None:
        assert d["family"] == "tests.FIR" and d["version"] == 2


def test_saving_needs_to_dict_and_registration(tmp_path):
    class Bare:
        pass

    with pytest.raises(sysid.DataError, match="to_dict"):
        sysid.save_model(Bare(), tmp_path / "m.json")
    with pytest.raises(sysid.DataError, match="from_dict"):
        sysid.register_model(Bare)

    class Unregistered(FIR):
        pass

    sysid.save_model(Unregistered(H_TRUE), tmp_path / "u.json")
    with pytest.raises(sysid.DataError, match="register"):
        sysid.load_model(tmp_path / "u.json")

    class Other(FIR):
        pass

    sysid.register_model(FIR, name="tests.FIR")
    with pytest.raises(sysid.DataError, match="already registered"):
        sysid.register_model(Other, name="tests.FIR")


def test_version_1_files_still_load(tmp_path):
    m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[2.0]], dt=0.5, info={"method": "old"})
    v1 = {"format": "sysid-state-space-model", "version": 1, "nstates": 1, "ninputs": 1,
          "noutputs": 1, "dt": 0.5, "A": [[0.5]], "B": [[1.0]], "C": [[2.0]], "D": [[0.0]],
          "K": None, "noise_cov": None, "x0": None, "input_names": ["u0"],
          "output_names": ["y0"], "info": {"method": "old"}}
    (tmp_path / "v1.json").write_text(json.dumps(v1))
    back = sysid.load_model(tmp_path / "v1.json")
    np.testing.assert_array_equal(back.C, m.C)
    assert back.info == {"method": "old"} and back.dt == 0.5


def test_missing_members_are_named():
    class Half:
        dt = 1.0

        def simulate(self, u, x0=None):
            return np.asarray(u)

    assert not isinstance(Half(), sysid.Model) and not isinstance(np.eye(2), sysid.Model)
    with pytest.raises(sysid.DataError, match="lacks predict, freqresp"):
        sysid.compare(Half(), (np.zeros(10), np.zeros(10)))
    for fn in (sysid.residuals, sysid.error_spectrum, sysid.criteria, sysid.report):
        with pytest.raises(sysid.DataError, match="must satisfy sysid.Model"):
            fn(Half(), (np.zeros(10), np.zeros(10)), *(["out"] if fn is sysid.report else []))
    with pytest.raises(sysid.DataError, match="lacks simulate"):
        sysid.select_order((np.zeros(10), np.zeros(10)), models=[object()])
    with pytest.raises(sysid.DataError, match="x0 must be 'estimate' or 'zero'"):
        sysid.compare(FIR(H_TRUE), (np.zeros(10), np.zeros(10)), x0=[1.0])
    with pytest.raises(sysid.DataError, match="needs the data's sample time"):
        sysid.compare(_families()["continuous"], (np.zeros((10, 1)), np.zeros((10, 1))))


def test_polynomial_k_step_prediction_matches_the_conditional_mean():
    """yhat(t | t-k) of an ARMAX model equals the output re-simulated with the innovations
    after t - k set to zero (their conditional mean) -- an oracle built with lfilter."""
    from scipy.signal import lfilter

    a, b, c = np.array([1, -1.2, 0.5]), np.array([0, 0.5, 0.3]), np.array([1, 0.4, 0.2])
    m = sysid.PolynomialModel([[a[1:]]], [[b[1:]]], [[1]], 1.0, c=[c[1:]])
    rng = np.random.default_rng(5)
    n = 60
    u, e = rng.standard_normal(n), 0.3 * rng.standard_normal(n)
    y = lfilter(b, a, u) + lfilter(c, a, e)
    for k in (1, 2, 3, 7):
        pred = m.predict(u[:, None], y[:, None], horizon=k)[:, 0]
        oracle = np.empty(n)
        for t in range(n):
            ek = e.copy()
            ek[max(t - k + 1, 0):] = 0.0
            oracle[t] = (lfilter(b, a, u) + lfilter(c, a, ek))[t]
        np.testing.assert_allclose(pred, oracle, atol=1e-10)
    np.testing.assert_allclose(m.predict(u[:, None], y[:, None], horizon=400),
                               m.simulate(u[:, None]), atol=1e-10)
    with pytest.raises(sysid.DataError, match="horizon"):
        m.predict(u[:, None], y[:, None], horizon=0)


def test_frd_takes_part_where_meaningful():
    """An FRD has no time response, but its frequency side plots beside models."""
    from sysid.plot.model import plot_bode, plot_sigma

    m = _families()["statespace"]
    w = np.linspace(0.5, 20.0, 60)
    frd = sysid.FRD(w, m.freqresp(w), dt=DT)
    assert (frd.ninputs, frd.noutputs) == (1, 1)
    np.testing.assert_array_equal(frd.freqresp(w[::-1]), m.freqresp(w[::-1]))
    mid = 0.5 * (w[3] + w[4])  # linear interpolation between neighbours
    np.testing.assert_allclose(frd.freqresp([mid])[0], 0.5 * (frd.response[3] + frd.response[4]))
    with pytest.raises(sysid.DataError, match="extrapolate"):
        frd.freqresp([30.0])
    fig = plot_bode([m, frd], labels=["model", "data"])
    xs = fig.axes[0].lines[1].get_xdata()
    np.testing.assert_allclose(xs, w / (2 * np.pi))  # the FRD's own grid
    assert plot_sigma(frd).lines
    with pytest.raises(sysid.DataError, match="no time response"):
        sysid.compare(frd, (np.zeros(10), np.zeros(10)))
    with pytest.raises(sysid.DataError, match="no time response"):
        sysid.compare((np.zeros(10), np.zeros(10)), frd)
    plt.close("all")


def test_docs_models_examples_run(tmp_path, monkeypatch, capsys):
    """docs/models.md: every Python block runs and prints what the comments say."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "models.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) == 3
    monkeypatch.chdir(tmp_path)
    for i, block in enumerate(blocks):
        exec(compile(block, f"docs/models.md[{i}]", "exec"), {})
    out = capsys.readouterr().out.splitlines()
    # print(compare(...)) shows its summary: a header, the column names, one row per output
    assert out[0].startswith("simulation of") and out[1].split()[:3] == ["exp", "output", "fit"]
    out = out[2:]
    assert out[1] == "True" and out[2] == "4 bic"
    assert out[3].startswith("[0.  1.  0.6 0.3]")
    assert out[4] == "[[100.]]" and out[6] == "True"
    assert out[7:] == ["['valve', 'heater'] ['temp']", "[[5.]]", "['temp', 'flow']"]


def test_mixin_defaults_go_through_to_statespace():
    """ModelMixin writes predict, poles, zeros, step and impulse once, via to_statespace()."""
    ss = sysid.StateSpaceModel([[0.8, 0.1], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, -0.5]],
                               K=[[0.4], [0.1]], dt=DT)

    class Wrapped(sysid.ModelMixin):
        dt, info, n_parameters = DT, {}, 7
        ninputs = noutputs = 1
        input_names, output_names = ["u0"], ["y0"]

        def simulate(self, u, x0=None):
            return ss.simulate(u)

        def freqresp(self, omega):
            return ss.freqresp(omega)

        def to_statespace(self):
            return ss

    w = Wrapped()
    rng = np.random.default_rng(1)
    u, y = rng.standard_normal((2, 80, 1))
    for k in (1, 3):
        np.testing.assert_array_equal(w.predict(u, y, k), ss.predict(u, y, k))
    np.testing.assert_array_equal(w.poles(), ss.poles())
    np.testing.assert_array_equal(w.zeros(), ss.zeros())
    np.testing.assert_allclose(w.step(20).y, ss.step(20).y, atol=1e-14)
    np.testing.assert_allclose(w.impulse(20).y, ss.impulse(20).y, atol=1e-14)
    assert sysid.damp(w).dt == DT and len(sysid.damp(w)) == 2
    # the polynomial family gets step/impulse from the mixin too, equal to its state space
    poly = _families()["polynomial"]
    np.testing.assert_allclose(sysid.step(poly, 25).y, sysid.step(poly.to_statespace(), 25).y,
                               atol=1e-12)

    class NoStateSpace(sysid.ModelMixin):
        pass

    with pytest.raises(sysid.DataError, match=r"predict needs a state-space form.*to_statespace"):
        NoStateSpace().predict(u, y, 2)


def test_simulation_of_a_polynomial_model_estimates_its_initial_conditions():
    """compare(x0="estimate") fits the initial state of to_statespace(): exact on data
    that start away from rest, where starting from rest is visibly worse."""
    poly = _families()["polynomial"]
    ss = poly.to_statespace()
    u = np.random.default_rng(4).standard_normal((200, 1))
    y = ss.simulate(u, x0=[2.0, -1.0])
    est = sysid.compare(poly, (u, y))
    np.testing.assert_allclose(est.fit, 100.0, atol=1e-6)
    assert sysid.compare(poly, (u, y), x0="zero").fit[0, 0] < 99
    assert sysid.compare(FIR(H_TRUE), (u, y)).x0 == [None]  # no state form: from rest


def test_coupled_mimo_arx_k_step_prediction_matches_the_conditional_mean():
    """A matrix-A ARX model: yhat(t | t-k) equals the output re-simulated with the innovations
    after t - k set to zero; k = 1 leaves exactly the innovations as residuals."""
    a = [[np.array([-0.5]), np.array([0.2])], [np.array([-0.3]), np.array([-0.4, 0.1])]]
    b = [[np.array([1.0])], [np.array([0.5])]]
    m = sysid.PolynomialModel(a, b, [[1], [1]], 1.0)
    assert m.coupled
    rng = np.random.default_rng(8)
    n = 40
    u, e = rng.standard_normal((n, 1)), 0.2 * rng.standard_normal((n, 2))

    def run(ee):
        y = np.zeros((n, 2))
        for t in range(n):
            for i in range(2):
                s = ee[t, i] + (b[i][0][0] * u[t - 1, 0] if t >= 1 else 0.0)
                for q in range(2):
                    for lag, c in enumerate(a[i][q], start=1):
                        if t >= lag:
                            s -= c * y[t - lag, q]
                y[t, i] = s
        return y

    y = run(e)
    np.testing.assert_allclose(m.residuals(u, y), e, atol=1e-12)
    np.testing.assert_allclose(run(np.zeros_like(e)), m.simulate(u), atol=1e-12)
    for k in (1, 2, 4):
        oracle = np.empty((n, 2))
        for t in range(n):
            ek = e.copy()
            ek[max(t - k + 1, 0):] = 0.0
            oracle[t] = run(ek)[t]
        np.testing.assert_allclose(m.predict(u, y, horizon=k), oracle, atol=1e-12)
    assert sysid.compare(m, (u, y), horizon=2).fit.shape == (1, 2)


def test_state_space_tools_go_through_to_statespace():
    """Modal analysis and balanced reduction take any model with to_statespace(); others are
    told which method is missing, continuous ones to discretise first."""
    poly = _families()["polynomial"]
    ss = poly.to_statespace()
    np.testing.assert_allclose(sysid.hankel_singular_values(poly),
                               sysid.hankel_singular_values(ss))
    np.testing.assert_allclose(np.sort(sysid.modal_analysis(poly).omega),
                               np.sort(sysid.modal_analysis(ss).omega))
    with pytest.raises(sysid.DataError, match=r"to_statespace\(\)"):
        sysid.gramians(FIR(H_TRUE, DT))
    with pytest.raises(sysid.DataError, match="c2d"):
        sysid.modal_analysis(_families()["continuous"])


def test_pzmap_draws_each_pole_s_confidence_region():
    # MATLAB's showConfidence(pzmap(sys)): pzmap(model, confidence=0.95) was a TypeError
    import warnings

    from matplotlib.patches import Ellipse

    from sysid.models.uncertainty import UncertaintyWarning

    rng = np.random.default_rng(5)
    true = sysid.StateSpaceModel([[0.7, 0.5, 0.0], [-0.5, 0.7, 0.0], [0.0, 0.0, 0.3]],
                                 [[1.0], [0.0], [1.0]], [[1.0, 0.0, 1.0]], dt=1.0)
    u = rng.standard_normal((1000, 1))
    d = sysid.IOData(u, true.simulate(u) + 0.1 * rng.standard_normal((1000, 1)), 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.ssest(d, 3, focus="simulation")
    p, sd = m.poles(std=True)
    ax = sysid.pzmap(m, confidence=0.95)
    k2, k1 = np.sqrt(-2 * np.log(0.05)), 1.959964
    ellipses = [a for a in ax.patches if isinstance(a, Ellipse)]
    cplx = [(q, s) for q, s in zip(p, sd) if q.imag != 0]
    assert len(ellipses) == len(cplx) == 2
    for (q, s), e in zip(cplx, ellipses):
        assert e.center == pytest.approx((q.real, q.imag))
        assert (e.width, e.height) == pytest.approx((2 * k2 * s.real, 2 * k2 * s.imag))
    q, s = next((q, s) for q, s in zip(p, sd) if q.imag == 0)
    seg = [ln for ln in ax.lines if ln.get_linewidth() == 3]
    assert len(seg) == 1
    assert seg[0].get_xdata() == pytest.approx([q.real - k1 * s.real, q.real + k1 * s.real])
    plt.close("all")
    with pytest.warns(UncertaintyWarning, match="carry no parameter uncertainty"):
        sysid.pzmap(true, confidence=0.9)
    plt.close("all")


def test_matlab_s_bode_and_pzmap_and_the_plot_package_s_own_names():
    # docs/pem.md said `sysid.plot.plot_bode(model, confidence=0.95)`, which raised
    # AttributeError (the function was only in sysid.plot.model), and MATLAB's bode(sys1,
    # sys2) and pzmap(sys) had no sysid name
    import subprocess
    import sys

    a = sysid.StateSpaceModel([[0.9]], [[1.0]], [[0.1]], dt=0.1)
    b = sysid.StateSpaceModel([[0.5, 0.2], [0.0, 0.3]], [[1.0], [0.5]], [[0.5, 1.0]], dt=0.1)
    assert sysid.plot.plot_bode is sysid.plot.model.plot_bode
    assert sysid.plot.realization.plot_stabilization  # a submodule, reached on first use
    fig = sysid.bode(a, b, labels=["a", "b"])
    assert len(fig.axes) == 2 and len(fig.axes[0].lines) == 2
    ax = sysid.pzmap(a, b)
    poles = np.concatenate([ln.get_xdata() for ln in ax.lines if ln.get_marker() == "x"])
    assert sorted(np.round(poles, 6)) == [0.3, 0.5, 0.9]
    plt.close("all")
    with pytest.raises(sysid.DataError, match="at least one model"):
        sysid.bode()
    with pytest.raises(AttributeError, match="plot_nothing"):
        sysid.plot.plot_nothing  # noqa: B018
    # importing sysid (and reaching these names) does not load matplotlib
    code = "import sys, sysid; sysid.bode; sysid.plot; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "False", out.stderr
