"""nlssest's Hammerstein-Wiener start: embedded exactly, chosen by validation, init errors."""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _hw(order=3):
    fi = [sysid.SigmoidNetwork(2), sysid.Nonlinearity()]
    fi[0].params = np.array([0.3, 1.2, 0.1, -0.7, 0.5, -0.4])
    fo = [sysid.SigmoidNetwork(3), sysid.Nonlinearity()]
    fo[0].params = np.array([0.2, 0.8, 0.3, 0.5, -1.5, 1.0, -0.3, 0.4, -0.2])
    rng = np.random.default_rng(order)
    A = np.array([[0.9, 0.2, 0.0], [-0.2, 0.9, 0.0], [0.0, 0.1, 0.5]])[:order, :order]
    return sysid.HammersteinWienerSSModel(fi, fo, A, rng.standard_normal((order, 2)),
                                          rng.standard_normal((2, order)), dt=1.0)


def _record(hw, n=1200, seed=1):
    # inputs and outputs far from zero mean and unit scale: the embedding must carry the
    # channel offsets and scales of the neural model's scaled channels
    rng = np.random.default_rng(seed)
    u = np.column_stack([2 * rng.standard_normal(n) + 1, rng.uniform(3, 5, n)])
    y = hw.simulate(u) + np.array([10.0, -3.0]) + 0.01 * rng.standard_normal((n, 2))
    return u, sysid.IOData(u, y, 1.0)


def test_hammerstein_wiener_start_simulates_as_the_model():
    hw = _hw()
    u, d = _record(hw)
    m = sysid.nlssest(d, 3, init=hw, epochs=0, progress=False)
    assert m.info["start"] == "hammerstein-wiener" and m.info["training"]["best_epoch"] == 0
    ref = hw.simulate(u)
    assert np.max(np.abs(m.simulate(u) - ref)) < 1e-9 * np.max(np.abs(ref))
    # a direct term of an identity input channel is linear: embedded too
    lin_in = sysid.HammersteinWienerSSModel([sysid.Nonlinearity()] * 2, hw.output_nls, hw.A,
                                            hw.B, hw.C, [[0.5, -0.2], [0.0, 0.3]], dt=1.0)
    m = sysid.nlssest(d, 3, init=lin_in, epochs=0, progress=False)
    assert np.max(np.abs(m.simulate(u) - lin_in.simulate(u))) < 1e-9


@pytest.mark.filterwarnings("ignore::sysid.IterationLimitWarning")  # a short nlhw_ss fit
def test_start_with_an_operating_point_simulates_as_the_model():
    # nlhw_ss keeps the record's means as its operating point (u_offset, y_offset) when they
    # lie off zero: the embedded start must map u - u_offset and add y_offset as it does
    hw = _hw()
    u, d = _record(hw)
    hw.u_offset, hw.y_offset = np.array([1.5, 4.0]), np.array([10.0, -3.0])
    m = sysid.nlssest(d, 3, init=hw, epochs=0, progress=False)
    ref = hw.simulate(u)
    assert np.max(np.abs(m.simulate(u) - ref)) < 1e-9 * np.max(np.abs(ref))
    # as fitted: nlhw_ss centres a record whose means lie off zero
    fit = sysid.nlhw_ss(d, 3, input_nl=sysid.SigmoidNetwork(3),
                        output_nl=sysid.SigmoidNetwork(3), max_iter=3, progress=False)
    assert np.any(fit.u_offset != 0) and np.any(fit.y_offset != 0)
    m = sysid.nlssest(d, 3, init=fit, epochs=0, progress=False)
    assert np.max(np.abs(m.simulate(u) - fit.simulate(u))) < 1e-9 * np.max(np.abs(ref))


def test_auto_picks_the_start_that_validates_better():
    # a Hammerstein plant (tanh input): the sigmoid Hammerstein-Wiener start beats the linear
    # one on the held-out end, and training never returns worse than the chosen start
    rng = np.random.default_rng(0)
    u = rng.standard_normal(1500)
    x = np.zeros(1501)
    for t in range(1500):
        x[t + 1] = 0.8 * x[t] + 0.5 * np.tanh(2 * u[t])
    d = sysid.IOData(u, x[:-1], 1.0)
    m = sysid.nlssest(d, 1, hidden=8, epochs=5, progress=False)
    sv = m.info["start_validation"]
    assert set(sv) == {"linear", "hammerstein-wiener"}
    assert sv["hammerstein-wiener"] < 0.05 * sv["linear"]
    assert m.info["start"] == "hammerstein-wiener"
    v = m.info["training"]["validation"]
    assert v[0] == pytest.approx(sv["hammerstein-wiener"], rel=1e-12)
    assert min(v) <= v[0]
    # no room for its units (hidden=2 < 3): only the linear start
    m = sysid.nlssest(d, 1, hidden=2, epochs=1, progress=False)
    assert set(m.info["start_validation"]) == {"linear"}


