"""The excitation check agrees with the input's spectrum (issue 26): a band-limited multisine
with 59 lines is persistently exciting of order 118 (it was called order 4, and every fit
warned), the shipped real records raise no excitation warning, and truly poor inputs (one
sinusoid, a step at the start of the record, three sines) still warn."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import ExcitationWarning

N = 2048
T = np.arange(N)


def _multisine(lines, noise=1e-5, seed=0):
    """Lines (DFT bins of N) with Schroeder-like phases, unit power, a little input noise
    (a measured or quantised reference signal)."""
    lines = np.asarray(lines)
    u = np.cos(2 * np.pi * np.outer(T, lines) / N + np.pi * lines**2 / lines.size).sum(1)
    u /= u.std()
    return u + noise * np.random.default_rng(seed).standard_normal(N)


def _record(u, seed=1):
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 dt=1.0)
    y = true.simulate(u) + 0.01 * np.random.default_rng(seed).standard_normal((N, 1))
    return sysid.IOData(u=u, y=y, dt=1.0)


def _excitation_warnings(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fn()
    return [w for w in caught if issubclass(w.category, ExcitationWarning)]


def test_band_limited_multisine_with_59_lines_is_richly_exciting():
    u = _multisine(np.arange(1, 60) * 2)      # 59 lines in the lowest 12 % of the band
    # the lag-covariance rank (MATLAB's pexcit rule) calls it order 5 ...
    assert sysid.persistent_excitation_order(u, 20, method="covariance") < 8
    # ... but 59 distinct frequencies make it persistently exciting of order 118
    assert sysid.persistent_excitation_order(u, 20) == 20
    assert sysid.persistent_excitation_order(u, 200) >= 110
    for fit in (lambda: sysid.n4sid(_record(u), 2), lambda: sysid.moesp(_record(u), 4),
                lambda: sysid.check_excitation(u, 10)):
        assert not _excitation_warnings(fit)


@pytest.mark.parametrize("name", ["dryer", "robot_arm", "winding", "f16", "f16_level3"])
def test_no_excitation_warning_on_the_shipped_real_records(name):
    data = getattr(sysid.datasets, f"load_{name}")()
    assert sysid.persistent_excitation_order(data.u, 20) == 20
    if data.n_samples > 5000:   # the F-16: the check only (its fits are tested elsewhere)
        return
    d = sysid.detrend(data, "mean")
    est = sysid.SubspaceEstimator(d)
    for order in (2, 4, 6, 8):
        assert not _excitation_warnings(lambda o=order: est.fit(o)), (name, order)


def test_the_f16_shaker_reference_voltage_is_exciting():
    """The generator's voltage (a clean 2-15 Hz multisine): order 4 by the lag-covariance
    rule, far more by its lines."""
    raw = np.loadtxt(sysid.datasets.path("f16"), delimiter=",", skiprows=1,
                     usecols=1, max_rows=16384)
    assert sysid.persistent_excitation_order(raw, 40) == 40


def test_poor_inputs_still_warn():
    sine = np.sin(0.3 * T)
    assert sysid.persistent_excitation_order(sine, 20) == 2
    with pytest.warns(ExcitationWarning, match="order 2 only"):
        sysid.check_excitation(sine, order=2)
    step = np.ones(N)                          # a step applied at the first sample
    assert sysid.persistent_excitation_order(step, 20) == 1
    with pytest.warns(ExcitationWarning, match="order 1 only"):
        sysid.check_excitation(step, order=1)
    # three sines and a little noise: the subspace fit runs (the noise keeps its input rows
    # of full rank) but order 4 needs 8 excited frequencies, and the input has 6
    three = np.sin(0.3 * T) + np.sin(0.9 * T) + np.sin(1.7 * T)
    three = three + 1e-5 * np.random.default_rng(3).standard_normal(N)
    assert sysid.persistent_excitation_order(three, 20) == 6
    assert _excitation_warnings(lambda: sysid.n4sid(_record(three), 4))
    assert not _excitation_warnings(lambda: sysid.n4sid(_record(three), 3))


@pytest.mark.parametrize("snr_db", [30, 40, 60])
def test_measured_tones_warn_like_their_spectrum(snr_db):
    """A shaker's drive of three tones, measured with sensor noise 30-60 dB below them: the
    noise keeps the lag matrix of full rank at any rounding tolerance (the fit read order
    22 and stayed silent at order 11), but the spectrum has 6 lines, and the fit's warning
    says what ``persistent_excitation_order`` says."""
    t = np.arange(8 * N)
    three = sum(np.sin(2 * np.pi * f * t + ph) for f, ph in ((0.031, 1.0), (0.0375, 2.0),
                                                             (0.047, 3.0)))
    rng = np.random.default_rng(snr_db)
    u = three + np.sqrt(1.5) * 10 ** (-snr_db / 20) * rng.standard_normal(t.size)
    true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.5]], [[1.0, 0.0]],
                                 dt=1.0)
    data = sysid.IOData(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal((t.size, 1)),
                        dt=1.0)
    assert sysid.persistent_excitation_order(u, 40) == 6
    est = sysid.SubspaceEstimator(data)
    assert _excitation_warnings(lambda: est.fit(11))
    assert _excitation_warnings(lambda: est.fit(4))
    assert not _excitation_warnings(lambda: est.fit(3))


def test_white_noise_and_a_noisy_tone_read_rich_without_the_spectrum():
    """The fast path: an input whose lag covariance is within 30 dB of flat (white noise, a
    tone in noise of its own power) is rich without a pass over the data."""
    rng = np.random.default_rng(5)
    for u in (rng.standard_normal(N), np.sin(0.3 * T) + rng.standard_normal(N)):
        est = sysid.SubspaceEstimator(_record(u))
        assert not _excitation_warnings(lambda e=est: e.fit(8))
        assert "spectrum" not in est._pe_cache


def test_several_inputs_count_the_weakest_direction_whatever_the_units():
    rng = np.random.default_rng(4)
    u = rng.standard_normal((N, 2))
    assert sysid.persistent_excitation_order(u, 20) == 20
    # units do not matter
    assert sysid.persistent_excitation_order(u * [1e-3, 1e3], 20) == 20
    # identical inputs: the difference never moves
    same = np.column_stack([u[:, 0], 2.0 * u[:, 0]])
    assert sysid.persistent_excitation_order(same, 20) <= 1
    # each input on its own 10 lines (zippered multisine): 20 lines each
    a, b = _multisine(np.arange(1, 11) * 40, 0.0), _multisine(np.arange(1, 11) * 40 + 20, 0.0)
    assert sysid.persistent_excitation_order(np.column_stack([a, b]), 40) == 20


@pytest.mark.parametrize("bits", [3, 5, 6])
def test_a_short_periodic_input_counts_the_lines_of_its_period(bits):
    # a maximum-length PRBS of period M repeated a few times is persistently exciting of
    # order M exactly (its M lines, the offset included: Ljung 1999, section 13.2); under
    # the window a short record's lines merged into one run (period 7 over 35 samples: 20)
    period = 2 ** bits - 1
    u = np.tile(sysid.prbs(period), (5, 1))
    assert sysid.persistent_excitation_order(u, 3 * period) == period
    assert sysid.persistent_excitation_order(u, 3 * period, method="covariance") == period
    # a sinusoid whose period is not a whole number of samples is not exactly periodic
    t = np.arange(5 * period)
    assert sysid.persistent_excitation_order(np.sin(0.3 * t), 10) == 2


def test_a_step_test_refused_by_the_subspace_methods_says_what_fits_it():
    """A TCLab heater step test (0 -> 50 % after one sample) made identify, ssest(order=
    'auto') and n4sid raise 'not persistently exciting ... use a richer input, a shorter
    horizon': no horizon helps (the step comes before the data matrix's future rows start),
    and nothing said what does fit a step test. The refusal now says it is a step test,
    where the input changes, and names the fits simulated from rest."""
    n = 300
    u = np.r_[0.0, np.full(n - 1, 50.0)]
    y = sysid.StateSpaceModel([[0.98]], [[1.0]], [[0.02]], dt=1.0).simulate(u).ravel()
    y += 0.01 * np.random.default_rng(1).standard_normal(n)
    d = sysid.IOData(u=u, y=y - y[0], dt=1.0)
    for fit in (lambda: sysid.n4sid(d), lambda: sysid.ssest(d, order="auto")):
        with pytest.raises(sysid.ExcitationError) as err:
            fit()
        msg = str(err.value)
        assert "step test" in msg and "(index 1)" in msg and "no horizon helps" in msg
        assert "shorter horizon" not in msg
        assert "sysid.procest" in msg and "sysid.oe" in msg
    # what it names fits: oe from rest recovers the plant, and identify fits it that way
    # (process models by BIC, tests/test_identify_steptest.py)
    assert abs(sysid.oe(d, 1, 1, 1).poles()[0] - 0.98) < 0.01
    res = sysid.identify(d, progress=False)
    assert res.score == "BIC" and abs(np.max(np.abs(res.model.poles())) - 0.98) < 0.01
    # a rich input refused for another reason keeps the core's remedies
    assert sysid.subspace.steptest.step_test_note([(np.c_[np.arange(50.0)], None)], 8) == ""


def test_the_cores_excitation_error_carries_its_facts_as_data():
    """The step-test refusal re-worded the core's ExcitationError by splitting its message
    at "; use a richer input". The binding now sets the core error's variant, the problem
    and the remedy on the exception; the messages are as before."""
    t = np.arange(500)
    u = np.sin(0.05 * t) + 0.5 * np.sin(0.3 * t)  # exciting of order 4 only
    y = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]]).simulate(u)
    with pytest.raises(sysid.ExcitationError) as err:
        sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=10)
    e = err.value
    assert e.kind == "NotPersistentlyExciting"
    assert e.problem.startswith("the input is not persistently exciting: the 10 rows")
    assert e.remedy.startswith("use a richer input") and "shorter horizon" in e.remedy
    assert str(e) == f"{e.problem}; {e.remedy}"
    # a step test: the core's problem, and what fits a step test as the remedy
    u = np.r_[0.0, np.full(299, 50.0)]
    d = sysid.IOData(u=u, y=sysid.StateSpaceModel([[0.98]], [[1.0]], [[0.02]]).simulate(u))
    with pytest.raises(sysid.ExcitationError) as err:
        sysid.SubspaceEstimator(d, horizon=8)
    e = err.value
    assert e.kind == "NotPersistentlyExciting" and "step test" in e.remedy
    assert str(e) == f"{e.problem}: {e.remedy}" and "richer input" not in str(e)
    # errors of other kinds and errors raised in Python
    with pytest.raises(sysid.OrderError) as err:
        sysid.n4sid(sysid.IOData(u=np.random.default_rng(0).standard_normal(200), y=y[:200]),
                    9, horizon=3)
    assert err.value.kind == "OrderTooLarge" and err.value.remedy is None
    assert err.value.problem == str(err.value)
    assert sysid.DataError("raised in Python").kind is None
