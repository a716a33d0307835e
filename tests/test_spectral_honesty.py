"""Non-parametric estimates that said more than the data hold.

* ``etfe(smoothing=L)``: the frequency window was off-centre by half a bin (a periodic window
  and an even-length kernel), a phase error of ``pi D / n`` on a delay of ``D`` samples (+6.9
  degrees for ``D = 20``, ``n = 512``).
* ``spa``'s default lag window was a fixed multiple of the last significant lag: near a
  resonance its bias left the truth outside the 99 % band in up to 64 % of runs.
* A constant input or channel: unsmoothed ``etfe`` returned a one-point response at zero
  frequency (the ratio of the means), ``coherence`` and ``correlation`` returned 0 for
  what is 0 / 0.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import sysid

# ------------------------------------------------------------------ etfe window centring


def _flat_multisine(n: int, seed: int = 0) -> np.ndarray:
    """A periodic signal with the same magnitude on every bin but zero and Nyquist."""
    phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, n // 2 + 1)
    spectrum = np.exp(1j * phases)
    spectrum[0] = spectrum[-1] = 0.0
    return np.fft.irfft(spectrum, n)


@pytest.mark.parametrize("smoothing", [20, 21])
def test_etfe_window_is_centred_on_the_bin(smoothing: int) -> None:
    # y is u delayed by D samples (circularly): G = exp(-i w D) on every bin. With |U| flat,
    # a window centred on the bin gives the exact phase; the old periodic, even-length window
    # shifted it by half a bin: pi D / n = 7.03 degrees
    n, D = 512, 20
    u = _flat_multisine(n)
    f = sysid.etfe(sysid.IOData(u=u, y=np.roll(u, D)), smoothing=smoothing)
    err = np.degrees(np.angle(f.response[:, 0, 0] * np.exp(1j * f.omega * D)))
    inner = slice(15, -15)  # away from the unexcited zero and Nyquist bins
    assert np.abs(err[inner]).max() < 1e-6, np.abs(err[inner]).max()
    assert f.info["window_bins"] == 21  # an even width is rounded up to an odd one


def test_etfe_phase_of_a_delay_is_unbiased_on_noise_input() -> None:
    # the auditor's reproducer: median phase error +6.91 degrees before, now about 0
    rng = np.random.default_rng(0)
    n, D = 512, 20
    u = rng.standard_normal(n)
    f = sysid.etfe(sysid.IOData(u=u, y=np.roll(u, D)), smoothing=21)
    err = np.degrees(np.median(np.angle(f.response[:, 0, 0] * np.exp(1j * f.omega * D))))
    assert abs(err) < 2.0, err


def test_etfe_window_width_is_odd_and_fits_the_spectrum() -> None:
    u = np.random.default_rng(1).standard_normal(256)
    d = sysid.IOData(u=u, y=np.roll(u, 3))
    assert sysid.etfe(d, smoothing=8).info["window_bins"] == 9
    assert sysid.etfe(d, smoothing=9, window="boxcar").info["window_bins"] == 9
    assert sysid.etfe(d, smoothing=256).info["window_bins"] == 255  # at most n bins


# ------------------------------------------------------------------ spa's default lag window


def _resonant_run(seed: int, n: int, c: float) -> tuple[sysid.IOData, np.ndarray]:
    """``(0.3 q^-1 + 0.2 q^-2) / (1 - 1.2 q^-1 + 0.6 q^-2)`` (a resonance near 7 rad/s at
    dt = 0.1) driven by AR(c) noise, output noise 0.3."""
    num, den = [0.0, 0.3, 0.2], [1.0, -1.2, 0.6]
    rng = np.random.default_rng(seed)
    u = signal.lfilter([1.0], [1.0, -c], rng.standard_normal(n))
    y = signal.lfilter(num, den, u) + 0.3 * rng.standard_normal(n)
    return sysid.IOData(u, y, 0.1), np.array([num, den])


def _truth(nd: np.ndarray, omega: np.ndarray) -> np.ndarray:
    zi = np.exp(-1j * omega * 0.1)
    return np.polyval(nd[0][::-1], zi) / np.polyval(nd[1][::-1], zi)


def test_spa_default_band_holds_the_truth_at_a_resonance() -> None:
    # Monte Carlo, 40 runs of 2000 samples with a coloured (AR 0.8) input. With the old
    # default (6 x the last significant lag, about 36 lags) the 99 % band held the truth
    # near the resonance in 32 % of these runs (36 % of 200); the bias check doubles the
    # window (72-168 lags here) until the estimates with M / 2 and M lags agree within the
    # band: 92 % here, 97 % of 200 runs
    inside, lags = [], []
    for seed in range(40):
        data, nd = _resonant_run(5000 + seed, 2000, 0.8)
        f = sysid.spa(data)
        lags.append(f.info["lags"])
        assert f.info["bias_check"] == "passed"
        inside.append(np.abs(f.response[:, 0, 0] - _truth(nd, f.omega)) <= f.radius[:, 0, 0])
    near = (f.omega > 4.0) & (f.omega < 10.0)
    coverage = np.mean(inside, axis=0)
    assert coverage[near].min() >= 0.9, (coverage[near].min(), np.median(lags))
    assert coverage.mean() >= 0.97


def test_spa_default_lags_record_the_bias_check() -> None:
    data, _ = _resonant_run(1, 2000, 0.8)
    M, info = sysid.default_lags(data)
    assert info["bias_check"] == "passed" and M <= info["max_lag"]
    first = max(10, 6 * info["significant_lag"])
    assert M in {first * 2**k for k in range(6)}, (M, info)
    # given lags are used as given
    assert sysid.spa(data, lags=30).info["lags"] == 30


# ------------------------------------------------------------------ constant channels


def test_etfe_refuses_a_constant_input_without_smoothing() -> None:
    # it returned a one-point FRD at zero frequency, mean(y) / mean(u)
    y = np.random.default_rng(0).standard_normal(500)
    with pytest.raises(sysid.ExcitationError, match="etfe: the input has no power"):
        sysid.etfe(sysid.IOData(u=np.full(500, 1.0), y=y))
    with pytest.raises(sysid.ExcitationError, match="etfe: the input has no power"):
        sysid.etfe(sysid.IOData([np.full(250, 1.0), np.full(250, 2.0)], [y[:250], y[250:]]))
    u = np.random.default_rng(1).standard_normal(500)
    with pytest.raises(sysid.ExcitationError, match=r"input\(s\) \['u1'\] are constant"):
        sysid.etfe(sysid.IOData([np.c_[u, np.full(500, 3.0)]] * 2, [y, y[::-1]]))
    assert sysid.etfe(sysid.IOData(u=u, y=y)).omega.size == 251  # a varying input is fine


def test_coherence_refuses_a_constant_channel_by_name() -> None:
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal(1000), rng.standard_normal(1000)
    with pytest.raises(sysid.ExcitationError, match=r"coherence: input u0 is constant.*0 / 0"):
        sysid.coherence(sysid.IOData(u=np.full(1000, 1.0), y=y))
    with pytest.raises(sysid.DataError, match=r"coherence: output y1 is constant"):
        sysid.coherence(sysid.IOData(u=u, y=np.c_[y, np.full(1000, -2.0)]))
    c = sysid.coherence(sysid.IOData(u=u, y=u + 0.1 * y))
    assert np.all(np.isfinite(c.values)) and c.values.min() > 0.9


def test_correlation_refuses_a_constant_channel_by_name() -> None:
    y = np.random.default_rng(0).standard_normal(500)
    with pytest.raises(sysid.ExcitationError, match=r"correlation: input u0 is constant"):
        sysid.correlation(sysid.IOData(u=np.full(500, 1.0), y=y))
    with pytest.raises(sysid.DataError, match=r"correlation: output y0 is constant"):
        sysid.correlation(sysid.IOData(u=None, y=np.full(500, 4.0)))
    # each experiment's mean removed: constant levels that differ are still no variation
    with pytest.raises(sysid.ExcitationError, match="input u0 is constant"):
        sysid.correlation(sysid.IOData([np.full(250, 1.0), np.full(250, 2.0)],
                                       [y[:250], y[250:]]))
    # without mean removal a nonzero constant correlates; an all-zero channel does not
    r = sysid.correlation(sysid.IOData(u=np.full(500, 1.0), y=y), 5, remove_mean=False)
    assert r.pair("u0", "u0")[r.lags == 0] == pytest.approx(1.0)
    with pytest.raises(sysid.ExcitationError, match="input u0 is zero in every sample"):
        sysid.correlation(sysid.IOData(u=np.zeros(500), y=y), 5, remove_mean=False)


def test_one_constant_channel_rule_for_estimators_and_spectra() -> None:
    # a stuck channel with round-off-level wiggle (1 + 1e-13 noise): the spectral estimates
    # refused it as constant (to 1e-12 of its size), oe and coherence took it (exact
    # comparison), arx refused it for rank and spafdr for "insufficient data"
    from sysid._checks import CONSTANT_TOL, constant_channels

    rng = np.random.default_rng(3)
    n = 400
    u1 = rng.standard_normal(n)
    y = np.convolve(u1, [0.0, 1.0, 0.5])[:n] + 0.1 * rng.standard_normal(n)
    stuck = sysid.IOData(u=np.c_[u1, 1.0 + 1e-13 * rng.standard_normal(n)], y=y)
    calls = {"arx": lambda d: sysid.arx(d, 2, [2, 2], [1, 1]),
             "oe": lambda d: sysid.oe(d, [2, 2], [2, 2], [1, 1]),
             "spafdr": sysid.spafdr, "etfe": lambda d: sysid.etfe(d, smoothing=31),
             "welch_frf": sysid.welch_frf, "coherence": sysid.coherence}
    for who, call in calls.items():
        with pytest.raises(sysid.DataError, match=r"u1 (is 1 in every sample|is constant)|"
                           r"\['u1'\] are constant") as caught:
            call(stuck)
        assert who in str(caught.value)  # each in its own words
    # the one rule and its tolerance: varying by more than CONSTANT_TOL of its size varies
    parts = [np.c_[np.ones(5), 1.0 + np.r_[0, 0, 0, 0, 10 * CONSTANT_TOL]]]
    assert constant_channels(parts).tolist() == [True, False]
    assert constant_channels(parts, "all").tolist() == [True, False]
    two = [np.full((3, 1), 1.0), np.full((3, 1), 2.0)]  # a level per experiment
    assert constant_channels(two).tolist() == [True]        # no spectrum
    assert constant_channels(two, "all").tolist() == [False]  # but it moves the output


# ------------------------------------------------ bands at the real lines (zero, Nyquist)


def test_band_covers_at_its_level_at_zero_nyquist_and_inside() -> None:
    # at zero frequency and at Nyquist the spectra of a real record are real, and so is the
    # error of the estimate: one degree of freedom, not two. The complex rule's 99 % band
    # held the truth there 95-97 % of the time (a flat G = 2: no smoothing bias, the
    # distribution alone is measured)
    rng = np.random.default_rng(2024)
    runs, n = 400, 512
    real, inner = [], []
    w = np.linspace(0.0, np.pi, 33)
    for _ in range(runs):
        u = rng.standard_normal(n)
        d = sysid.IOData(u=u, y=2.0 * u + 0.5 * rng.standard_normal(n), dt=1.0)
        for f in (sysid.welch_frf(d, nperseg=32), sysid.spa(d, lags=16, omega=w),
                  sysid.etfe(d, smoothing=15, remove_mean=False)):
            inside = f.within_band(2.0 * np.ones(f.omega.size))[:, 0, 0]
            at = f.real_lines()[:, 0, 0]
            assert at.sum() == (1 if f.method == "welch" else 2)  # welch drops zero
            real.extend(inside[at])
            inner.append(inside[~at].mean())
    real_cover, inner_cover = float(np.mean(real)), float(np.mean(inner))
    assert 0.983 <= real_cover <= 0.997, real_cover  # was 0.96
    assert abs(inner_cover - 0.99) < 0.004, inner_cover
