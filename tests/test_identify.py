"""Issue 26 (items 2-4): order and feedthrough chosen from the data, and ``sysid.identify``.

Real records: the shipped DaISy copies (``sysid.datasets``) with the splits of the records'
README (dryer 1:500 / 501:1000, robot arm 1:800 / 801:1024, winding first 2/3 / last 1/3).
"""

from __future__ import annotations

import re
import time
import warnings

import numpy as np
import pytest
from _guides import guide_text, python_blocks, run_guide

import sysid
from sysid.validation.crossval import choose, cross_validated_order

from conftest import daisy_split, feedthrough_record, quiet


def plain_po_moesp(data: sysid.IOData, n: int, i: int = 10) -> sysid.StateSpaceModel:
    """The reference of the issue, as a user writes it: PO-MOESP in NumPy (LQ, SVD, A and C
    from the shift), B, D and x0 by least squares on the data."""
    (u, y), = data.experiments
    m, l = u.shape[1], y.shape[1]
    j = u.shape[0] - 2 * i + 1

    def hank(x, s):
        return np.vstack([x[s + k:s + k + j].T for k in range(i)])
    Z = np.vstack([hank(u, i), hank(u, 0), hank(y, 0), hank(y, i)])
    R = np.linalg.qr(Z.T, mode="r").T
    U, s, _ = np.linalg.svd(R[2 * m * i + l * i:, m * i:2 * m * i + l * i])
    Ob = U[:, :n] * np.sqrt(s[:n])
    C, A = Ob[:l], np.linalg.lstsq(Ob[:-l], Ob[l:], rcond=None)[0]
    N = u.shape[0]
    cols, M = [], C.copy()
    free = np.empty((N, l, n))
    for t in range(N):
        free[t], M = M, M @ A
    cols.append(free.reshape(N * l, n))
    for jj in range(m):
        for k in range(n):
            Bk = np.zeros((n, m))
            Bk[k, jj] = 1.0
            cols.append(sysid.StateSpaceModel(A, Bk, C).simulate(u).reshape(-1, 1))
    for r in range(l):
        for jj in range(m):
            col = np.zeros((N, l))
            col[:, r] = u[:, jj]
            cols.append(col.reshape(-1, 1))
    th = np.linalg.lstsq(np.hstack(cols), y.ravel(), rcond=None)[0]
    B = th[n:n + n * m].reshape(m, n).T
    return sysid.StateSpaceModel(A, B, C, th[n + n * m:].reshape(l, m))


# -- order="auto" ------------------------------------------------------------------------
def test_auto_order_on_the_dryer_is_not_one_or_two_and_says_why():
    est, val = daisy_split("dryer")
    for fit in (sysid.moesp, sysid.n4sid):
        m = quiet(fit, est)
        sel = m.info["order_selection"]
        assert m.nstates >= 3, sel  # the singular-value gap picked 2 here
        assert sel["criterion"] == "cross-validated simulation fit"
        assert set(sel["table"]) >= set(range(1, 9)) and "order" in sel["reason"]
        # and the automatic model is as good on fresh data as the literature's order 4
        ref = quiet(fit, est, order=4)
        assert (quiet(sysid.compare, m, val).mean_fit
                > quiet(sysid.compare, ref, val).mean_fit - 0.5)


def test_auto_order_recovers_the_true_order_of_noise_free_data():
    rng = np.random.default_rng(3)
    true = sysid.StateSpaceModel(np.diag([0.9, 0.5, -0.3, 0.1]), np.ones((4, 1)),
                                 np.array([[1.0, 0.7, 0.4, 0.2]]))
    u = rng.standard_normal((600, 1))
    data = sysid.IOData(u=u, y=true.simulate(u))
    assert cross_validated_order(data, sysid.SubspaceEstimator).order == 4


def test_choose_prefers_a_smaller_order_only_within_the_tolerance():
    assert choose({1: 50.0, 2: 80.0, 3: 80.3, 4: 79.0})[0] == 2
    assert choose({1: 50.0, 2: 80.0, 3: 81.0})[0] == 3
    assert choose({1: 90.0, 2: 98.9, 3: 99.0})[0] == 3  # 5 % of the error: 0.05
    # within RESOLUTION (0.1 point) of 100 %: ties, as identify's board reads them (5 % of
    # the error, 0.0005, took order 3 here)
    assert choose({1: 99.0, 2: 99.99, 3: 99.999})[0] == 2


