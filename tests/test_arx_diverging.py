"""arx and armax say when their model's simulation diverges (issue 26: no unstable model
returned silently). Both used to return a pole on or outside the unit circle without a word,
where n4sid on the same record warned (the unshipped EMPS servo record: 1 + 5e-5)."""
import warnings

import numpy as np
import pytest

import sysid


def _record(unstable: bool, seed: int = 0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    n = 800
    u = rng.standard_normal((n, 1))
    y = np.zeros((n, 1))
    a = 1.003 if unstable else 0.8  # slowly unstable: the estimate lands outside the circle
    for t in range(1, n):
        y[t] = a * y[t - 1] + 0.5 * u[t - 1, 0]
    return sysid.IOData(u=u, y=y + 0.01 * rng.standard_normal((n, 1)), dt=1.0)


@pytest.mark.parametrize("fit", [lambda d: sysid.arx(d, 1, 1, 1),
                                 lambda d: sysid.arx(d, 1, 1, 1, regularization=(1e-6, np.eye(2))),
                                 lambda d: sysid.armax(d, 1, 1, 1, 1)],
                         ids=["arx", "arx (lam, R)", "armax"])
def test_a_diverging_simulation_is_named(fit):
    with pytest.warns(sysid.StabilityWarning, match=r"pole .* >= 1.*predictor is stable"):
        m = fit(_record(unstable=True, seed=1))
    assert np.max(np.abs(m.poles())) >= 1.0


@pytest.mark.parametrize("fit", [lambda d: sysid.arx(d, 1, 1, 1),
                                 lambda d: sysid.armax(d, 1, 1, 1, 1)], ids=["arx", "armax"])
def test_a_stable_fit_is_silent(fit):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = fit(_record(unstable=False))
    assert np.max(np.abs(m.poles())) < 1.0
