"""The nonlinear state-space fits refuse an oversampled record with the decimation that helps
(:func:`sysid.nlss.common.linear_start`): their linear start sees only the training part, too
short for the subspace estimators' own note, which named a richer input instead."""

import warnings

import numpy as np
import pytest

import sysid


def _pendulum(n: int = 1001) -> sysid.IOData:
    # a lightly damped 0.45 Hz pendulum with a quadratic sensor, logged at 20 Hz while a chirp
    # sweeps it from 0.09 to 0.7 Hz: its input needs half the rate it is logged at
    dt, wn, z = 0.05, 2 * np.pi * 0.45, 0.05
    ct = sysid.ContinuousStateSpace([[0.0, 1.0], [-wn ** 2, -2 * z * wn]], [[0.0], [wn ** 2]],
                                    [[1.0, 0.0]])
    t = np.arange(n) * dt
    u = np.sin(2 * np.pi * (0.09 + 0.61 * t / t[-1] / 2) * t)
    x = sysid.c2d(ct, dt).simulate(u)
    y = x + 0.1 * x ** 2 + 0.01 * np.random.default_rng(0).standard_normal((n, 1))
    return sysid.IOData(u=u, y=y, dt=dt)


@pytest.mark.parametrize("fit", [lambda d: sysid.nlssest(d, 2, progress=False),
                                 lambda d: sysid.pnlss(d, 2)], ids=["nlssest", "pnlss"])
def test_an_oversampled_record_is_refused_with_the_decimation_that_fits(fit) -> None:
    data = _pendulum()
    with pytest.raises(sysid.ExcitationError, match=r"sysid\.decimate\(data, 2\)") as said:
        fit(data)
    assert said.value.remedy.startswith("the inputs change slowly")
    assert "rows of future inputs" in said.value.problem  # the subspace fit's own finding
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = fit(sysid.decimate(data, 2))  # the advice taken: the fit runs
    assert model.dt == pytest.approx(0.1)
    assert np.all(np.isfinite(model.simulate(sysid.decimate(data, 2).u)))
