"""Bad input found by fuzzing: huge requested sizes, channels near the ends of double
precision, constant signals and a Tustin pole at 2/dt each get a clear sysid error (or,
where the answer is unitless, the same answer as in ordinary units)."""

import numpy as np
import pytest

import sysid
from sysid._checks import MAX_ELEMENTS, check_elements

from conftest import first_order_record


@pytest.fixture(scope="module")
def rec():
    m, u, y, _ = first_order_record()
    return m, u, y


def _data(u, y, k=1.0):
    return sysid.IOData(u=u * k, y=y * k, dt=0.1)


# -- 1. sizes that would exhaust memory are refused before allocating --------------------
def test_check_elements_bound():
    check_elements(MAX_ELEMENTS, "a full request", "ask for less")
    with pytest.raises(sysid.DataError, match="GiB.*ask for less"):
        check_elements(MAX_ELEMENTS + 1, "a request", "ask for less")


def test_spa_huge_n_freq(rec):
    _, u, y = rec
    with pytest.raises(sysid.DataError, match=r"n_freq = 1000000000 would allocate .*GiB.*"
                                              r"smaller n_freq"):
        sysid.spa(_data(u, y), n_freq=10**9)


def test_welch_frf_huge_nfft(rec):
    _, u, y = rec
    with pytest.raises(sysid.DataError, match=r"nfft = 10000000000 would allocate .*GiB.*"
                                              r"smaller nfft"):
        sysid.welch_frf(_data(u, y), nperseg=64, nfft=10**10)


def test_welch_nperseg_beyond_record_before_window(rec):
    _, u, y = rec
    with pytest.raises(sysid.InsufficientDataError, match="shorter than nperseg"):
        sysid.spectra(_data(u, y), nperseg=10**11)


def test_resample_huge_factor(rec):
    _, u, y = rec
    with pytest.raises(sysid.DataError, match=r"dt = 1e-09 s .*would allocate .*GiB.*"
                                              r"longer dt"):
        sysid.resample(_data(u, y), 1e-9)


def test_forecast_huge_horizon(rec):
    _, _, y = rec
    model = sysid.ar(sysid.IOData(y=y, dt=0.1), 2)
    with pytest.raises(sysid.DataError, match=r"horizon = 1000000000 would allocate .*GiB.*"
                                              r"fewer steps"):
        sysid.forecast(model, y, 10**9)


# -- 2. fits and unitless statistics do not depend on the channels' units ----------------
@pytest.mark.parametrize("k", [1e-200, 1e200, 2.0**-900])
def test_compare_fit_any_scale(rec, k):
    m, u, y = rec
    ref = sysid.compare(m, _data(u, y))
    got = sysid.compare(m, _data(u, y, k))
    assert np.all(np.isfinite(got.fit))
    np.testing.assert_allclose(got.fit, ref.fit, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got.vaf, ref.vaf, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got.rmse / k, ref.rmse, rtol=1e-9)


def test_compare_fit_bitwise_unchanged_by_power_of_two(rec):
    m, u, y = rec
    ref = sysid.fit_metrics(y, y + 0.1 * u)
    got = sysid.fit_metrics(y * 2.0**-700, (y + 0.1 * u) * 2.0**-700)
    assert np.array_equal(got["fit"], ref["fit"]) and np.array_equal(got["vaf"], ref["vaf"])


def test_correlation_huge_channels(rec):
    _, u, y = rec
    ref = sysid.correlation(_data(u, y))
    got = sysid.correlation(_data(u, y, 1e300))
    np.testing.assert_allclose(got.values, ref.values, atol=1e-12)


def test_spectra_overflowing_units(rec):
    _, u, y = rec
    with pytest.raises(sysid.DataError, match="overflow double precision.*rescale"):
        sysid.spectra(_data(u, y, 1e300))
    # spectra that fit in double precision come out in the data's units
    ref = sysid.spectra(_data(u, y))
    got = sysid.spectra(_data(u, y, 1e150))
    np.testing.assert_allclose(got.matrix / 1e300, ref.matrix, rtol=1e-12, atol=0)
    coh = sysid.coherence(_data(u, y, 1e300))
    np.testing.assert_allclose(coh.values, sysid.coherence(_data(u, y)).values, atol=1e-12)


