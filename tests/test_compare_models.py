"""compare with several models (MATLAB's compare(z, m1, m2, ...)), and a model that diverges
on the validation data reported with fit -inf, not raised (issue 26)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


def _data(n=3000, seed=0):
    rng = np.random.default_rng(seed)
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 dt=0.1)
    u = rng.standard_normal(n)
    y = true.simulate(u) + 0.05 * rng.standard_normal((n, 1))
    return true, sysid.IOData(u=u, y=y, dt=0.1)


def test_a_diverging_model_is_reported_not_raised():
    true, data = _data()
    unstable = sysid.StateSpaceModel([[1.3]], [[1.0]], [[1.0]], dt=0.1)  # overflows on 3000
    with pytest.warns(sysid.StabilityWarning, match="diverged"):  # and said so
        r = sysid.compare(unstable, data)           # was: NumericalError
    assert r.diverged.tolist() == [True] and r.fit[0, 0] == -np.inf
    assert "diverged" in repr(r) and "diverged" in r.summary()
    assert bool(r.to_pandas()["diverged"].iloc[0])
    # prediction too, and a mildly unstable model that does not overflow but explodes
    mild = sysid.StateSpaceModel([[1.02]], [[1.0]], [[1.0]], dt=0.1)
    with pytest.warns(sysid.StabilityWarning, match="diverged"):
        assert sysid.compare(mild, data).diverged[0]
    with pytest.warns(sysid.StabilityWarning, match="diverged"):
        assert sysid.compare(unstable, data, horizon=5).fit[0, 0] == -np.inf


def test_a_continuous_model_unstable_within_one_sample_is_reported_not_raised():
    # tfest(spa(data), 2) on the winding record gave a pole at s = +2.7e7 rad/s; compare
    # raised "A has non-finite entries" from sampling it (exp(A dt) overflows) instead of
    # reporting the divergence
    _, data = _data()
    tf = sysid.TransferFunction([[[1.0]]], [[[1.0, -1e4]]])            # pole at s = +1e4
    ss = sysid.ContinuousStateSpace([[1e4]], [[1.0]], [[1.0]])
    for model in (tf, ss):
        with pytest.warns(sysid.StabilityWarning, match="diverged"):
            r = sysid.compare(data, model)
        assert r.diverged.tolist() == [True] and r.fit[0, 0] == -np.inf
        with pytest.raises(sysid.NumericalError, match="pole at s = 1e"):
            model.simulate(np.ones(5), dt=0.1)


def test_several_models_matlab_order():
    true, data = _data()
    good = sysid.n4sid(data, 2)
    worse = sysid.n4sid(data, 1)
    unstable = sysid.StateSpaceModel([[1.3]], [[1.0]], [[1.0]], dt=0.1)
    with pytest.warns(sysid.StabilityWarning, match="model 3: .* diverged"):
        cs = sysid.compare(data, good, worse, unstable)
    assert isinstance(cs, sysid.CompareSet) and len(cs) == 3
    assert cs.fit.shape == (3, 1, 1)
    np.testing.assert_allclose(cs.fit[0], sysid.compare(good, data).fit)
    np.testing.assert_allclose(cs.fit[1], sysid.compare(data, worse).fit)
    assert cs.fit[0, 0, 0] > cs.fit[1, 0, 0] > -np.inf and cs.fit[2, 0, 0] == -np.inf
    assert cs.diverged.tolist() == [False, False, True] and cs.best == 0
    text = cs.summary()
    assert "diverged" in text and "best" in text and text.count("\n") == 4
    assert "diverged" in repr(cs)
    df = cs.to_pandas()
    assert len(df) == 3 and list(df["diverged"]) == [False, False, True]
    assert df["model"].nunique() == 3
    # the same with predictions, keyword horizon
    cp = sysid.compare(data, good, worse, horizon=1)
    assert cp.kind == "1-step prediction" and cp.fit[0, 0, 0] > 90


def test_compare_set_plot():
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    true, data = _data(500)
    with pytest.warns(sysid.StabilityWarning, match="diverged"):
        cs = sysid.compare(data, sysid.n4sid(data, 2),
                           sysid.StateSpaceModel([[1.3]], [[1.0]], [[1.0]], dt=0.1))
    fig = cs.plot()
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels[0] == "measured" and any("diverged" in t for t in labels)


def test_bad_arguments_are_clear():
    true, data = _data(200)
    with pytest.raises(sysid.DataError, match="compare"):
        sysid.compare(true)
    with pytest.raises(sysid.DataError, match="at least one model"):
        sysid.compare(data)
    with pytest.raises(sysid.DataError, match="one record"):
        sysid.compare(data, true, data)
    # the old positional horizon still works
    assert sysid.compare(true, data, 1).kind == "1-step prediction"


def test_docs_validation_several_models_block_runs():
    """docs/validation.md's block on several models and pole uncertainty runs as shown."""
    import re
    import warnings
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "validation.md").read_text()
    block = next(b for b in re.findall(r"```python\n(.*?)```", text, flags=re.S)
                 if "cs = sysid.compare(" in b)
    ns: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sysid.StabilityWarning)
        exec(compile(block, "docs/validation.md[several models]", "exec"), ns)
    cs = ns["cs"]
    assert cs.diverged.tolist() == [False, False, True] and cs.best == 1
    assert [w.category for w in ns["said"]] == [sysid.StabilityWarning]
    assert set(ns["table"].std_method) == {"linear"}
    assert np.all(np.isfinite(ns["table"].wn_hz_std))


