"""A ``(u, y)`` pair of arrays is a record (``dt = 1``) for every discrete-time estimator, as
for ``ssest``, ``arx`` and ``compare``; the tools whose frequency axis follows the sample
time refuse it and name the fix."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError

PLANT = sysid.StateSpaceModel([[0.8, 0.2], [-0.2, 0.7]], [[1.0], [0.4]], [[1.0, 0.5]])


def record() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    u = rng.standard_normal((400, 1))
    y = PLANT.simulate(u) + 0.05 * np.tanh(PLANT.simulate(u)) ** 3
    return u, y + 0.01 * rng.standard_normal(y.shape)


FITS = {
    "n4sid": lambda d: sysid.n4sid(d, 2),
    "moesp": lambda d: sysid.moesp(d, 2, feedthrough=True),
    "cva": lambda d: sysid.cva(d),
    "pbsid": lambda d: sysid.pbsid(d, 2),
    "ssarx": lambda d: sysid.ssarx(d, 2),
    "pnlss": lambda d: sysid.pnlss(d, 2, degree=2, max_iter=3),
    "nlhw_ss": lambda d: sysid.nlhw_ss(d, 2, max_iter=3),
    "nlhw": lambda d: sysid.nlhw(d, 2, 2, 1, max_iter=3),
    "nlarx": lambda d: sysid.nlarx(d, 2, 2, 1),
}


@pytest.mark.parametrize("name", sorted(FITS))
def test_a_pair_of_arrays_fits_the_model_the_record_fits(name):
    u, y = record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = FITS[name]((u, y))
        b = FITS[name](sysid.IOData(u=u, y=y))
    ya, yb = a.simulate(u), b.simulate(u)
    assert np.all(np.isfinite(ya))
    np.testing.assert_allclose(ya, yb, rtol=0, atol=1e-12 * np.max(np.abs(yb)))


def test_the_checks_take_a_pair_too():
    u, y = record()
    d = sysid.IOData(u=u, y=y)
    assert sysid.check_feedback((u, y)).p_value == sysid.check_feedback(d).p_value
    assert sysid.delayest((u, y)) == sysid.delayest(d)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = sysid.SubspaceEstimator((u, y))
    np.testing.assert_array_equal(est.singular_values,
                                  sysid.SubspaceEstimator(d).singular_values)


@pytest.mark.parametrize("name", ["spa", "etfe", "spectra", "coherence", "bla"])
def test_the_frequency_tools_refuse_a_pair_and_name_the_fix(name):
    u, y = record()
    with pytest.raises(DataError, match=rf"{name} takes an IOData record, got tuple: "
                                        rf"wrap the arrays first, sysid\.{name}\(sysid\.IOData"):
        getattr(sysid, name)((u, y), **({"periods": 2} if name == "bla" else {}))


@pytest.mark.parametrize("bad", [np.zeros((10, 2)), [1.0, 2.0], (np.zeros(5),)])
def test_anything_else_is_refused_by_name(bad):
    with pytest.raises(DataError, match="n4sid takes an IOData record or a \\(u, y\\) pair"):
        sysid.n4sid(bad, 1)
    with pytest.raises(DataError, match="pnlss takes an IOData record or a \\(u, y\\) pair"):
        sysid.pnlss(bad, 1)