def test_ssest_with_a_range_of_orders_cross_validates_the_refined_models():
    est, val = daisy_split("dryer")
    m = quiet(sysid.ssest, est, order=range(1, 7))
    sel = m.info["order_selection"]
    assert sorted(sel["table"]) == list(range(1, 7))
    assert m.nstates == sel["order"] >= 3
    assert "refined" in sel["criterion"]
    assert quiet(sysid.compare, m, val).mean_fit > 80


def test_ssest_order_auto():
    est, _ = daisy_split("dryer")
    m = quiet(sysid.ssest, est)  # order="auto" is the default
    assert m.nstates >= 3 and m.info["order_selection"]["order"] == m.nstates


# -- feedthrough="auto" ------------------------------------------------------------------
@pytest.mark.parametrize("d", [0.0, 0.8])
def test_ssest_feedthrough_auto_decides_from_the_data(d):
    m = quiet(sysid.ssest, feedthrough_record(d, seed=1), 2, feedthrough="auto")
    sel = m.info["feedthrough_selection"]
    assert sel["feedthrough"] is (d != 0), sel
    assert abs(m.D[0, 0] - d) < 0.05


@pytest.mark.parametrize("d", [0.0, 0.8])
def test_subspace_feedthrough_auto_decides_by_held_out_fit(d):
    m = quiet(sysid.moesp, feedthrough_record(d, seed=2), feedthrough="auto")
    sel = m.info["feedthrough_selection"]
    assert sel["feedthrough"] is (d != 0), sel
    assert m.nstates == 2 and abs(m.D[0, 0] - d) < 0.05


def test_feedthrough_auto_on_the_winding_record_estimates_d():
    # the winding record's validation fit (moesp, order chosen): 74.7 % with D, 64.6 % without
    est, val = daisy_split("winding")
    m = quiet(sysid.moesp, est, feedthrough="auto")
    assert m.info["feedthrough_selection"]["feedthrough"] is True
    assert quiet(sysid.compare, m, val).mean_fit > 72


# -- identify ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["dryer", "robot_arm"])
def test_identify_beats_the_plain_po_moesp_reference_on_held_out_data(name):
    raw_est, raw_val = daisy_split(name, centred=False)
    est, val = daisy_split(name)
    res = quiet(sysid.identify, raw_est, raw_val, progress=False)
    assert res.model.is_stable()
    ours = res.model.compare(raw_val).mean_fit
    assert ours == pytest.approx(res.validation_fit)
    # the reference at the literature's order (README: dryer 4; robot arm 4, 6 slightly better)
    ref = max(quiet(sysid.compare, plain_po_moesp(est, n), val).mean_fit for n in (4, 6))
    assert ours >= ref - 0.5, (ours, ref, res.summary())


def scipy_refined(data: sysid.IOData, start: sysid.StateSpaceModel) -> sysid.StateSpaceModel:
    """The issue's second reference: every entry of A, B, C, D and x0 refined by SciPy's
    ``least_squares`` on the simulation error, as a user writes it."""
    from scipy.optimize import least_squares

    (u, y), = data.experiments
    n, m, l = start.nstates, start.ninputs, start.noutputs
    x0 = sysid.estimate_x0(start, u, y)
    shapes = [(n, n), (n, m), (l, n), (l, m), (n,)]
    sizes = np.cumsum([0] + [int(np.prod(s)) for s in shapes])

    def unpack(p):
        return [p[a:b].reshape(s) for a, b, s in zip(sizes[:-1], sizes[1:], shapes)]

    def res(p):
        A, B, C, D, x = unpack(p)
        try:
            e = (sysid.StateSpaceModel(A, B, C, D).simulate(u, x0=x) - y).ravel()
        except sysid.errors.NumericalError:  # a trial step that diverges
            return np.full(y.size, 1e10)
        return np.where(np.isfinite(e), e, 1e10)
    p0 = np.concatenate([start.A.ravel(), start.B.ravel(), start.C.ravel(), start.D.ravel(),
                         x0])
    A, B, C, D, _ = unpack(least_squares(res, p0, max_nfev=50, x_scale="jac").x)
    return sysid.StateSpaceModel(A, B, C, D)


