"""The polynomial estimators check their one-sample delay against the record's direct term
(sysid.polynomial.feedthrough): arx, oe, armax and bj with nk = 1 on a plant whose output
answers the input within the sample said nothing (the warning audit: 100/100 silent), where
ssest's default (no D) warned in 95/100."""

import warnings

import numpy as np
import pytest
from scipy import signal

import sysid

N = 1500


def _record(seed: int, d: float, coloured: bool = False, noise: float = 0.1):
    """y = (q^-1 + ... ) / (1 - 1.2 q^-1 + 0.5 q^-2) u + d u(t) + noise (white output noise)."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(2 * N)
    if coloured:  # a low-pass input, where u(t) is close to u(t - 1)
        u = signal.lfilter([0.2], [1, -0.8], u)
    y = signal.lfilter([0, 1.0, 0.5], [1, -1.2, 0.5], u) + d * u
    y = y + noise * np.std(y) * rng.standard_normal(2 * N)
    return sysid.IOData(u[:N, None], y[:N, None], 1.0), sysid.IOData(u[N:, None], y[N:, None], 1.0)


def _said(fit):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = fit()
    return m, [x for x in w if issubclass(x.category, sysid.FeedthroughWarning)]


CALLS = {
    "arx": lambda d, nk: sysid.arx(d, 2, 2, nk),
    "oe": lambda d, nk: sysid.oe(d, 2, 2, nk),
    "armax": lambda d, nk: sysid.armax(d, 2, 2, 1, nk),
    "bj": lambda d, nk: sysid.bj(d, 2, 1, 1, 2, nk),
}


@pytest.mark.parametrize("name", list(CALLS))
def test_a_direct_term_left_out_by_nk_1_is_said_and_nk_0_holds_it(name):
    est, val = _record(0, d=1.0)
    m1, said = _said(lambda: CALLS[name](est, 1))
    assert len(said) == 1, name
    text = str(said[0].message)
    assert "nk=0" in text and "y0" in text and "feedback within the sample" in text
    assert m1.info["feedthrough_check"]["ratio"] >= 2.0
    m0, said0 = _said(lambda: CALLS[name](est, 0))
    assert not said0 and "feedthrough_check" not in m0.info  # nk = 0: nothing left out
    # the warning is right: nk = 0 simulates the new record better, by many points
    fits = [float(sysid.compare(val, m).fit[0, 0]) for m in (m1, m0)]
    assert fits[1] > fits[0] + 10, fits


@pytest.mark.parametrize("coloured", [False, True])
@pytest.mark.parametrize("name", ["arx", "oe"])
def test_no_direct_term_no_warning_whatever_the_input(name, coloured):
    # strictly proper plants under white and low-pass inputs, 10 records each: the check's
    # ratio stays near 1 (u(t) is independent of the sample's noise), never at 2
    ratios = []
    for seed in range(10):
        est, _ = _record(seed, d=0.0, coloured=coloured, noise=0.3)
        m, said = _said(lambda est=est: CALLS[name](est, 1))
        assert not said, (name, seed, str(said[0].message))
        check = m.info["feedthrough_check"]
        ratios.append(max(check["ratio"], check.get("subspace_ratio", 0.0)))
        assert ("subspace_ratio" in check) == (name == "oe")  # arx: the ARX check only
    assert max(ratios) < 1.3, ratios


def test_a_channel_with_a_deliberate_delay_is_not_checked():
    est, _ = _record(1, d=1.0)
    m, said = _said(lambda: sysid.arx(est, 2, 2, 2))
    assert not said and "feedthrough_check" not in m.info


def test_arxstruc_scores_nk_rather_than_warning_per_row():
    est, val = _record(2, d=1.0)
    nn = sysid.struc([2], [2], [0, 1, 2])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        v = sysid.arxstruc(est, val, nn)
    # the table itself shows the direct term: nk = 0 has the smallest loss
    assert int(v[np.argmin(v[:, 3]), 2]) == 0


@pytest.mark.parametrize("kw", [{"dt": 1.0}, {}])
def test_tfest_s_one_sample_lag_is_checked_in_its_own_words(kw):
    # discrete tfest (feedthrough=False, a one-sample lag) and a strictly proper continuous
    # tfest cannot answer within the sample either; they said nothing
    est, _ = _record(3, d=1.0)
    est = sysid.IOData(est.u, est.y, 1.0)
    G, said = _said(lambda: sysid.tfest(est, 2, **kw))
    assert len(said) == 1  # tfest's own, not also the oe it runs inside
    text = str(said[0].message)
    assert text.startswith("tfest") and ("feedthrough=True" if kw else "n_zeros") in text
    assert G.info["feedthrough_check"]["ratio"] >= 2.0
    quiet, said = _said(lambda: sysid.tfest(_record(3, d=0.0)[0], 2, **kw))
    assert not said and quiet.info["feedthrough_check"]["ratio"] < 1.3
    if kw:  # feedthrough=True holds the direct term: nothing to check
        G1, said = _said(lambda: sysid.tfest(est, 2, feedthrough=True, **kw))
        assert not said and "feedthrough_check" not in G1.info