@pytest.mark.filterwarnings("ignore::sysid.IterationLimitWarning")  # few epochs, for speed
def test_save_load_round_trip(tmp_path):
    hw = _hw()
    u, d = _record(hw)
    m = sysid.nlssest(d, 3, init=hw, epochs=2, progress=False)
    sysid.save_model(m, tmp_path / "m.npz")
    back = sysid.load_model(tmp_path / "m.npz")
    np.testing.assert_array_equal(back.simulate(u), m.simulate(u))
    assert back.info["start"] == "hammerstein-wiener"


def test_bad_init():
    hw = _hw()
    _, d = _record(hw, n=400)
    for bad in ("hw", 3, [1.0]):
        with pytest.raises(DataError, match="init must be"):
            sysid.nlssest(d, 3, init=bad, epochs=0, progress=False)
    with pytest.raises(DataError, match="states"):
        sysid.nlssest(d, 2, init=hw, epochs=0, progress=False)
    sat = _hw()
    sat.input_nls = [sysid.Saturation(), sysid.Nonlinearity()]
    with pytest.raises(DataError, match="SigmoidNetwork"):
        sysid.nlssest(d, 3, init=sat, epochs=0, progress=False)
    with pytest.raises(DataError, match="at least 2 units"):
        sysid.nlssest(d, 3, init=hw, hidden=1, epochs=0, progress=False)
    with pytest.raises(DataError, match="output network"):
        sysid.nlssest(d, 3, init=hw, output_hidden=None, epochs=0, progress=False)
    fed = sysid.HammersteinWienerSSModel(hw.input_nls, hw.output_nls, hw.A, hw.B, hw.C,
                                         np.ones((2, 2)), dt=1.0)
    with pytest.raises(DataError, match="direct term"):
        sysid.nlssest(d, 3, init=fed, epochs=0, progress=False)


def _hammerstein(n=1500):
    rng = np.random.default_rng(0)
    u = rng.standard_normal(n)
    x = np.zeros(n + 1)
    for t in range(n):
        x[t + 1] = 0.8 * x[t] + 0.5 * np.tanh(2 * u[t])
    return u, sysid.IOData(u, x[:-1], 1.0)


@pytest.mark.filterwarnings("ignore::sysid.IterationLimitWarning")  # few epochs, for speed
def test_auto_trains_from_both_starts_and_keeps_where_training_ends_lower():
    # the start's own validation need not rank where its training ends: both starts are
    # trained (each as it would be alone) and the lower held-out error at the best epoch wins
    u, d = _hammerstein()
    kw = dict(hidden=8, epochs=4, progress=False)
    m = sysid.nlssest(d, 1, **kw)
    runs = m.info["starts"]
    assert set(runs) == {"linear", "hammerstein-wiener"}
    best = {k: r["validation"][r["best_epoch"]] for k, r in runs.items()}
    assert min(best.values()) == best[m.info["start"]]
    assert m.info["training"] == runs[m.info["start"]]
    for k, r in runs.items():  # epoch 0 of each training is its start's validation error
        assert r["validation"][0] == pytest.approx(m.info["start_validation"][k], rel=1e-12)
    alone = sysid.nlssest(d, 1, init="linear", **kw)
    assert alone.info["training"] == runs["linear"]
    assert best[m.info["start"]] <= alone.info["training"]["validation"][
        alone.info["training"]["best_epoch"]]


def test_auto_stops_every_training_when_progress_says_so():
    _, d = _hammerstein()
    calls = []

    def stop(epoch, val, train):
        calls.append(epoch)
        return False

    m = sysid.nlssest(d, 1, hidden=8, epochs=4, progress=stop)
    assert len(calls) == 1 and len(m.info["starts"]) == 1
    assert m.info["training"]["stop"] == "cancelled"
