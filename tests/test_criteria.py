"""Information criteria and order selection."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid import _sysid
from sysid.validation.criteria import CRITERIA, Criteria, n_parameters

needs_engine = pytest.mark.skipif(not hasattr(_sysid, "Subspace"),
                                  reason="the subspace engine is not in this build yet")


def test_parameter_count():
    # n (2 l + m) + l m: A, B, C, K minus the n^2 of the state basis, plus D
    assert n_parameters(4, 1, 1) == 4 * 3 + 1
    assert n_parameters(3, 2, 3) == 3 * (6 + 2) + 6
    assert n_parameters(3, 2, 3, feedthrough=False) == 24
    assert n_parameters(3, 2, 3, noise_model=False) == 3 * (3 + 2) + 6
    assert n_parameters(3, 2, 3, x0=True, n_experiments=2) == 30 + 6


def test_criteria_formulas():
    c = Criteria(np.log(0.01), 10, 500)
    assert c.aic == pytest.approx(500 * np.log(0.01) + 20)
    assert c.aicc == pytest.approx(c.aic + 2 * 10 * 11 / (500 - 11))
    assert c.bic == pytest.approx(500 * np.log(0.01) + 10 * np.log(500))
    assert c.fpe == pytest.approx(0.01 * (1 + 10 / 500) / (1 - 10 / 500))
    many = Criteria(0.0, 600, 500)
    assert np.isinf(many.fpe) and np.isinf(many.aicc)
    assert "AIC" in repr(c)


def test_criteria_of_a_model_penalise_extra_parameters():
    rng = np.random.default_rng(0)
    m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]], [[0.5]], K=[[0.3]])
    u = rng.standard_normal(800)
    y = m.simulate(u) + 0.1 * rng.standard_normal((800, 1))
    c = sysid.criteria(m, (u, y))
    assert c.n_params == n_parameters(1, 1, 1, x0=True)
    assert c.loss == pytest.approx(np.var(y - m.predict(u, y, 1, sysid.estimate_x0(m, u, y, 1))),
                                   rel=0.05)
    c2 = sysid.criteria(m, (u, y), n_params=c.n_params + 5)
    assert c2.aic == pytest.approx(c.aic + 10) and c2.bic > c.bic
    zero = sysid.criteria(m, (u, y), x0="zero")
    assert zero.n_params == c.n_params - 1


def test_regularised_loss_on_exact_data():
    m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    u = np.random.default_rng(1).standard_normal(300)
    c = sysid.criteria(m, (u, m.simulate(u)), resolution=1e-6)
    # the floor is (resolution * rms(y))^2: round-off does not count as information
    assert c.loss == pytest.approx(1e-12 * np.mean(m.simulate(u) ** 2), rel=1e-3)


def order6_system(seed=0):
    rng = np.random.default_rng(seed)
    A = np.zeros((6, 6))
    for k, (r, f) in enumerate([(0.95, 0.05), (0.9, 0.15), (0.85, 0.3)]):
        p = r * np.exp(2j * np.pi * f)
        A[2 * k: 2 * k + 2, 2 * k: 2 * k + 2] = [[p.real, -p.imag], [p.imag, p.real]]
    return sysid.StateSpaceModel(A, rng.standard_normal((6, 2)), rng.standard_normal((2, 6)),
                                 rng.standard_normal((2, 2)))


@needs_engine
def test_noise_free_order_6_is_picked_by_every_rule():
    true = order6_system()
    rng = np.random.default_rng(2)
    u, uv = rng.standard_normal((1000, 2)), rng.standard_normal((500, 2))
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=true.simulate(u)), horizon=8)
    sel = sysid.select_order(est, validation=(uv, true.simulate(uv)))
    assert sel.picks == {"aic": 6, "aicc": 6, "bic": 6, "fpe": 6, "svd": 6, "validation": 6}
    assert sel.order == 6 and "validation" in sel.reason
    orders = sorted(r["order"] for r in sel.rows)
    assert orders[0] == 1 and orders[-1] >= 6
    np.testing.assert_allclose(np.sort_complex(sel.model().poles()),
                               np.sort_complex(true.poles()), atol=1e-8)
    # without validation data, the rule of order="auto" decides (held-out blocks of the
    # estimation record), and it too finds 6; BIC stays one call away
    alone = sysid.select_order(est)
    assert alone.criterion == "cv" and alone.order == 6 and alone.picks["cv"] == 6
    assert all(np.isfinite(r["fit_held_out"]) for r in alone.rows if r["order"] <= 6)
    assert sysid.select_order(est, criterion="bic").order == 6


@needs_engine
def test_cv_falls_back_and_says_so_where_the_record_cannot_be_split():
    rng = np.random.default_rng(3)
    u = rng.standard_normal(20)
    y = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]).simulate(u)[:, 0] + 0.01 * u
    sel = sysid.select_order(sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), 2), [1],
                             criterion="cv")
    assert sel.criterion == "bic" and "could not be cross-validated" in sel.reason
    assert "cv" not in sel.picks


@needs_engine
def test_dryer_order_selection_picks_4_or_5_and_explains():
    d = sysid.datasets.load_dryer()
    est_data = sysid.IOData(u=d.u[:500], y=d.y[:500], dt=d.dt)
    val = sysid.IOData(u=d.u[500:], y=d.y[500:], dt=d.dt)
    sel = sysid.select_order(est_data, horizon=15, validation=val)
    assert sel.order in (4, 5), repr(sel)
    assert sel.picks["bic"] in (4, 5)
    assert f"order {sel.order}" in sel.reason and "validation fit" in sel.reason
    assert "Votes" in sel.reason and "BIC -> " in sel.reason
    df = sel.to_pandas()
    assert {"order", "aic", "bic", "fit_validation", "stable"} <= set(df.columns)
    assert len(df) == len(sel.rows)
    # reusing one compression for several weightings
    est = sysid.SubspaceEstimator(est_data, horizon=15)
    both = sysid.select_order(est, range(1, 8), methods=["moesp", "n4sid"], validation=val,
                              criterion="bic")
    assert {r["method"] for r in both.rows} == {"moesp", "n4sid"}
    assert set(both.singular_values) == {"moesp", "n4sid"}
    assert both.criterion == "bic" and both.order == both.picks["bic"]


@needs_engine
def test_order_selection_plots_and_stabilisation_diagram():
    plt = pytest.importorskip("matplotlib.pyplot")
    true = order6_system(3)
    u = np.random.default_rng(4).standard_normal((600, 2))
    sel = sysid.select_order(sysid.IOData(u=u, y=true.simulate(u)), horizon=6)
    fig = sel.plot()
    assert len(fig.axes) == 3
    ax = sel.stabilization_plot()
    assert len(ax.lines) > 0
    orders = [o for o, _ in sel.damping()]
    assert orders == sorted(orders)
    plt.close("all")


@needs_engine
def test_order_selection_bad_input():
    rng = np.random.default_rng(5)
    data = sysid.IOData(u=rng.standard_normal((300, 1)), y=rng.standard_normal((300, 1)))
    est = sysid.SubspaceEstimator(data, horizon=5)
    with pytest.raises(sysid.DataError, match="larger than the horizon allows"):
        sysid.select_order(est, [1, est.max_order + 1])
    with pytest.raises(sysid.DataError, match="every entry of orders must be a positive integer"):
        sysid.select_order(est, [0])
    with pytest.raises(sysid.DataError, match="empty"):
        sysid.select_order(est, [])
    with pytest.raises(sysid.DataError, match="unknown method"):
        sysid.select_order(est, [1], methods=["pem"])
    with pytest.raises(sysid.DataError, match="not available"):
        sysid.select_order(est, [1, 2], criterion="validation")
    with pytest.raises(sysid.DataError, match="IOData or SubspaceEstimator"):
        sysid.select_order(np.zeros((10, 2)))
    with pytest.raises(sysid.ShapeError, match="input"):
        sysid.select_order(est, [1], validation=(np.zeros((50, 2)), np.zeros((50, 1))))
    assert set(CRITERIA) == {"aic", "aicc", "bic", "fpe"}


def test_the_horizon_follows_the_orders_asked_for():
    # select_order(data, range(1, 9)) on a 200-sample record refused order 5 ("larger than
    # the horizon allows (4)") though the data hold it; n4sid(data, 8) fits it
    rng = np.random.default_rng(6)
    true = sysid.StateSpaceModel(np.diag([0.9, 0.6, -0.5, 0.3, 0.1]), np.ones((5, 1)),
                                 np.ones((1, 5)))
    u = rng.standard_normal((200, 1))
    data = sysid.IOData(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal((200, 1)))
    assert sysid.SubspaceEstimator(data).max_order < 8
    sel = sysid.select_order(data, range(1, 9))
    assert sorted({r["order"] for r in sel.rows}) == list(range(1, 9))
    assert sel.order >= 4 and sysid.n4sid(data, 8).nstates == 8
    with pytest.raises(sysid.DataError, match="larger than the horizon allows"):
        sysid.select_order(sysid.IOData(u=u[:40], y=data.y[:40]), range(1, 30))


@needs_engine
def test_order_selection_from_a_factor_uses_the_gap():
    true = order6_system(6)
    u = np.random.default_rng(7).standard_normal((600, 2))
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=true.simulate(u)), horizon=6)
    bare = sysid.SubspaceEstimator.from_factor(est.factor)
    sel = sysid.select_order(bare, range(1, 7))
    assert sel.criterion == "svd" and sel.order == 6
    assert np.isnan(sel.rows[0]["aic"])  # no data, no criteria


@needs_engine
def test_sweep_settings_change_the_table():
    d = sysid.datasets.load_dryer()
    est = sysid.SubspaceEstimator(sysid.IOData(u=d.u[:500], y=d.y[:500], dt=d.dt), horizon=15)
    val = sysid.IOData(u=d.u[500:], y=d.y[500:], dt=d.dt)
    base = sysid.select_order(est, range(1, 8), validation=val)
    # a looser tolerance lets a smaller order win; zero tolerance takes the best fit
    loose = sysid.select_order(est, range(1, 8), validation=val, fit_tol=5.0)
    strict = sysid.select_order(est, range(1, 8), validation=val, fit_tol=0.0)
    assert loose.order < base.order <= strict.order
    best = max(r["fit_validation"] for r in strict.rows)
    assert strict.model().info["order"] == strict.order
    assert [r["fit_validation"] for r in strict.rows if r["order"] == strict.order] == [best]
    # the parameter count follows the model structure
    lean = sysid.select_order(est, [4], x0="zero", feedthrough=False, kalman=False)
    assert lean.rows[0]["n_params"] == n_parameters(4, 1, 1, feedthrough=False,
                                                   noise_model=False)
    assert base.rows[3]["n_params"] == n_parameters(4, 1, 1, feedthrough=False, x0=True)
    assert lean.model().K is None and np.all(lean.model().D == 0)


def test_select_order_ranks_time_series_models_by_their_one_step_predictions():
    # an AR(4) series: simulated from its past alone every AR model "fits" about 0 %, so the
    # ranking by validation recommended AR(1) against every criterion's vote for 4; a time
    # series is validated on its one-step predictions, as the subspace sweep does
    from scipy import signal

    a = np.poly([0.95 * np.exp(0.5j), 0.95 * np.exp(-0.5j), 0.6 * np.exp(2j),
                 0.6 * np.exp(-2j)]).real
    y = signal.lfilter([1.0], a, np.random.default_rng(0).standard_normal(6000))
    d, v = sysid.IOData(None, y[:4000], 1.0), sysid.IOData(None, y[4000:], 1.0)
    sel = sysid.select_order(d, models=[sysid.ar(d, k) for k in range(1, 9)], validation=v)
    assert sel.order == 4
    rows = sel.to_pandas().set_index("order")
    assert rows.loc[4, "fit_validation"] > rows.loc[1, "fit_validation"] + 10.0


@needs_engine
def test_docs_cv_block_chooses_without_the_validation_data():
    """docs/validation.md's select_order(criterion="cv") block: the printed orders hold."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "validation.md").read_text()
    block = next(b for b in re.findall(r"```python\n(.*?)```", text, flags=re.S)
                 if 'criterion="cv"' in b)
    d = sysid.datasets.load_dryer()
    ns = {"sysid": sysid, "val_data": sysid.IOData(u=d.u[500:], y=d.y[500:], dt=d.dt),
          "est": sysid.SubspaceEstimator(sysid.IOData(u=d.u[:500], y=d.y[:500], dt=d.dt),
                                         horizon=15)}
    exec(compile(block, "docs/validation.md[cv]", "exec"), ns)
    assert (ns["sel"].order, ns["sel"].picks["validation"]) == (4, 4)
    assert "only reported on" in ns["sel"].reason


