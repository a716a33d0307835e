"""The initial conditions of ``arma`` and of ``pem`` given a polynomial model (MATLAB's
``InitialCondition``, the machinery of :mod:`sysid.polynomial.initial`): series and records
that start off rest, the old numbers with ``"zero"``, calibration on short series."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

import sysid
from sysid.errors import DataError

A3 = [-1.5, 0.7, -0.1]


def _free(h: list[float], n: int = 100, a: list[float] = A3) -> np.ndarray:
    """A noise-free series off rest: the free response of ``A`` to the initial pulses ``h``."""
    return lfilter([1.0], [1.0, *a], np.r_[h, np.zeros(n - len(h))])


@pytest.mark.parametrize("ic", ["estimate", "auto"])
def test_arma_recovers_a_noise_free_series_off_rest(ic: str) -> None:
    y = _free([1.0, -0.3, 0.4])
    zero = sysid.arma(y, 3, 1, initial_condition="zero")
    # from rest the start is an impulse of e through C/A: C of order 1 cannot shape it
    assert np.max(np.abs(zero.a[0][0] - A3)) > 1e-2
    m = sysid.arma(y, 3, 1, initial_condition=ic)
    np.testing.assert_allclose(m.a[0][0], A3, atol=1e-12)
    np.testing.assert_allclose(m.c[0], [0.0], atol=1e-12)  # C: no noise to model
    assert m.info["initial_condition"] == "estimate"
    # the state is h_e of C e = A y + h_e: with e = 0, y = -h_e / A
    h = np.asarray(m.info["initial_state"][0]["noise"])
    np.testing.assert_allclose(lfilter([1.0], [1.0, *m.a[0][0]], np.r_[-h, np.zeros(97)]), y,
                               atol=1e-10)


def test_arma_each_experiment_has_its_own_state() -> None:
    ys = [_free(h, n) for h, n in (([1.0, -0.3, 0.4], 80), ([0.2, 0.5, -1.0], 60))]
    d = sysid.IOData(None, [y[:, None] for y in ys], 1.0)
    m = sysid.arma(d, 3, 0)
    np.testing.assert_allclose(m.a[0][0], A3, atol=1e-12)
    assert len(m.info["initial_state"]) == 2
    zero = sysid.arma(d, 3, 0, initial_condition="zero")
    assert np.max(np.abs(zero.a[0][0] - A3)) > 1e-2


def _stationary(seed: int, n: int, a: list[float], c: list[float]) -> np.ndarray:
    """An ARMA series in steady state: ``C/A e`` with its first 300 samples dropped."""
    e = np.random.default_rng(seed).standard_normal(n + 300)
    return lfilter([1.0, *c], [1.0, *a], e)[300:]


def test_zero_reproduces_the_fits_from_rest() -> None:
    """The numbers of the code before ``initial_condition`` existed (computed with it)."""
    y = _stationary(21, 100, [-1.6, 0.8], [0.3])
    m = sysid.arma(y, 2, 1, initial_condition="zero")
    np.testing.assert_allclose(m.a[0][0], [-1.6699691126509726, 0.8667170218590288],
                               rtol=1e-12)
    np.testing.assert_allclose(m.c[0], [0.3714599841471868], rtol=1e-12)
    assert m.info["initial_condition"] == "zero"
    d = _armax_record()
    start = sysid.armax(d, 2, 2, 1, 1, max_iter=1, initial_condition="zero")
    m = sysid.pem(d, start, initial_condition="zero")
    np.testing.assert_allclose(m.a[0][0], [-1.199995820423482, 0.49708694920980534],
                               rtol=1e-12)
    np.testing.assert_allclose(m.b[0][0], [0.5007346285187623, 0.19934316875690963],
                               rtol=1e-12)
    np.testing.assert_allclose(m.c[0], [0.11154034279845493], rtol=1e-12)


def _armax_record() -> sysid.IOData:
    """ARMAX ``A y = B u(t-1) + C e``, C = 1 + 0.3 q^-1, from sample 100 of a run from rest."""
    rng = np.random.default_rng(22)
    u, e = rng.standard_normal(600), 0.05 * rng.standard_normal(600)
    y = lfilter([0, 0.5, 0.2], [1, -1.2, 0.5], u) + lfilter([1, 0.3], [1, -1.2, 0.5], e)
    return sysid.IOData(u[100:], y[100:], 1.0)


def test_pem_of_a_polynomial_model_estimates_the_initial_state() -> None:
    d = _armax_record()
    start = sysid.armax(d, 2, 2, 1, 1, max_iter=1, initial_condition="zero")
    zero = sysid.pem(d, start, initial_condition="zero")
    m = sysid.pem(d, start)  # "auto": the record starts mid-response
    assert m.info["initial_condition"] == "estimate"
    est = sysid.pem(d, start, initial_condition="estimate")
    np.testing.assert_array_equal(m.c[0], est.c[0])
    # from rest C soaks up the transient (0.11 for 0.3); with the state, within 2 std
    assert abs(zero.c[0][0] - 0.3) > 3 * zero.std["c"][0][0]
    assert abs(m.c[0][0] - 0.3) < 2 * m.std["c"][0][0]
    # noise-free and off rest: exact
    u = np.random.default_rng(5).standard_normal(160)
    y = lfilter([0, 0.5, 0.2], [1, -1.2, 0.5], u)
    dn = sysid.IOData(u[60:], y[60:], 1.0)
    start = sysid.armax(dn, 2, 2, 1, 1, initial_condition="zero")  # from rest: C = -0.31
    assert np.max(np.abs(start.a[0][0] - [-1.2, 0.5])) > 1e-8
    m = sysid.pem(dn, start)
    assert m.info["initial_condition"] == "estimate"
    np.testing.assert_allclose(m.a[0][0], [-1.2, 0.5], atol=1e-10)
    np.testing.assert_allclose(m.b[0][0], [0.5, 0.2], atol=1e-10)


def test_the_keyword_is_checked_and_only_for_polynomial_models() -> None:
    y = _free([1.0, -0.3, 0.4])
    with pytest.raises(DataError, match="'auto', 'zero' or 'estimate'"):
        sysid.arma(y, 3, 1, initial_condition="est")
    with pytest.raises(DataError, match="'backcast' is not offered"):
        sysid.arma(y, 3, 1, initial_condition="backcast")
    d = _armax_record()
    start = sysid.armax(d, 2, 2, 1, 1, max_iter=1)
    with pytest.raises(DataError, match="'auto', 'zero' or 'estimate'"):
        sysid.pem(d, start, initial_condition=None)
    ss = sysid.n4sid(d, 2)
    with pytest.raises(DataError, match="x0"):
        sysid.pem(d, ss, initial_condition="zero")


def test_arma_std_is_calibrated_on_short_series_off_rest() -> None:
    """600 ARMA(2, 1) series of 100 samples in steady state (poles of radius 0.89: the
    state before the record matters for some 40 samples). From rest ``C`` soaks up the
    start (bias 21 standard errors of the mean, the sample std 1.55 times the reported
    one, 95 % intervals covering 0.67); with ``"auto"`` (the state estimated on 386 of the
    600) the reported std is within 0.85-1.25 of the sample std (1.01, 0.99 and 1.13 for
    ``C``, a small-sample shortfall, 1.11 on 1000 other runs; the ratio's own sampling error
    3 % here), the intervals cover 0.88-0.99 (0.95, 0.95, 0.90; binomial sd 0.9 %) and
    ``C`` is unbiased (0.1 standard errors)."""
    a, c, runs = [-1.6, 0.8], [0.3], 600
    truth = np.r_[a, c]
    est, sd = np.empty((runs, 3)), np.empty((runs, 3))
    for s in range(runs):
        m = sysid.arma(_stationary(1000 + s, 100, a, c), 2, 1)
        est[s], sd[s] = np.r_[m.a[0][0], m.c[0]], m.uncertainty.std
    ratio = est.std(axis=0, ddof=1) / np.sqrt(np.mean(sd ** 2, axis=0))
    assert np.all((ratio > 0.85) & (ratio < 1.25)), ratio
    cover = (np.abs(est - truth) < 1.96 * sd).mean(axis=0)
    assert np.all((cover > 0.88) & (cover < 0.99)), cover
    se = est.std(axis=0, ddof=1) / np.sqrt(runs)
    assert abs(est[:, 2].mean() - c[0]) < 3 * se[2]
