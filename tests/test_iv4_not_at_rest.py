"""iv4 on records that do not start at rest: the prefiltered (fourth) stage's sums start after
the prefilter's start-up in every experiment, so noise-free data give the system exactly.

The prefilter of stage 3 is a moving average of order ``p`` (the number of parameters of the
equation) run from rest: its first ``p`` outputs lack the samples before the record, and the
rows built from them have an equation error that is not zero. Used in the sums, they biased
the estimate by about 5e-4 on noise-free data (where least squares is exact)."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

import sysid


def test_siso_noise_free_record_cut_from_a_longer_run():
    """a was off by [-4.8e-4, 4.3e-4]; now to round-off (arx: 1e-16)."""
    u = np.random.default_rng(0).standard_normal(3200)
    y = lfilter([0, 0.1, 0.05], [1, -1.8, 0.85], u)
    d = sysid.IOData(u[200:, None], y[200:, None], 1.0)
    m = sysid.iv4(d, 2, 2, 1)
    np.testing.assert_allclose(m.a[0][0], [-1.8, 0.85], rtol=0, atol=1e-10)
    np.testing.assert_allclose(m.b[0][0], [0.1, 0.05], rtol=0, atol=1e-10)
    assert m.noise_variance[0] < 1e-20


def test_mimo_noise_free_experiments_cut_from_longer_runs():
    """A 2 x 2 coupled ARX system, two experiments each cut from the middle of a run."""
    def run(n, cut, seed):
        rng = np.random.default_rng(seed)
        u = rng.standard_normal((n, 2))
        y = np.zeros((n, 2))
        for t in range(2, n):
            y[t, 0] = 0.6 * y[t - 1, 0] - 0.2 * y[t - 1, 1] + u[t - 1, 0] + 0.3 * u[t - 2, 1]
            y[t, 1] = (0.1 * y[t - 1, 0] + 0.5 * y[t - 1, 1] + 0.7 * u[t - 1, 1]
                       - 0.4 * u[t - 1, 0])
        return u[cut:], y[cut:]

    (ua, ya), (ub, yb) = run(1500, 500, 1), run(1000, 300, 2)
    d = sysid.IOData([ua, ub], [ya, yb], 1.0)
    m = sysid.iv4(d, [[1, 1], [1, 1]], [[1, 1], [1, 1]], [[1, 2], [1, 1]])
    np.testing.assert_allclose(m.parameters[0], [-0.6, 0.2, 1.0, 0.3], rtol=0, atol=1e-10)
    np.testing.assert_allclose(m.parameters[1], [-0.1, -0.5, -0.4, 0.7], rtol=0, atol=1e-10)


def test_miso_noise_free_record_not_at_rest():
    rng = np.random.default_rng(4)
    n = 2500
    u = rng.standard_normal((n, 2))
    y = (lfilter([0, 0.5], [1, -1.2, 0.5], u[:, 0])
         + lfilter([0, 0, 0.3, 0.2], [1, -1.2, 0.5], u[:, 1]))
    d = sysid.IOData(u[400:], y[400:, None], 1.0)
    m = sysid.iv4(d, 2, [[1, 2]], [[1, 2]])
    np.testing.assert_allclose(m.parameters[0], [-1.2, 0.5, 0.5, 0.3, 0.2], rtol=0,
                               atol=1e-10)
