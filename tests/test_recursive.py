"""Recursive subspace identification: equal to the batch estimate without forgetting,
tracking a drifting pole with forgetting."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


def test_each_update_equals_the_batch_estimate_without_forgetting():
    rng = np.random.default_rng(0)
    true = sysid.StateSpaceModel([[0.8, 0.2], [-0.2, 0.7]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 K=[[0.5], [0.1]])
    n = 3000
    u = rng.standard_normal(n)
    y = true.simulate(u) + sysid.StateSpaceModel(true.A, true.K, true.C, [[1.0]]).simulate(
        0.3 * rng.standard_normal(n))
    rs = sysid.RecursiveSubspace(order=2, horizon=6)
    cuts = [0, 5, 40, 500, 1300, 3000]
    for a, b in zip(cuts[:-1], cuts[1:]):
        model = rs.update(u[a:b], y[a:b])
        if b < 2 * 6 * 2 + 11:
            assert model is None
            continue
        batch = sysid.SubspaceEstimator(sysid.IOData(u=u[:b], y=y[:b]), 6).fit(
            2, feedthrough=False, kalman=False)
        np.testing.assert_allclose(model.markov(20), batch.markov(20), rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(np.sort_complex(model.poles()),
                                   np.sort_complex(batch.poles()), atol=1e-9)
    assert model.info["n_samples"] == n and model.info["effective_columns"] == n - 11


def test_forgetting_tracks_a_drifting_pole():
    rng = np.random.default_rng(1)
    n, chunk = 20_000, 500
    a = np.linspace(0.5, 0.85, n)  # the pole drifts slowly
    u = rng.standard_normal(n)
    e = 0.1 * rng.standard_normal(n)
    y = np.zeros(n)
    x = 0.0
    for t in range(n):
        y[t] = x + e[t]
        x = a[t] * x + u[t]
    tracked = sysid.RecursiveSubspace(order=1, horizon=4, forgetting=0.995)
    frozen = sysid.RecursiveSubspace(order=1, horizon=4)
    errs, errs_frozen = [], []
    for k in range(0, n, chunk):
        m1 = tracked.update(u[k:k + chunk], y[k:k + chunk])
        m2 = frozen.update(u[k:k + chunk], y[k:k + chunk])
        if k >= 2_000:
            now = a[k + chunk - 1]
            errs.append(abs(m1.poles()[0].real - now))
            errs_frozen.append(abs(m2.poles()[0].real - now))
    # memory about 200 samples: lag error about 200 * da/dt = 0.0035 plus noise
    assert max(errs) < 0.03, max(errs)
    assert errs_frozen[-1] > 0.1 and max(errs) < 0.3 * errs_frozen[-1]


def test_arguments_and_repr():
    with pytest.raises(sysid.DataError, match="forgetting"):
        sysid.RecursiveSubspace(1, 4, forgetting=1.2)
    rs = sysid.RecursiveSubspace(1, 4)
    with pytest.raises(sysid.InsufficientDataError):
        _ = rs.factor
    rs.update(np.ones(3), np.ones(3))
    with pytest.raises(sysid.DataError, match="chunks"):
        rs.update(np.ones((3, 2)), np.ones(3))
    assert "RecursiveSubspace(order=1" in repr(rs)
