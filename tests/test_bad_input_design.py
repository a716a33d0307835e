"""Bad input found by fuzzing (round 2): sizes that would abort, hang or exhaust memory,
non-finite test-signal parameters, an impulse response that overflows and a decimation that
leaves nothing each get a clear sysid error before anything big is allocated."""

import numpy as np
import pytest

import sysid
from sysid.greybox.outer import OuterParameters

from conftest import first_order_record


@pytest.fixture(scope="module")
def rec():
    return first_order_record()


def _motor(p, dt=None):
    return [[-1 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]


# -- 1. okid: a huge count aborted the process in the Rust core --------------------------
def test_okid_huge_count_is_refused(rec):
    d = rec[3]
    with pytest.raises(sysid.DataError, match=r"count = 1000000000 would allocate .*GiB"):
        sysid.okid(d, 5, count=10**9)
    assert sysid.okid(d, 5, count=20).markov.shape == (20, 1, 1)


# -- 2. greyest: multistart is bounded (10**12 starts never ended) -----------------------
def test_greyest_multistart_is_bounded(rec, monkeypatch):
    def no_search(*a, **k):
        raise AssertionError("the search started")

    monkeypatch.setattr(OuterParameters, "best_of_starts", no_search)
    gb = sysid.GreyBox(_motor, params={"K": 2.0, "tau": sysid.param(0.5, bounds=(0.01, 10))})
    with pytest.raises(sysid.DataError, match=r"multistart = 1000000000000 .*at most 10000"):
        sysid.greyest(rec[3], gb, multistart=10**12)


# -- 3. prbs: a long hold builds only the samples returned -------------------------------
def test_prbs_long_hold_builds_only_what_is_returned():
    x = sysid.prbs(100, hold=10**9)
    assert x.shape == (100, 1) and np.all(x == x[0])
    np.testing.assert_array_equal(sysid.prbs(20, n_bits=3, hold=3),
                                  np.repeat(sysid.prbs(7, n_bits=3), 3, axis=0)[:20])


# -- 4. sizes that raised a raw MemoryError or numpy's "array is too big" ----------------
def test_impulse_from_frf_huge_n_fft(rec):
    frd = sysid.FRD.from_model(rec[0], np.linspace(0, 31.4, 100))
    with pytest.raises(sysid.DataError, match=r"n_fft = 1000000000000 would allocate"):
        sysid.impulse_from_frf(frd, 10**12)


def test_multisine_huge_periods():
    with pytest.raises(sysid.DataError, match=r"periods = 1000000000000 .*fewer periods"):
        sysid.multisine(100, periods=10**12)


def test_nyquist_n_points(rec):
    with pytest.raises(sysid.DataError, match=r"n_points = 10000000000 would allocate"):
        sysid.nyquist(rec[0], n_points=10**10)
    with pytest.raises(sysid.DataError, match=r"n_points must be an integer >= 2, got 0"):
        sysid.nyquist(rec[0], n_points=0)


def test_from_irregular_tiny_dt(rec):
    _, u, y, _ = rec
    with pytest.raises(sysid.DataError, match=r"dt = 1e-09 .*would allocate.*typical spacing"):
        sysid.IOData.from_irregular(np.arange(400) * 0.1, u, y, dt=1e-9)


def test_greybox_delay_longer_than_the_record(rec):
    g = sysid.GreyBox(_motor, params={"K": 1.0, "tau": 0.5}, input_delay=1e9)
    with pytest.raises(sysid.DataError, match=r"input_delay .*longer than the record"):
        sysid.greyest(rec[3], g)


def test_greybox_parameter_that_is_not_a_number_is_named():
    # float("x") raised a bare ValueError that named neither the parameter nor the fix
    with pytest.raises(sysid.DataError, match=r"parameter 'tau': .*real number, got 'x'"):
        sysid.GreyBox(_motor, params={"K": 1.0, "tau": "x"})
    with pytest.raises(sysid.DataError, match=r"parameter 'K': .*finite, got nan"):
        sysid.GreyBox(_motor, params={"K": np.nan, "tau": 0.5})
    with pytest.raises(sysid.DataError, match=r"real number, got \[1, 2\]"):
        sysid.param([1, 2])
    assert sysid.GreyBox(_motor, params={"K": np.float32(1.0), "tau": 0.5}) is not None


def test_tap_states_refuse_a_huge_delay_chain():
    from sysid.greybox.delays import tap_states

    mats = {k: np.ones((1, 1)) for k in "ABCD"}
    with pytest.raises(sysid.DataError, match=r"input delays of 10000000000 samples"):
        tap_states(mats, [(0, 10**10)], 1)


# -- 5. test signals with non-finite parameters were silently NaN or inf -----------------
@pytest.mark.parametrize("call, phrase", [
    (lambda: sysid.multisine(100, rms=float("inf")), "rms must be a finite positive number"),
    (lambda: sysid.chirp(100, 0.1, 0.1, 1, amplitude=float("nan")),
     "amplitude must be a finite number"),
    (lambda: sysid.random_binary(100, levels=(-np.inf, 1)), "levels must be finite"),
    (lambda: sysid.random_gaussian(100, mean=float("inf")), "mean must be a finite number"),
    (lambda: sysid.random_gaussian(100, std=float("inf")), "std must be a finite positive"),
])
def test_signal_parameters_must_be_finite(call, phrase):
    with pytest.raises(sysid.DataError, match=phrase):
        call()


def test_per_channel_mean_still_accepted():
    x = sysid.random_gaussian(100, mean=np.array([1.0, 2.0]), n_channels=2, seed=0)
    np.testing.assert_allclose(x.mean(axis=0), [1.0, 2.0])


# -- 6. impulse of an unstable model overflows: a NumericalError, as step ----------------
def test_impulse_of_unstable_model_raises_like_step():
    unstable = sysid.StateSpaceModel([[1.2]], [[1.0]], [[1.0]], dt=0.1)
    with pytest.raises(sysid.NumericalError, match="overflowed"):
        sysid.step(unstable, 10000)
    with pytest.raises(sysid.NumericalError, match=r"impulse response overflowed.*fewer "
                                                   r"n_samples"):
        sysid.impulse(unstable, 10000)
    assert np.isfinite(sysid.impulse(unstable, 50).y).all()


# -- 7. decimate: a factor that leaves (almost) nothing, and order 0 ---------------------
def test_decimate_refuses_a_factor_that_leaves_too_few_samples(rec):
    d = rec[3]
    with pytest.raises(sysid.InsufficientDataError, match=r"leave 1 sample.*pass q <= 44"):
        sysid.decimate(d, 10**6)
    assert sysid.decimate(d, 44).n_samples == 10
    with pytest.raises(sysid.DataError, match=r"order must be an integer between 1 and 30"):
        sysid.decimate(d, 2, order=0)
