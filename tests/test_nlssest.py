"""Neural state space: training improves on the linear start, seeds, save/load, errors."""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def _data(seed=0, n=1500):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    x = np.zeros(n + 1)
    for t in range(n):
        x[t + 1] = 0.8 * x[t] + 0.5 * np.tanh(2 * u[t])
    return sysid.IOData(u, x[:-1], 1.0)


def _fit(**kw):
    return sysid.nlssest(_data(), 1, hidden=8, epochs=20, learning_rate=1e-2, progress=False,
                         **kw)


def test_training_beats_linear_start_on_fresh_data():
    m = _fit()
    v = m.info["training"]["validation"]
    assert min(v) < 0.05 * v[0]
    test = _data(seed=3)
    lin = m.info["training"]["validation"][0]
    err = np.mean((m.simulate(test.u) - test.y) ** 2)
    assert err < 0.05 * lin


def test_same_seed_same_model_and_progress_can_stop():
    a, b = _fit(), _fit()
    np.testing.assert_array_equal(a.params, b.params)
    seen = []
    sysid.nlssest(_data(), 1, hidden=4, epochs=10, progress=lambda e, v, t: seen.append(e)
                  or e < 3)
    assert seen == [1, 2, 3]


def test_save_load_and_encoder(tmp_path):
    m = _fit()
    sysid.save_model(m, tmp_path / "m.npz")
    back = sysid.load_model(tmp_path / "m.npz")
    d = _data(seed=4)
    np.testing.assert_array_equal(back.simulate(d.u), m.simulate(d.u))
    x0 = m.initial_state(d.u[:100], d.y[:100])
    y = m.simulate(d.u[100:], x0=x0)
    assert np.mean((y - d.y[100:]) ** 2) < 0.01 * np.var(d.y)
    assert isinstance(m, sysid.Model) and "hidden" in repr(m)


def test_bad_input():
    d = _data()
    with pytest.raises(DataError, match="hidden"):
        sysid.nlssest(d, 1, hidden=0)
    with pytest.raises(DataError, match="validation"):
        sysid.nlssest(d, 1, validation=0.95)
    with pytest.raises(DataError, match="horizon"):
        sysid.nlssest(sysid.IOData(d.u[:50], d.y[:50], 1.0), 1, horizon=100)