class _Squared(sysid.ModelMixin):
    """A Wiener model y = (G u)^2 + G u whose to_statespace() is its linear part G."""

    dt, ninputs, noutputs, n_parameters, info = 1.0, 1, 1, 3, {}
    input_names, output_names = ["u0"], ["y0"]

    def __init__(self):
        self.G = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])

    def to_statespace(self):
        return self.G

    def simulate(self, u, x0=None):
        z = self.G.simulate(np.asarray(u, float).reshape(-1, 1))
        return z + z ** 2

    def freqresp(self, omega):
        return self.G.freqresp(omega)


def test_compare_simulates_a_nonlinear_model_not_its_linear_part():
    """compare(model, data) with the default x0="estimate" simulated a model's
    to_statespace() in its place, to fit the initial state: for a nonlinear model that is
    its linear part (nlssest on a heat exchanger: -49.8 % instead of 80.9 %). A state-space
    form that does not reproduce the model's simulation, or a class that says so, is not
    used: the model itself is simulated, from rest."""
    rng = np.random.default_rng(0)
    model = _Squared()
    u = rng.standard_normal((300, 1))
    y = model.simulate(u)
    c = sysid.compare(model, sysid.IOData(u=u, y=y))
    assert np.allclose(c.fit, 100.0)  # the model itself, not G (which misses z^2)
    assert sysid.NeuralStateSpaceModel.statespace_is_exact is False
    assert sysid.PNLSSModel.statespace_is_exact is False
    assert sysid.NonlinearGreyBox.statespace_is_exact is False
    # a linear model's state-space form is still used for its initial state
    arx = sysid.arx(sysid.IOData(u=u, y=model.G.simulate(u)), 1, 1, 1)
    assert sysid.compare(arx, sysid.IOData(u=u[50:], y=model.G.simulate(u)[50:])).fit[0][0] > 99.9


def test_matlab_order_with_a_prediction_horizon():
    # MATLAB's compare(data, sys, K) raised "int lacks simulate, predict, ..."
    from scipy.signal import lfilter

    rng = np.random.default_rng(0)
    u = rng.standard_normal(300)
    y = lfilter([0, 0.5], [1, -0.8], u) + lfilter([1], [1, -0.9], 0.1 * rng.standard_normal(300))
    d = sysid.IOData(u, y, 1.0)
    m = sysid.armax(d, [1, 1, 1, 1])
    five = sysid.compare(d, m, horizon=5).fit
    np.testing.assert_array_equal(sysid.compare(d, m, 5).fit, five)
    np.testing.assert_array_equal(sysid.compare(d, m, np.inf).fit, sysid.compare(d, m).fit)
    both = sysid.compare(d, m, sysid.arx(d, [1, 1, 1]), 5)
    np.testing.assert_array_equal(both.fit[0], five)
    with pytest.raises(sysid.DataError, match="horizon given twice"):
        sysid.compare(d, m, 5, horizon=5)
