"""Hammerstein-Wiener fits on a binary input: a static input curve through two levels is any
curve, and the fit says so."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import ExcitationWarning


def _dryer():
    # the DaISy dryer: its heater input is a binary PRBS (3.41 V and 6.41 V)
    d = np.loadtxt(sysid.datasets.path("dryer"))
    return sysid.IOData(u=d[:500, :1], y=d[:500, 1:2], dt=0.08)


@pytest.mark.parametrize("fit", [
    lambda d: sysid.nlhw(d, 2, 2, 1, input_nl=sysid.SigmoidNetwork(3), output_nl=None),
    # a saturation on the dryer is fitted both about its means and not: said once
    lambda d: sysid.nlhw(d, 2, 2, 1, input_nl=sysid.Saturation(), output_nl=None),
    lambda d: sysid.nlhw_ss(d, 2, input_nl=sysid.SigmoidNetwork(3), output_nl=None),
])
def test_an_input_curve_fitted_through_two_levels_is_said(fit):
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        fit(_dryer())
    (w,) = [w for w in said if w.category is ExcitationWarning]
    assert "u0 takes 2 levels" in str(w.message) and "input_nl=None" in str(w.message)


def test_the_identity_an_output_curve_and_many_levels_are_not():
    d = _dryer()
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, (400, 1))
    y = np.convolve(np.tanh(2 * u[:, 0]), [0.0, 0.5, 0.3])[:400, None]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warnings.simplefilter("error", ExcitationWarning)
        sysid.nlhw(d, 2, 2, 1, input_nl=None, output_nl=sysid.SigmoidNetwork(3))
        sysid.nlhw(sysid.IOData(u, y, 1.0), 2, 2, 1, input_nl=sysid.SigmoidNetwork(3),
                   output_nl=None, max_iter=200)
