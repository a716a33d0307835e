"""One offset check for every linear estimator (issue 26): n4sid/ssest warned about a large
mean, arx/oe/bj/armax/pem/iv4 did not and returned validation fits of -275 % to -9202 %."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import OffsetWarning


def _raw_record(seed=0, n=600):
    """A 2nd-order process around an operating point: input 50 +- 1, output 300 + dynamics."""
    rng = np.random.default_rng(seed)
    true = sysid.StateSpaceModel([[1.5, -0.7], [1.0, 0.0]], [[1.0], [0.0]], [[0.1, 0.05]],
                                 dt=1.0)
    du = rng.standard_normal(n)
    y = true.simulate(du) + 0.01 * rng.standard_normal((n, 1))
    return sysid.IOData(u=50.0 + du, y=300.0 + y, dt=1.0)


ESTIMATORS = {
    "n4sid": lambda d: sysid.n4sid(d, 2),
    "moesp": lambda d: sysid.moesp(d, 2),
    "ssest": lambda d: sysid.ssest(d, 2),
    # its defaults (order and feedthrough chosen from the data) said it three times
    "ssest defaults": lambda d: sysid.ssest(d),
    "pem": lambda d: sysid.pem(d, sysid.StateSpaceModel(
        [[0.5, 0.0], [0.0, 0.3]], [[1.0], [1.0]], [[1.0, 1.0]], dt=1.0)),
    "arx": lambda d: sysid.arx(d, 2, 2, 1),
    "armax": lambda d: sysid.armax(d, 2, 2, 1, 1),
    "oe": lambda d: sysid.oe(d, 2, 2, 1),
    "bj": lambda d: sysid.bj(d, 2, 1, 1, 2, 1),
    "iv4": lambda d: sysid.iv4(d, 2, 2, 1),
    # a transfer function and a process model have no constant term either (a heat exchanger
    # record at 97 degrees: validation fits of -1579 % and -1267 % without a word)
    "tfest": lambda d: sysid.tfest(d, 2),
    "procest": lambda d: sysid.procest(d, "P2"),
}


@pytest.mark.parametrize("name", list(ESTIMATORS))
def test_every_linear_estimator_warns_once_about_offsets(name):
    fit = ESTIMATORS[name]
    raw = _raw_record()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            fit(raw)
        except sysid.SysidError:
            pass  # the warning is the point; a fit may fail on such data
    offs = [w for w in caught if issubclass(w.category, OffsetWarning)]
    assert len(offs) == 1, [(w.filename, w.lineno) for w in offs]
    msg = str(offs[0].message)
    assert "output y0 has an offset (300" in msg and "input u0" in msg
    assert "sysid.detrend" in msg and "sysid.identify" in msg and "trend.apply" in msg
    assert offs[0].filename == __file__  # points at the caller's line
    # detrended: silent
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit(sysid.detrend(raw, "mean"))
    assert not [w for w in caught if issubclass(w.category, OffsetWarning)]


def test_offset_warning_is_a_user_warning_with_a_docstring():
    assert issubclass(OffsetWarning, UserWarning) and OffsetWarning.__doc__
    assert sysid.OffsetWarning is OffsetWarning


def test_a_raw_record_merged_into_a_detrended_one_still_warns():
    # merge labelled the whole result "detrended", and the raw part's offset went unseen
    rng = np.random.default_rng(3)
    u = rng.standard_normal(600)
    y = 96.0 + sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]).simulate(u)[:, 0]
    y = y + 0.05 * rng.standard_normal(600)
    d = sysid.IOData(u=u, y=y, dt=1.0)
    est, val = d.split(0.5)
    merged = sysid.detrend(est, "mean").merge(val)
    with pytest.warns(sysid.OffsetWarning, match="offset"):
        sysid.n4sid(merged, 1)
    both = sysid.detrend(est, "mean").merge(sysid.detrend(val, "mean"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.OffsetWarning)
        sysid.n4sid(both, 1)


def test_ar_and_ssi_run_the_offset_check():
    # ar fitted a series at +100 silently (a pole at 0.9996 for 0.837); ssi lost a mode to
    # an offset of 22 standard deviations and returned a damping of -1, without a word
    rng = np.random.default_rng(4)
    y = 100.0 + np.convolve(rng.standard_normal(2000), [1.0, 0.6, 0.2])[:2000]
    with pytest.warns(sysid.OffsetWarning, match="offset"):
        m = sysid.ar(sysid.IOData(None, y[:, None], 1.0, output_names=["level"]), 2)
    assert m.output_names == ["level"]  # the data's name (it came back as y0)
    yy = np.column_stack([y, 0.5 * y + rng.standard_normal(2000)])
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        try:
            sysid.ssi(sysid.IOData(None, yy, 0.1), range(2, 5, 2))
        except sysid.SysidError:
            pass
    assert any(issubclass(w.category, sysid.OffsetWarning) for w in rec)


def _step_from_rest(n=400, level=50.0, seed=3):
    """A step test from rest: the input switched from 0 to ``level`` after one sample, the
    output a first-order response measured from its initial value (as a TCLab heater test)."""
    rng = np.random.default_rng(seed)
    u = np.r_[0.0, np.full(n - 1, level)]
    true = sysid.StateSpaceModel([[0.98]], [[1.0]], [[0.02]], dt=1.0)
    y = true.simulate(u).ravel() + 0.05 * rng.standard_normal(n)
    return sysid.IOData(u=u, y=y - y[0], dt=1.0)


def test_a_step_from_rest_is_not_an_offset():
    """A heater step test (0 -> 50 % after one sample, 800 samples) warned 'input u0 has an
    offset (49.91) much larger than its variation (std 2.16)' and told the user to remove the
    mean, which moves the record's start off rest: the step is the excitation, not an
    offset. A channel whose values reach zero is not flagged; one that never does still is."""
    rest = _step_from_rest()
    assert abs(rest.u.mean()) > 10 * rest.u.std()  # the ratio the check flags at
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = sysid.oe(rest, 1, 1, 1)
    assert not [w for w in caught if issubclass(w.category, OffsetWarning)]
    assert abs(m.poles()[0] - 0.98) < 0.01  # from rest, the step determines the plant
    acts = [f.topic for f in sysid.advice(rest).findings if f.verdict == "act"]
    assert "offsets" not in acts
    # the same test measured in kelvin: the output's offset is real, the input's still not
    hot = sysid.IOData(u=rest.u, y=rest.y + 300.0, dt=1.0)
    with pytest.warns(OffsetWarning) as caught:
        sysid.oe(hot, 1, 1, 1)
    msg = str(caught[0].message)
    assert "output y0 has an offset" in msg and "input u0" not in msg
