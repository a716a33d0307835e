"""Basis-function input augmentation: a known system linear in [u, f(u)] is recovered
exactly by ARX and by subspace on the augmented inputs."""

from __future__ import annotations

import numpy as np
import pytest

import sysid


def _system(n, seed):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, (n, 1))
    y = np.zeros((n, 1))
    for t in range(1, n):
        y[t] = 0.6 * y[t - 1] + u[t - 1] - 0.4 * u[t - 1] ** 3
    return u, y


def test_arx_and_subspace_on_augmented_inputs_are_exact():
    u, y = _system(800, 1)
    d = sysid.IOData(u, y, 1.0)
    m = sysid.augmented_fit(d, ["cube"], method="arx", na=1, nb=1)
    assert np.max(np.abs(m.simulate(u) - y)) < 1e-9
    ss = sysid.augmented_fit(d, [lambda v: v ** 3], method="n4sid", order=1)
    assert np.allclose(ss.poles().real, [0.6], atol=1e-6)
    uv, yv = _system(300, 2)
    assert np.max(np.abs(ss.simulate(uv) - yv)) < 1e-5
    # the augmentation matters: without the cube, a linear ARX misses
    lin = sysid.arx(d, 1, 1, 1)
    assert np.max(np.abs(lin.simulate(u) - y)) > 1e-2
    assert isinstance(m, sysid.Model) and m.freqresp(np.array([0.5])).shape == (1, 1, 1)


def test_augment_inputs_and_errors():
    u, y = _system(50, 3)
    d = sysid.augment_inputs(sysid.IOData(u, y, 1.0), ["square", "abs"])
    assert d.n_inputs == 3 and d.input_names == ["u0", "u0:square", "u0:abs"]
    with pytest.raises(sysid.DataError, match="unknown basis function"):
        sysid.augment_inputs(sysid.IOData(u, y, 1.0), ["sqrt"])
    with pytest.raises(sysid.DataError, match="order"):
        sysid.augmented_fit(sysid.IOData(u, y, 1.0), ["square"])
    with pytest.raises(sysid.DataError, match="method"):
        sysid.augmented_fit(sysid.IOData(u, y, 1.0), ["square"], method="pem", order=1)
