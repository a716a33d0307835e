"""``sysid.compare`` of time-series polynomial models (AR, ARMA: no inputs)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


def ar2_record(n: int = 600, seed: int = 0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    e = rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(2, n):
        y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + e[t]
    return sysid.IOData(y=y)


@pytest.mark.parametrize("fit", [lambda d: sysid.ar(d, 2), lambda d: sysid.arma(d, 2, 1)])
def test_compare_takes_a_time_series_model(fit):
    data = ar2_record()
    m = fit(data)
    sim = sysid.compare(m, data)              # the free response from the fitted state
    pred = sysid.compare(data, m, horizon=1)  # one-step prediction
    assert np.isfinite(sim.mean_fit) and pred.mean_fit > 50
    both = sysid.compare(data, m, sysid.ar(data, 4), horizon=1)
    assert len(both) == 2 and not both.diverged.any()


def test_time_series_state_space_form_predicts_as_the_polynomials():
    data = ar2_record(seed=1)
    m = sysid.arma(data, 2, 1)
    ss = m.to_statespace()
    assert ss.ninputs == 0 and ss.nstates == 2 and ss.K.shape == (2, 1)
    np.testing.assert_allclose(np.sort_complex(ss.poles()), np.sort_complex(m.poles()))
    y = data.y
    np.testing.assert_allclose(ss.predict(np.zeros((y.shape[0], 0)), y, 1),
                               m.predict(np.zeros((y.shape[0], 0)), y, 1), atol=1e-9)
