"""``sysid identify`` on a time series (no ``--inputs``): its subspace fit at the time-series
default horizons (:mod:`sysid.subspace.series_horizon`), as ``sysid.moesp(data, n)``."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import signal

import sysid
from sysid import _sysid
from sysid.cli import identify as run_identify

pytestmark = pytest.mark.skipif(not hasattr(_sysid, "Subspace"),
                                reason="the subspace engine is not in this build yet")


def _series(n: int = 2000, outputs: int = 1) -> sysid.IOData:
    rng = np.random.default_rng(0)
    e = rng.standard_normal((n, outputs))
    y = np.column_stack([signal.lfilter([1.0, 0.5], [1, -1.5, 0.7], e[:, 0])]
                        + [signal.lfilter([1.0], [1, -0.6 + 0.1 * k], e[:, k] + 0.5 * e[:, 0])
                           for k in range(1, outputs)])
    return sysid.IOData(None, y, 1.0)


@pytest.mark.parametrize("outputs", [1, 2])
def test_the_chosen_order_is_fitted_at_its_default_horizons(outputs: int) -> None:
    d = _series(outputs=outputs)
    est, val = d.slice(0, 1400), d.slice(1400, 2000)
    out = run_identify(est, val)
    m = out["model"]
    n = m.nstates
    ref = sysid.moesp(est, n)  # the time-series default for n states
    sel = ref.info["horizon_selection"]
    assert sel["future"] == -(-n // outputs) + 1 < sel["past"]  # shorter than the sweep's
    # before, the model kept the sweep's future (= past) and its rule said so
    assert m.info["settings"]["future"] == sel["future"]
    assert m.info["settings"]["past"] == sel["past"]
    assert m.info["horizon_selection"]["future"] == sel["future"]
    np.testing.assert_allclose(np.sort_complex(m.poles()), np.sort_complex(ref.poles()),
                               rtol=1e-9)
    np.testing.assert_allclose(m.C, ref.C, rtol=1e-9, atol=1e-12)


def test_a_given_order_takes_the_default_of_its_order() -> None:
    d = _series()
    est, val = d.slice(0, 1400), d.slice(1400, 2000)
    out = run_identify(est, val, order=2)
    ref = sysid.moesp(est, 2)
    assert out["model"].info["settings"]["future"] == ref.info["horizon_selection"]["future"]
    np.testing.assert_allclose(np.sort_complex(out["model"].poles()),
                               np.sort_complex(ref.poles()), rtol=1e-9)
    # an order above the autoregression's: the record's horizon, as moesp (it was refused:
    # "larger than the data and horizon support", the sweep's past of p + 1 allowing p)
    p = ref.info["horizon_selection"]["ar_order"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # orders above the process's: unstable, said
        out = run_identify(est, val, order=p + 3)
        ref = sysid.moesp(est, p + 3)
    assert out["model"].nstates == p + 3
    assert out["model"].info["settings"]["past"] == ref.info["settings"]["past"]
    np.testing.assert_allclose(np.sort_complex(out["model"].poles()),
                               np.sort_complex(ref.poles()), rtol=1e-9)


def test_a_given_horizon_is_kept() -> None:
    d = _series()
    out = run_identify(d.slice(0, 1400), d.slice(1400, 2000), horizon=10)
    assert out["model"].info["settings"]["past"] == out["model"].info["settings"]["future"] == 10
