"""The subspace estimators warn (StabilityWarning) whenever they return an unstable model
(issue 26: n4sid(order=3) on a level-control record returned one silently)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import StabilityWarning


def _unstable_record(n=300, seed=0):
    """A slowly diverging process (pole 1.015) with a stable mode: any honest estimate of it
    is unstable."""
    rng = np.random.default_rng(seed)
    true = sysid.StateSpaceModel(np.diag([1.015, 0.5]), [[0.05], [1.0]], [[1.0, 1.0]], dt=1.0)
    u = rng.standard_normal(n)
    return sysid.IOData(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal((n, 1)), dt=1.0)


FITS = {
    "n4sid": lambda d, **k: sysid.n4sid(d, 2, **k),
    "moesp": lambda d, **k: sysid.moesp(d, 2, **k),
    "cva": lambda d, **k: sysid.cva(d, 2, **k),
    "pbsid": lambda d, **k: sysid.pbsid(d, 2, **k),
    "ssarx": lambda d, **k: sysid.ssarx(d, 2, **k),
    "SubspaceEstimator.fit": lambda d, **k: sysid.SubspaceEstimator(d).fit(2, **k),
}


@pytest.mark.parametrize("name", list(FITS))
def test_unstable_subspace_model_warns_with_the_pole_and_the_remedy(name):
    data = _unstable_record()
    with pytest.warns(StabilityWarning) as rec:
        model = FITS[name](data)
    assert not model.is_stable()
    msg = str(rec[0].message)
    top = float(np.max(np.abs(model.poles())))
    assert f"{top:.4g}" in msg and "focus='simulation'" in msg
    assert rec[0].filename == __file__
    if name in ("pbsid", "ssarx"):   # closed loop: no stable=True; pem is the remedy named
        assert "sysid.pem" in msg
        return
    assert "stable=True" in msg
    # the remedy it names works, silently
    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)
        assert FITS[name](data, stable=True).is_stable()


def test_stable_models_do_not_warn_and_the_class_is_documented():
    rng = np.random.default_rng(1)
    true = sysid.StateSpaceModel(np.diag([0.9, 0.5]), [[1.0], [1.0]], [[1.0, 1.0]], dt=1.0)
    u = rng.standard_normal(300)
    data = sysid.IOData(u=u, y=true.simulate(u) + 0.01 * rng.standard_normal((300, 1)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)
        for fit in FITS.values():
            assert fit(data).is_stable()
    assert issubclass(StabilityWarning, UserWarning) and StabilityWarning.__doc__
    assert sysid.StabilityWarning is StabilityWarning
