"""Warnings that fired for the wrong cause or stayed silent where due (benches/warning_audit.py,
benches/results/warning_audit.md): small Monte Carlo checks with binomial bounds."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.subspace.estimator import FEEDBACK_WARNING_LEVEL

TRUE = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.5]], [[1.0, 0.0]], dt=1.0)


def _open_loop(seed: int, n: int = 3000, offset: float = 0.0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 1))
    y = TRUE.simulate(u)
    y = y + 0.1 * y.std() * rng.standard_normal(y.shape)
    return sysid.IOData(u=u + offset * u.std(), y=y + offset * y.std(), dt=1.0)


def _closed_loop(seed: int, n: int = 3000, offset: float = 0.0) -> sysid.IOData:
    """u = r - 0.4 y(t-1) (measured, noisy output), r white."""
    rng = np.random.default_rng(seed)
    r, e = rng.standard_normal(n), 0.6 * rng.standard_normal(n)
    x, u, y = np.zeros(2), np.zeros(n), np.zeros(n)
    for t in range(n):
        y[t] = TRUE.C[0] @ x + e[t]
        u[t] = r[t] - (0.4 * y[t - 1] if t else 0.0)
        x = TRUE.A @ x + TRUE.B[:, 0] * u[t]
    return sysid.IOData(u=u[:, None] + offset * u.std(), y=y[:, None] + offset * y.std(), dt=1.0)


def _pvalue(data: sysid.IOData) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sysid.SubspaceEstimator(data).feedback_pvalue()


def test_offset_left_in_is_not_feedback():
    # open loop, offsets 20 x the variation: the subspace feedback test read the offset as
    # feedback in 20 of 20 records (uncentred regressions); its level is 1e-6
    hits = sum(_pvalue(_open_loop(k, offset=20.0)) < FEEDBACK_WARNING_LEVEL for k in range(20))
    assert hits <= 1


def test_feedback_with_offset_still_found():
    # the confirmation on the mean-removed record keeps the test's power: with the offset the
    # p-value is that of the zero-mean record, and the loop is found
    for k in range(4):
        raw, centred = _pvalue(_closed_loop(k, offset=20.0)), _pvalue(_closed_loop(k))
        assert raw < FEEDBACK_WARNING_LEVEL and abs(np.log10(raw / centred)) < 1.0


def test_n4sid_on_raw_record_names_the_offset_only():
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        sysid.n4sid(_open_loop(3, offset=20.0), 2)
    said = {x.category.__name__ for x in w}
    assert "OffsetWarning" in said and "FeedbackWarning" not in said


def _two_sines(seed: int, n: int = 1500) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    u = np.sin(0.3 * t) + np.sin(0.9 * t + 1.0)
    y = TRUE.simulate(u[:, None])
    y = y + 0.05 * y.std() * rng.standard_normal(y.shape)
    return sysid.IOData(u=u, y=y, dt=1.0)


@pytest.mark.parametrize("fit", [
    lambda d: sysid.oe(d, 3, 3, 1),
    lambda d: sysid.armax(d, 3, 3, 3, 1),
    lambda d: sysid.tfest(d, 3),
], ids=["oe", "armax", "tfest"])
def test_polynomial_fit_on_two_sines_warns(fit):
    # two sines excite order 4; these models need 6 (nb + nf, na + nb, n_poles + n_zeros + 1)
    # and were fitted silently
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        fit(_two_sines(0))
    msgs = [str(x.message) for x in w if issubclass(x.category, sysid.ExcitationWarning)]
    assert len(msgs) == 1 and "order 4 only" in msgs[0] and "needs order 6" in msgs[0]


def test_polynomial_excitation_check_silent_on_rich_inputs():
    # white, held PRBS, low-pass noise and a band-limited multisine of 40 lines: never
    rng = np.random.default_rng(1)
    n, t = 1200, np.arange(1200)
    e = rng.standard_normal(n + 100)
    low = np.zeros_like(e)
    for k in range(1, e.size):
        low[k] = 0.8 * low[k - 1] + e[k]
    lines = np.arange(1, 41)
    inputs = [rng.standard_normal(n), np.sign(rng.standard_normal(n // 3)).repeat(3),
              low[100:], np.cos(2 * np.pi * np.outer(t, lines) / 400 + lines ** 2).sum(1)]
    said = []
    for u in inputs:
        y = TRUE.simulate(u[:, None])
        d = sysid.IOData(u=u, y=y + 0.1 * y.std() * rng.standard_normal(y.shape), dt=1.0)
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            sysid.oe(d, 4, 4, 1)
            sysid.armax(d, 4, 4, 4, 1)
        said += [x for x in w if issubclass(x.category, sysid.ExcitationWarning)]
    assert not said


def test_tfest_cap_warns_only_short_of_the_minimum():
    # tfest warned whenever it stopped at max_iter, also one iteration short of a minimum it
    # had settled on; it now follows every other capped search's rule (warn_if_capped)
    rng = np.random.default_rng(0)
    u = rng.standard_normal((1000, 1))
    y = TRUE.simulate(u)
    d = sysid.IOData(u=u, y=y + 0.1 * y.std() * rng.standard_normal(y.shape), dt=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.tfest(d, 2)
    init = sysid.TransferFunction([[np.asarray(m.num[0][0]) * 0.7]],
                                  [[np.asarray(m.den[0][0]) * np.array([1.0, 1.3, 0.8])]])
    full = sysid.tfest(d, 2, init=init)
    said = {}
    for cap in (1, 6):
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            capped = sysid.tfest(d, 2, max_iter=cap, init=init)
        assert capped.info["stop"] == ["maximum iterations"]
        said[cap] = [x for x in w if issubclass(x.category, sysid.IterationLimitWarning)]
        gap = sysid.compare(d, full).fit.mean() - sysid.compare(d, capped).fit.mean()
        assert (gap > 0.01) == bool(said[cap]), (cap, gap)
    assert said[1] and not said[6]