def test_aic_and_fpe_give_matlabs_numbers():
    # MATLAB's documented examples: tfest(z1, 2) on 300 samples (4 coefficients and 2
    # initial states, loss 1.6575) and oe(z2, [1 3 2]) on 400 samples (4 coefficients)
    m = sysid.StateSpaceModel([[0.5, 0.1], [0.0, 0.3]], [[1.0], [0.5]], [[1.0, 0.0]],
                              noise_cov=[[1.6575]],
                              info={"pem": {"n_samples": 300, "x0": ["estimate"]}})
    assert sysid.aic(m) == pytest.approx(0.5453, abs=1e-4)
    assert sysid.aic(m, kind="nAIC") == sysid.aic(m)
    assert sysid.aic(m, kind="AIC") == pytest.approx(1.0150e3, abs=0.5)
    assert sysid.aic(m, kind="AICc") == pytest.approx(1.0153e3, abs=0.5)
    assert sysid.aic(m, kind="BIC") == pytest.approx(1.0372e3, abs=0.5)
    assert sysid.fpe(m) == pytest.approx(1.7252, abs=1e-4)
    oe = sysid.PolynomialModel([[[]]], [[[1.067]]], [[2]], 0.1,
                               f=[[[-1.824, 1.195, -0.2307]]], noise_variance=[0.9615])
    oe.info["n_samples"] = 400
    assert sysid.fpe(oe) == pytest.approx(0.9809, abs=1e-4)
    with pytest.raises(sysid.DataError, match="kind must be one of"):
        sysid.aic(m, kind="hqc")
    with pytest.raises(sysid.DataError, match="pass the estimation data"):
        sysid.aic(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))


def test_aic_on_data_is_criteria_with_matlabs_constants():
    rng = np.random.default_rng(4)
    m = sysid.StateSpaceModel([[0.9, 0.0], [0.0, 0.5]], [[1.0], [0.5]], [[1.0, 0.0], [0.0, 1.0]])
    u = rng.standard_normal(300)
    d = (u, m.simulate(u) + 0.1 * rng.standard_normal((300, 2)))
    c = sysid.criteria(m, d)
    const = 300 * 2 * (np.log(2 * np.pi) + 1)
    assert sysid.aic(m, d) == pytest.approx(c.log_loss + 2 * c.n_params / 300)
    assert sysid.aic(m, d, "aic") == pytest.approx(c.aic + const)
    assert sysid.aic(m, d, "aicc") == pytest.approx(c.aicc + const)
    # MATLAB's BIC constant is N (ny log(2 pi) + 1), as documented
    assert sysid.aic(m, d, "bic") == pytest.approx(c.bic + 300 * (2 * np.log(2 * np.pi) + 1))
    assert sysid.fpe(m, d) == pytest.approx(c.fpe)
    assert sysid.aic(m, d, x0="zero") < sysid.aic(m, d)  # no initial states to charge here