def test_identify_reaches_the_scipy_refinement_on_the_dryer():
    # main validated 85.8 % here (a subspace model of order 4), the reference 86.8 %: the
    # held-out blocks cannot tell orders 3-6 apart, the BIC of the refined re-fits can
    raw_est, raw_val = daisy_split("dryer", centred=False)
    est, val = daisy_split("dryer")
    res = quiet(sysid.identify, raw_est, raw_val, progress=False)
    ref = quiet(sysid.compare, quiet(scipy_refined, est, plain_po_moesp(est, 4)), val).mean_fit
    assert ref > 86.0  # the reference itself (validation 86.8 %)
    assert res.model.is_stable() and res.validation_fit >= ref - 0.5, (ref, res.summary())


def test_identify_on_the_winding_record_with_subspace_candidates_only():
    raw_est, raw_val = daisy_split("winding", centred=False)
    est, val = daisy_split("winding")
    res = quiet(sysid.identify, raw_est, raw_val, refine=False, progress=False)
    ref = quiet(sysid.compare, plain_po_moesp(est, 6), val).mean_fit
    assert res.model.is_stable() and res.validation_fit >= ref - 0.5, res.summary()


def test_identify_result_presents_itself_and_predicts_raw_data():
    rng = np.random.default_rng(0)
    true = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])
    u = rng.standard_normal((600, 1))
    y = true.simulate(u) + 5.0 + 0.02 * rng.standard_normal((600, 1))
    res = sysid.identify(sysid.IOData(u=u + 2.0, y=y), refine=False, progress=False)
    assert res.model.nstates == 2
    np.testing.assert_allclose(res.model.u_offset, 2.0, atol=0.2)
    sim = res.model.simulate(u + 2.0)  # raw in, raw out
    assert abs(sim.mean() - y.mean()) < 0.2
    assert "IdentifyResult" in repr(res) and "held-out fit" in res.summary()
    df = res.to_pandas()
    assert {"family", "order", "held_out_fit", "stable", "seconds"} <= set(df.columns)
    chosen = [r for r in res.leaderboard if r["chosen"]]
    assert len(chosen) == 1 and chosen[0]["held_out_fit"] >= df["held_out_fit"].max() - 0.5
    assert "offsets" in res.checks and "feedback" in res.checks


def test_identify_refuses_output_only_data_and_too_short_records():
    with pytest.raises(sysid.errors.DataError, match="inputs"):
        sysid.identify(sysid.IOData(u=None, y=np.random.default_rng(0).standard_normal(100)))
    with pytest.raises(sysid.errors.SysidError):
        sysid.identify(sysid.IOData(u=np.arange(12.0), y=np.arange(12.0) ** 2))


def test_identify_is_callable_as_a_package_and_a_function():
    import sysid.identify.core  # noqa: F401 - the submodule import must not shadow it

    assert callable(sysid.identify)