# -- 3. constant signals -----------------------------------------------------------------
def test_delayest_constant_input(rec):
    _, _, y = rec
    with pytest.raises(sysid.ExcitationError, match="input u0 is 1 in every sample: delayest"):
        sysid.delayest(sysid.IOData(u=np.ones((400, 1)), y=y, dt=0.1))


def test_delayest_constant_output(rec):
    # its ARX losses are all zero: it raised numpy's "argmin of an empty sequence"
    _, u, _ = rec
    with pytest.raises(sysid.DataError, match="output y0 is 0 in every sample: delayest"):
        sysid.delayest(sysid.IOData(u=u, y=np.zeros((u.shape[0], 1)), dt=0.1))


def test_impulse_response_constant_input(rec):
    _, _, y = rec
    with pytest.raises(sysid.ExcitationError, match="u0 is 1 in every sample: impulse_resp"):
        sysid.impulse_response(sysid.IOData(u=np.ones((400, 1)), y=y, dt=0.1), 10)


def test_ssi_constant_outputs():
    with pytest.raises(sysid.DataError, match="y0 is 1 in every sample: ssi cannot"):
        sysid.ssi(sysid.IOData(y=np.ones((400, 2)), dt=0.1), range(2, 6))


# -- 4. Tustin of a pole at 2/dt ---------------------------------------------------------
def test_c2d_tustin_pole_at_two_over_dt():
    sys = sysid.ContinuousStateSpace([[20.0]], [[1.0]], [[1.0]])
    with pytest.raises(sysid.DataError, match=r"pole at s = 20 rad/s, at 2/dt.*another method"):
        sysid.c2d(sys, 0.1, "tustin")
    # a very fast stable pole (a badly conditioned I - A dt/2) is not refused
    stiff = sysid.ContinuousStateSpace([[-1e14, 0.0], [0.0, -1.0]], [[1.0], [1.0]],
                                       [[1.0, 1.0]])
    assert np.all(np.isfinite(sysid.c2d(stiff, 0.1, "tustin").A))


# -- 5. frequency responses of channels near the ends of double precision ----------------
@pytest.mark.parametrize("est", [sysid.spa, sysid.welch_frf, sysid.etfe,
                                 lambda d: sysid.etfe(d, smoothing=9)])
@pytest.mark.parametrize("ku, ky", [(1e300, 1e300), (1e150, 1e150), (1e-200, 1e-200),
                                    (1e-150, 1e150)])
def test_frf_any_scale(rec, est, ku, ky):
    _, u, y = rec
    ref = est(_data(u, y))
    got = est(sysid.IOData(u=u * ku, y=y * ky, dt=0.1))
    np.testing.assert_array_equal(got.omega, ref.omega)
    np.testing.assert_allclose(got.response * (ku / ky), ref.response, rtol=1e-10)
    if ref.std is not None:
        np.testing.assert_allclose(got.std * (ku / ky), ref.std, rtol=1e-9)
    if ref.coherence is not None:
        np.testing.assert_allclose(got.coherence, ref.coherence, atol=1e-12)


def test_frf_beyond_double_precision(rec):
    _, u, y = rec
    with pytest.raises(sysid.DataError, match="beyond double precision; rescale"):
        sysid.spa(sysid.IOData(u=u * 1e-200, y=y * 1e200, dt=0.1))


@pytest.mark.parametrize("fn", [sysid.spa, sysid.etfe, sysid.spafdr, sysid.default_lags])
def test_frequency_response_of_a_time_series_names_the_spectrum_tools(fn):
    # MATLAB's spa(y) / etfe(y) give a time series' spectrum; here the error said only that
    # a frequency response needs inputs, not where the spectrum is
    data = sysid.IOData(y=np.random.default_rng(0).standard_normal(400), dt=0.1)
    with pytest.raises(sysid.DataError, match=r"time series .*sysid\.spectra\(data\).*"
                                              r"sysid\.periodogram\(data\)"):
        fn(data)
    assert np.all(np.isfinite(sysid.spectra(data).psd("y0")))
