"""Saving and loading estimated nonlinear grey-box models (functions by reference)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


def tank(t, x, u, p):
    return [-p.a * np.sqrt(np.maximum(x[0], 0.0)) + p.b * u[0]]


def level(t, x, u, p):
    return [x[0]]


def dtank_dx(t, x, u, p):
    return [[-p.a * 0.5 / np.sqrt(max(x[0], 1e-12))]]


def dtank_dp(t, x, u, p):
    return {"a": [-np.sqrt(max(x[0], 0.0))], "b": [u[0]]}


@pytest.fixture(scope="module")
def fitted():
    dt = 0.1
    rng = np.random.default_rng(0)
    u = (1.0 + 0.5 * np.repeat(rng.standard_normal(15), 10))[:, None]
    truth = sysid.NonlinearGreyBox(tank, level, {"a": 0.5, "b": 1.0}, nx=1, x0=[1.0],
                                   vectorized=True)
    y = truth.simulate(u, dt=dt) + 0.01 * rng.standard_normal((150, 1))
    s = sysid.NonlinearGreyBox(
        tank, level, {"a": sysid.param(0.3, bounds=(0.0, 2.0), unit="m^0.5/s"),
                      "b": 0.8, "g": sysid.fixed(9.81, description="unused")},
        nx=1, x0=[0.9], x0_free=True, vectorized=True, dfdx=dtank_dx, dfdp=dtank_dp,
        integrator="rk4", substeps=2)
    return sysid.greyest(sysid.IOData(u=u, y=y, dt=dt, input_names=["q"],
                                      output_names=["h"]), s), u


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_round_trip(fitted, tmp_path, suffix):
    fit, u = fitted
    m = fit.model
    path = tmp_path / f"tank{suffix}"
    sysid.save_model(m, path)
    back = sysid.load_model(path)
    assert isinstance(back, sysid.NonlinearGreyBox)
    assert back.f is tank and back.h is level and back.dfdx is dtank_dx
    assert back.dhdx is None and back.jacobian_method == "sensitivity"
    for k in ("a", "b", "g"):
        assert back.params[k] == m.params[k]          # value, bounds, fixed, scale, unit
    assert back.params["a"].bounds == (0.0, 2.0) and back.params["g"].fixed
    np.testing.assert_array_equal(back.x0, m.x0)
    np.testing.assert_array_equal(back.x0_free, m.x0_free)
    assert back.dt == m.dt == 0.1 and back.substeps == 2
    assert back.input_names == ["q"] and back.output_names == ["h"]
    np.testing.assert_array_equal(back.simulate(u), m.simulate(u))
    np.testing.assert_array_equal(back.uncertainty.covariance, m.uncertainty.covariance)
    assert back.uncertainty.names == ["a", "b"]
    np.testing.assert_array_equal(back.uncertainty.std, fit.parameters.std[:2])
    rows, rows0 = back.info["greybox"]["parameters"], m.info["greybox"]["parameters"]
    assert [{**r, "ci95": list(r["ci95"])} for r in rows0] == rows   # JSON: tuples -> lists
    # the loaded model propagates its uncertainty like the original
    g0 = m.uncertainty.propagate(lambda s: s.simulate(u[:20])[-1])
    g1 = back.uncertainty.propagate(lambda s: s.simulate(u[:20])[-1])
    np.testing.assert_allclose(g1.std, g0.std, rtol=1e-12)


def test_functions_that_cannot_be_imported_are_named(fitted, tmp_path):
    fit, _ = fitted
    s = sysid.NonlinearGreyBox(lambda t, x, u, p: [-x[0]], level, {"a": 1.0}, nx=1)
    with pytest.raises(DataError, match=r"f is a lambda.*def"):
        sysid.save_model(s, tmp_path / "x.json")

    def local_h(t, x, u, p):
        return [x[0]]
    s = sysid.NonlinearGreyBox(tank, local_h, {"a": 1.0, "b": 1.0}, nx=1)
    with pytest.raises(DataError, match=r"h \(local_h\) is defined inside another function"):
        sysid.save_model(s, tmp_path / "x.json")
    main = sysid.NonlinearGreyBox(tank, level, {"a": 1.0, "b": 1.0}, nx=1)
    fake = type(tank)(tank.__code__, {"np": np, "__name__": "__main__"}, "tank")
    main.f = fake
    with pytest.raises(DataError, match=r"__main__.*top level of a module"):
        sysid.save_model(main, tmp_path / "x.json")
    # a file whose module has gone: the error names the function and what to do
    path = tmp_path / "tank.json"
    sysid.save_model(fit.model, path)
    d = json.loads(path.read_text())
    d["functions"]["h"] = "gone_module_xyz:level"
    path.write_text(json.dumps(d))
    with pytest.raises(DataError, match=r"cannot import h = gone_module_xyz:level.*sys.path"):
        sysid.load_model(path)
