"""An output-error fit whose F ends on the unit circle says so (issue 26, trust by default).

The search keeps every F stable, and a pole held just inside the circle is said by the
boundary warning; but rounding can leave the returned pole on or just outside it: on a
detrended step record ``oe(data, 2, 2, 1)`` returned F = (1 - q^-1)(1 - 0.9989 q^-1)
(``|pole|`` = 1 + 2e-11 as computed), ``is_stable()`` False, its simulation a ramp, and no
warning, where ``arx`` warns about any unstable model it returns."""

from __future__ import annotations

import warnings

import numpy as np
from scipy.signal import lfilter

import sysid
from sysid.polynomial import estimators


def test_an_oe_model_returned_on_the_unit_circle_warns(monkeypatch):
    rng = np.random.default_rng(0)
    u = rng.standard_normal(800)
    y = lfilter([0.0, 0.5], [1.0, -0.9], u) + 0.05 * rng.standard_normal(800)
    data = sysid.IOData(u=u, y=y, dt=1.0)
    # the search's result with F's pole pushed to where rounding left it on the record
    on_circle = np.convolve([1.0, -(1.0 + 2e-11)], [1.0, -0.9989])[1:]
    search = estimators._sysid.polynomial_pem

    def ends_on_the_circle(*args):  # type: ignore[no-untyped-def]
        r = dict(search(*args))
        theta = np.array(r["theta"], float)
        theta[-2:] = on_circle
        r["theta"] = theta
        return r

    monkeypatch.setattr(estimators._sysid, "polynomial_pem", ends_on_the_circle)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = sysid.oe(data, 1, 2, 1)
    assert not m.is_stable()
    said = [str(w.message) for w in caught if issubclass(w.category, sysid.StabilityWarning)]
    assert len(said) == 1 and "oe returned an unstable model" in said[0]
    assert "smaller nf" in said[0] and "differenced output" in said[0]


def test_an_arma_model_with_a_pole_past_one_warns():
    """A random walk (no offset to warn about: it crosses zero): ``arma(y, 2, 1)`` returns A
    with a pole just past 1, as the series asks; that is now said, with what to do."""
    y = np.cumsum(np.random.default_rng(0).standard_normal(1000))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = sysid.arma(y, 2, 1)
    assert not m.is_stable()
    said = [str(w.message) for w in caught if issubclass(w.category, sysid.StabilityWarning)]
    assert len(said) == 1 and "arma returned an unstable model" in said[0]
    assert "differenced series" in said[0]
    # a stationary series stays quiet
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sysid.arma(lfilter([1.0, 0.5], [1.0, -0.7], np.random.default_rng(1)
                           .standard_normal(2000)), 1, 1)