def test_the_command_line_uses_identify_by_default(tmp_path, capsys):
    from sysid.cli import main

    d = np.loadtxt(sysid.datasets.path("dryer"))
    path = tmp_path / "dryer.csv"
    np.savetxt(path, d, delimiter=",", header="heater,temperature", comments="")
    rep = tmp_path / "out"
    assert main(["identify", str(path), "--inputs", "heater", "--outputs", "temperature",
                 "--dt", "0.08", "--split", "500", "--report", str(rep), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "sysid.identify:" in out and "held-out fit" in out
    model = sysid.load_model(rep / "model.json")
    assert model.nstates >= 3 and model.info["identify"]["family"]
    offs = model.info["preprocessing"]["identify_offsets"]
    assert offs["y"][0] == pytest.approx(d[:500, 1].mean())


def test_the_identify_guide_runs():
    """docs/identify.md: every python block executes."""
    assert len(python_blocks(guide_text("identify.md"))) == 4
    ns = quiet(run_guide, "identify.md")
    assert ns["res"].model.is_stable() and ns["m"].nstates >= 3
    assert ns["step"].score == "BIC" and ns["step"].model.y_offset[0] == pytest.approx(
        21.0, abs=0.02)


def test_identify_returns_an_unstable_model_only_when_the_data_insist():
    # an open-loop unstable plant: every stable candidate simulates the held-out blocks
    # worse than the unstable ones, so the model is unstable, with a warning naming the pole
    rng = np.random.default_rng(4)
    plant = sysid.StateSpaceModel([[1.01, 0.0], [0.0, 0.6]], [[1.0], [1.0]], [[1.0, 1.0]])
    u = rng.standard_normal((600, 1))
    data = sysid.IOData(u=u, y=plant.simulate(u) + 0.05 * rng.standard_normal((600, 1)))
    with pytest.warns(sysid.errors.StabilityWarning, match="largest pole modulus 1.01"):
        res = sysid.identify(data, refine=False, progress=False)
    assert not res.model.is_stable() and "UNSTABLE" in repr(res.model)
    assert np.max(np.abs(res.model.poles())) == pytest.approx(1.01, abs=2e-3)
    # its uncertainty is the prediction-error criterion's (the simulation error diverges at
    # an unstable model; poles(std=True) raised "no parameter uncertainty" here)
    with warnings.catch_warnings():  # the extra poles of order 6 may overlap: Monte Carlo
        warnings.simplefilter("ignore", sysid.models.uncertainty.UncertaintyWarning)
        poles, std = res.model.poles(std=True)
    assert np.all(np.isfinite(std)) and np.all(np.abs(std) > 0)
    k = int(np.argmax(np.abs(poles)))
    assert abs(abs(poles[k]) - 1.01) < 3 * abs(std[k]) + 2e-3
    assert "prediction-error criterion" in res.checks["uncertainty"]
    # asked for a stable model, it gets the best stable one, without a warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        stable = sysid.identify(data, refine=False, enforce_stability=True, progress=False)
    assert stable.model.is_stable() and "UNSTABLE" not in repr(stable.model)
    with pytest.raises(sysid.errors.DataError, match="enforce_stability"):
        sysid.identify(data, enforce_stability="yes")


def test_the_unstable_model_warning_names_its_modes_and_the_margin():
    # the warning said only "an integrating or unstable plant", also for a growing
    # oscillation far from any integrator (a car's log: a pole pair of modulus 1.056 at a
    # quarter of the sample rate); it names each unstable mode and the held-out fits compared
    rng = np.random.default_rng(4)
    r, w = 1.01, 0.5
    a = [[r * np.cos(w), -r * np.sin(w), 0.0], [r * np.sin(w), r * np.cos(w), 0.0],
         [0.0, 0.0, 0.6]]
    plant = sysid.StateSpaceModel(a, [[1.0], [0.0], [1.0]], [[1.0, 0.5, 1.0]], dt=0.1)
    u = rng.standard_normal((800, 1))
    data = sysid.IOData(u=u, y=plant.simulate(u) + 0.05 * rng.standard_normal((800, 1)),
                        dt=0.1)
    with pytest.warns(sysid.errors.StabilityWarning) as rec:
        res = sysid.identify(data, refine=False, progress=False)
    text = " ".join(str(m.message) for m in rec
                    if "identify returns an unstable model" in str(m.message))
    f = float(np.angle(res.model.poles()[np.argmax(np.abs(res.model.poles()))]))
    assert re.search(r"a growing oscillation at ([0-9.]+) Hz \(pole pair of modulus 1\.01",
                     text), text
    hz = float(re.search(r"oscillation at ([0-9.]+) Hz", text).group(1))
    assert hz == pytest.approx(abs(f) / (2 * np.pi * 0.1), rel=1e-3)
    assert hz == pytest.approx(w / (2 * np.pi * 0.1), rel=0.02)
    assert re.search(r"held-out fit [0-9.]+ % against -?[0-9.]+ %", text), text


def test_identify_time_budget_keeps_the_subspace_sweep_and_says_it_stopped():
    est, _ = daisy_split("dryer")
    with pytest.warns(UserWarning, match="time_budget"):
        res = sysid.identify(est, time_budget=1e-3, progress=False)
    assert res.out_of_time and "time budget spent" in res.summary()
    fams = {r["family"] for r in res.leaderboard}
    assert {"moesp", "n4sid", "cva"} <= fams and res.model.is_stable()
    full = {r["family"] for r in quiet(sysid.identify, est, time_budget=None,
                                       progress=False).leaderboard}
    assert "pem" in full and "pem" not in fams
    with pytest.raises(sysid.errors.DataError, match="time_budget"):
        sysid.identify(est, time_budget=-1.0)


def test_identify_by_default_reads_no_clock(monkeypatch):
    # the default search is bounded in work, not seconds: on a busy machine (here a clock
    # that runs 1000 s per reading) it scores the same candidates and returns the same model
    # (with a 60 s CPU budget by default a 2 x 28 vibration record returned an unstable
    # subspace model under load and a stable refinement when idle)
    est, _ = daisy_split("dryer")
    idle = quiet(sysid.identify, est, progress=False)
    ticks = iter(range(10**9))
    monkeypatch.setattr(time, "process_time", lambda: 1000.0 * next(ticks))
    busy = quiet(sysid.identify, est, progress=False)
    assert not busy.out_of_time and busy.choice == idle.choice
    assert [r["held_out_fit"] for r in busy.leaderboard] == [
        r["held_out_fit"] for r in idle.leaderboard]
    assert "pem" in {r["family"] for r in busy.leaderboard}


def test_identified_model_is_validated_like_its_state_space_model():
    # compare, residuals and criteria ran identify's model (offsets kept with it) from rest
    # (a CD player arm record: 45.7 / -29.0 % against 70.0 / 82.9 % for its state-space
    # model), and its step response was the raw simulation from the offsets
    rng = np.random.default_rng(21)
    true = sysid.StateSpaceModel([[0.95, 0.1], [0.0, 0.8]], [[0.2], [1.0]], [[1.0, 0.0]])
    u = rng.standard_normal((800, 1))
    y = true.simulate(u, x0=[30.0, 0.0]) + 0.02 * rng.standard_normal((800, 1))
    d = sysid.IOData(u + 5.0, y + 50.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(d.slice(0, 500), refine=False)
    m, val = res.model, d.slice(500, 800)
    inner = sysid.compare(m.remove_offsets(val), m.statespace).fit
    np.testing.assert_allclose(sysid.compare(val, m).fit, inner, atol=1e-9)
    raw = sysid.compare(val, m)
    # in the record's units (a deviation model's would sit near 0, 50 below): within the
    # output's spread (the offsets are the estimation part's means, its start transient in)
    assert abs(raw.yhat[0].mean() - val.y.mean()) < val.y.std()
    e1, e2 = sysid.residuals(m, val).e, sysid.residuals(m.statespace, m.remove_offsets(val)).e
    np.testing.assert_allclose(np.asarray(e1), np.asarray(e2), atol=1e-9)
    np.testing.assert_allclose(sysid.step(m, 5).y, sysid.step(m.statespace, 5).y)
    a, b = sysid.stepinfo(m), sysid.stepinfo(m.statespace)  # (a pole at 1.0005 here: NaN)
    for k in ("steady_state", "rise_time", "settling_time", "overshoot", "peak"):
        np.testing.assert_allclose(getattr(a, k), getattr(b, k))
    H, sd = m.freqresp([0.1, 1.0], std=True)
    assert sd.shape == H.shape


def test_identify_result_is_accepted_where_a_model_is():
    # compare(val, sysid.identify(est)) refused the result ("IdentifyResult lacks simulate,
    # predict, ..."): a user's first call after identify; its model is what they mean
    rng = np.random.default_rng(23)
    u = rng.standard_normal((700, 1))
    y = sysid.StateSpaceModel([[0.9, 0.2], [0.0, 0.7]], [[0.0], [1.0]], [[1.0, 0.0]]).simulate(u)
    d = sysid.IOData(u, y + 0.02 * rng.standard_normal((700, 1)), dt=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(d.slice(0, 500), refine=False)
    val = d.slice(500, 700)
    want = sysid.compare(val, res.model).fit
    np.testing.assert_array_equal(sysid.compare(val, res).fit, want)
    np.testing.assert_array_equal(sysid.compare(res, val).fit, want)
    np.testing.assert_array_equal(sysid.compare(val, res, res.model).fit[0], want)
    e = sysid.residuals(res.model, val).e
    np.testing.assert_array_equal(np.asarray(sysid.residuals(res, val).e), np.asarray(e))
    np.testing.assert_array_equal(np.asarray(sysid.residuals(val, res).e), np.asarray(e))
    np.testing.assert_array_equal(sysid.damp(res).wn, sysid.damp(res.model).wn)
    with pytest.raises(sysid.DataError, match="lacks simulate"):
        sysid.compare(val, object())


def test_forecast_of_the_identified_model_is_in_raw_units():
    # forecast would take identify's model through its state-space form (the deviations)
    # and continue raw data as if they were deviations
    rng = np.random.default_rng(22)
    u = rng.standard_normal((600, 1))
    y = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]]).simulate(u)
    y = y + 0.05 * rng.standard_normal((600, 1))
    d = sysid.IOData(u + 5.0, y + 50.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(d.slice(0, 500), refine=False)
    f = sysid.forecast(res.model, d.slice(0, 500), 5, future_inputs=u[500:505] + 5.0)
    np.testing.assert_allclose(f.mean, y[500:505] + 50.0, atol=0.3)


def test_identify_says_a_record_is_too_short_before_checking_its_channels():
    """On 1 sample identify said "input u0 is 0 in every sample", and a 1-sample validation
    record "output y0 is constant": the length is checked first, with the numbers."""
    with pytest.raises(sysid.InsufficientDataError, match=r"too short to hold out a part for "
                       r"the choice \(1 sample; two held-out blocks of 20 need 40\)"):
        sysid.identify(sysid.IOData(u=np.array([0.0]), y=np.array([2.0])))
    rng = np.random.default_rng(0)
    u = rng.standard_normal(200)
    y = np.convolve(u, [0.0, 1.0, 0.5])[:200] + 0.01 * rng.standard_normal(200)
    with pytest.raises(sysid.InsufficientDataError, match=r"\(39 samples; two held-out"):
        sysid.identify(sysid.IOData(u=u[:39], y=y[:39]))
    # 5 random samples change "at samples 1, 2, 3, 4 only": identify called them a step test
    # that "no process model fitted stably" (NumericalError)
    with pytest.raises(sysid.InsufficientDataError, match=r"\(5 samples; two held-out"):
        sysid.identify(sysid.IOData(u=u[:5], y=y[:5]))
    with pytest.raises(sysid.InsufficientDataError, match=r"validation record is too short "
                       r"\(1 sample"):
        sysid.identify(sysid.IOData(u=u, y=y), validation=sysid.IOData(u=u[:1], y=y[:1]))


def test_identify_says_what_a_short_record_of_many_channels_needs():
    """57 samples of 5 inputs and 2 outputs (the size of DaISy's Lake Erie record): each
    part fitted without one held-out block (29 samples) is too short for a subspace window,
    and identify raised the subspace estimator's own error, "use a longer record or a
    smaller horizon", about a horizon the user never chose. It now says what identify needs
    and what to do; a record of that length is accepted."""
    rng = np.random.default_rng(3)
    u = rng.standard_normal((62, 5))
    y = np.column_stack([np.convolve(u[:, 0], [0.0, 1.0, 0.5])[:62],
                         np.convolve(u[:, 1] + u[:, 2], [0.0, 1.0, 0.3])[:62]])
    y = y + 0.05 * rng.standard_normal((62, 2))
    with pytest.raises(sysid.InsufficientDataError, match=r"too short for identify with 5 "
                       r"input\(s\) and 2 output\(s\).* at least 31 samples .* here has 29 "
                       r"\(the record: 57 samples\); pass a longer record \(about 62 samples"):
        sysid.identify(sysid.IOData(u=u[:57], y=y[:57]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(sysid.IOData(u=u, y=y))
    assert np.isfinite(res.model.simulate(u)).all()
