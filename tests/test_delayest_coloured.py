"""delayest with a coloured input and a noisy output: the least ARX(2, 2) loss over delays
came out a sample late (a second-order plant with delay 1: 2 in 27 of 30 runs with a smooth
input, 30 of 30 with a narrowband one), because the too-low ARX model's error is coloured and
favours a later window; the first lag with evidence of a response in an ARX model of an
order chosen by BIC is right."""

import warnings

import numpy as np
import pytest
from scipy import signal

import sysid

INPUTS = {"white": [1.0], "smooth": [1.0, -0.95],
          "narrowband": np.real(np.poly([0.97 * np.exp(0.4j), 0.97 * np.exp(-0.4j)]))}


def _hits(shape, delay, runs, rng):
    hits = 0
    for _ in range(runs):
        u = signal.lfilter([1.0], INPUTS[shape], rng.standard_normal(1300))[300:]
        y = signal.lfilter(np.r_[np.zeros(delay), 0.5, 0.3], np.poly([0.8, 0.5]), u)
        y += 0.1 * y.std() * rng.standard_normal(u.size)   # 10 % output noise
        hits += sysid.delayest(sysid.IOData(u, y, 1.0)) == delay
    return hits


def test_coloured_input_noisy_output():
    # 80 runs; the new estimate is right in about 95 % (its false early lags are bounded by
    # the 1 % test), the least ARX(2, 2) loss in under 5 %: 64 is far from both
    rng = np.random.default_rng(5)
    hits = sum(_hits(shape, delay, 20, rng) for shape in ("smooth", "narrowband")
               for delay in (1, 3))
    assert hits >= 64


def test_white_input_still_right():
    rng = np.random.default_rng(6)
    assert _hits("white", 1, 20, rng) + _hits("white", 3, 20, rng) >= 38


def test_input_exciting_few_lags_keeps_the_arx_loss():
    # a sum of two sines excites four lags: which one acts first is not in the data, and the
    # first significant lag would only be where too few lags are left to stand in for the
    # dropped ones (the end of the range); the least ARX(2, 2) loss decides there, as before
    t = np.arange(1000.0)
    u = np.sin(0.05 * t) + np.sin(0.3 * t)
    y = signal.lfilter([0, 0, 0, 0.5, 0.3], np.poly([0.8, 0.5]), u)
    y += 0.05 * y.std() * np.random.default_rng(7).standard_normal(u.size)
    from sysid.models.input_delay import input_delays
    from sysid.polynomial.delayest import _first_response
    one = [((u - u.mean())[:, None], (y - y.mean())[:, None])]
    assert _first_response(one, 0, 20).tolist() == [-2]
    # said: the delay returned is MATLAB's criterion's, not one the data determine
    with pytest.warns(sysid.DelayWarning, match="not determined: the input does not excite"):
        assert sysid.delayest(sysid.IOData(u, y, 1.0)) < 10
    # so input_delay="auto" gives such an input no delay states (the wing flutter record's
    # input, a steep low-pass: 14 samples, 28 states, validation fit 27.7 -> 13.1 %)
    with pytest.warns(sysid.DelayWarning, match="do not determine the delay"):
        assert input_delays(sysid.IOData(u, y, 1.0), "auto").tolist() == [0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        finding = sysid.advice(sysid.IOData(u, y, 1.0)).findings
    text = " ".join(str(f) for f in finding)
    assert "not determined (the input does not excite its lags independently)" in text
