"""MATLAB's idinput: shapes, periodicity, levels, bands, clock periods, sinusoid grids."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid


def test_shapes_follow_matlab_n():
    assert sysid.idinput(50, seed=0).shape == (50, 1)
    assert sysid.idinput((50, 3), seed=0).shape == (50, 3)
    assert sysid.idinput(np.array([50.0, 2.0]), seed=0).shape == (50, 2)  # MATLAB's doubles
    assert sysid.idinput(np.int64(7), "prbs").shape == (7, 1)
    with pytest.raises(sysid.DataError, match=r"n\[1\] \(inputs\)"):
        sysid.idinput((50, 1.5))
    u = sysid.idinput((40, 2, 5), "rgs", seed=0)
    assert u.shape == (200, 2)
    assert np.array_equal(u[:40], u[160:])  # a periodic request repeats one period
    # channels differ
    v = sysid.idinput((500, 2), "rbs", seed=1)
    assert not np.array_equal(v[:, 0], v[:, 1])


def test_binary_and_gaussian_levels():
    u = sysid.idinput((300, 2), "rbs", levels=(2.0, 7.0), seed=3)
    assert set(np.unique(u)) == {2.0, 7.0}
    g = sysid.idinput((300, 2), "rgs", levels=(1.0, 5.0), seed=3)  # mean -/+ one std
    np.testing.assert_allclose(g.mean(axis=0), 3.0, atol=1e-12)
    np.testing.assert_allclose(g.std(axis=0), 2.0, rtol=1e-12)


def test_band_limits_one_period_circularly():
    period = 256
    u = sysid.idinput((period, 1, 3), "rgs", band=(0.2, 0.5), seed=4)
    X = np.abs(np.fft.rfft(u[:period, 0] - u[:period, 0].mean()))
    frac = np.arange(X.size) / (period / 2)
    outside = (frac < 0.2) | (frac > 0.5)
    assert X[outside].max() < 1e-9 * X.max()
    assert np.all(X[~outside & (frac > 0)] > 0)


def test_prbs_clock_period_and_maximum_length_period():
    u = sysid.idinput((4 * 63, 1, 2), "prbs", band=(0, 0.25))
    one = u[:252, 0]
    assert np.all(one.reshape(-1, 4) == one[::4, None])  # each bit held 4 samples
    bits = one[::4]
    # a maximum-length sequence: its +-1 circular autocorrelation is 63 at lag 0, -1 elsewhere
    r = np.array([bits @ np.roll(bits, k) for k in range(63)])
    assert r[0] == 63 and np.all(r[1:] == -1)
    with pytest.raises(sysid.DataError, match=r"pass period 252 or 508"):
        sysid.idinput((300, 1, 2), "prbs", band=(0, 0.25))
    with pytest.raises(sysid.DataError, match=r"\(0, B\)"):
        sysid.idinput(100, "prbs", band=(0.1, 0.5))
    with pytest.raises(sysid.DataError, match="whole number"):
        sysid.idinput(100, "prbs", band=(0, 0.3))


def test_sine_frequencies_on_the_grid_one_input_each():
    period = 240
    u, w = sysid.idinput((period, 2, 2), "sine", band=(0.1, 0.8), levels=(-2.0, 4.0),
                         sine=(5, 20, 2), seed=5, return_frequencies=True)
    assert u.shape == (480, 2) and w.shape == (5, 2)
    k = w * period / (2 * np.pi)
    np.testing.assert_allclose(k, np.round(k), atol=1e-9)  # on the period's grid
    assert np.all(np.round(k) % 2 == 0)  # grid skip 2
    frac = w / np.pi
    assert np.all((frac >= 0.1) & (frac <= 0.8))
    assert not set(np.round(k[:, 0])) & set(np.round(k[:, 1]))  # interleaved lines
    for j in range(2):
        X = np.abs(np.fft.rfft(u[:period, j] - u[:period, j].mean()))
        lines = np.flatnonzero(X > 1e-8 * X.max())
        assert lines.tolist() == sorted(np.round(k[:, j]).astype(int).tolist())
        # the range fills levels: inside, touching one side
        assert u[:, j].min() >= -2.0 - 1e-12 and u[:, j].max() <= 4.0 + 1e-12
        assert np.isclose(u[:, j].min(), -2.0) or np.isclose(u[:, j].max(), 4.0)


def test_sine_trials_keep_the_lowest_peak():
    def peak_to_rms(trials):
        u = sysid.idinput(512, "sine", sine=(12, trials, 1), seed=7)
        return sysid.crest_factor(u - u.mean())[0]

    # the first trial of 30 is the single trial's draw (same seed), so 30 trials never lose
    assert peak_to_rms(30) <= peak_to_rms(1)


def test_bad_requests_name_the_fix():
    with pytest.raises(sysid.DataError, match="type must be one of"):
        sysid.idinput(10, "white")
    with pytest.raises(sysid.DataError, match=r"N, \(N, nu\) or \(period"):
        sysid.idinput((10, 1, 2, 3))
    with pytest.raises(sysid.DataError, match="n"):
        sysid.idinput(True)
    with pytest.raises(sysid.DataError, match="fewer sinusoids"):
        sysid.idinput(20, "sine", band=(0, 0.5))
    with pytest.raises(sysid.DataError, match="'sine' only"):
        sysid.idinput(20, "rbs", return_frequencies=True)
    with pytest.raises(sysid.DataError, match="far too large|GiB"):
        sysid.idinput((10**6, 100, 10**3))


@settings(max_examples=40, deadline=None)
@given(period=st.integers(8, 90), nu=st.integers(1, 3), reps=st.integers(1, 4),
       kind=st.sampled_from(["rbs", "rgs", "sine"]), seed=st.integers(0, 2**16))
def test_every_request_is_periodic_and_in_range(period, nu, reps, kind, seed):
    lines = (period - 1) // 2
    sine = (max(1, min(3, lines // nu)), 3, 1)
    if kind == "sine" and lines < nu:
        with pytest.raises(sysid.DataError):
            sysid.idinput((period, nu, reps), kind, sine=sine, seed=seed)
        return
    u = sysid.idinput((period, nu, reps), kind, sine=sine, seed=seed)
    assert u.shape == (period * reps, nu) and np.all(np.isfinite(u))
    assert np.array_equal(u, np.tile(u[:period], (reps, 1)))
    if kind != "rgs":
        assert u.min() >= -1.0 - 1e-12 and u.max() <= 1.0 + 1e-12
