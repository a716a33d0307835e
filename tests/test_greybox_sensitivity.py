"""Nonlinear grey-box Jacobians by the forward sensitivity equations (sysid.NonlinearGreyBox
with dfdx/dfdp/dhdx/dhdp or jacobian="sensitivity")."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid import _sysid
from sysid.errors import DataError

VALS = {"w2": 9.0, "c": 0.4, "b": 2.0}


def f(t, x, u, p):
    return [x[1], -p.w2 * np.sin(x[0]) - p.c * x[1] + p.b * u[0]]


def h(t, x, u, p):
    return [x[0], x[0] * x[1]]


def dfdx(t, x, u, p):
    return [[0.0, 1.0], [-p.w2 * np.cos(x[0]), -p.c]]


def dfdp(t, x, u, p):
    return {"w2": [0.0, -np.sin(x[0])], "c": [0.0, -x[1]], "b": [0.0, u[0]]}


def dhdx(t, x, u, p):
    return [[1.0, 0.0], [x[1], x[0]]]


def dhdp(t, x, u, p):
    return np.zeros((2, 3))


def _structure(**kw):
    return sysid.NonlinearGreyBox(f, h, VALS, nx=2, x0=[0.6, -0.2], **kw)


def _jacobian(s, u, dt, vals=None, x01=-0.2):
    """Outputs and Jacobian in (w2, c, b, x0[1]) from the core, by the structure's method."""
    vals = VALS if vals is None else vals
    free = s.free_names
    return _sysid.greybox_ode_jacobian(
        s.rhs(), s.out(), [u], (2, [vals[k] for k in s.names], [0, 1, 2], [[0.6, x01]],
                                [(0, 1)], [1.0] * 4),
        dt, integration=s.core_options(), jacobian=s.jacobian_options(free))


@pytest.mark.parametrize("integrator,given,tol", [
    ("rk4", True, 1e-6), ("rk4", False, 1e-6), ("adaptive", True, 1e-3)])
def test_sensitivity_jacobian_equals_central_differences(integrator, given, tol):
    """RK4 applied to (x, S) is the exact derivative of the RK4 simulation, so the
    sensitivities agree with central differences of the simulation to their truncation error
    (~1e-10 here); with the adaptive integrator the steps themselves move with the
    parameters, so the agreement is at the integrator's tolerance."""
    dt = 0.05
    u = np.repeat(np.random.default_rng(0).standard_normal(6), 10)[:, None]
    kw = dict(dfdx=dfdx, dfdp=dfdp, dhdx=dhdx, dhdp=dhdp) if given else \
        dict(jacobian="sensitivity")
    rtol = 1e-10 if integrator == "rk4" else 1e-8
    s = _structure(integrator=integrator, rtol=rtol, atol=rtol / 100, substeps=2, **kw)
    assert s.jacobian_method == "sensitivity"
    y, J = _jacobian(s, u, dt)
    plain = _structure(integrator=integrator, rtol=rtol, atol=rtol / 100, substeps=2)
    assert plain.jacobian_method == "fd"
    y_fd, J_fwd = _jacobian(plain, u, dt)
    np.testing.assert_allclose(y, y_fd, atol=100 * rtol)  # the same simulation
    # central differences of the simulated outputs (the FD columns of the core are forward)
    cols = []
    for k in range(4):
        step = 1e-5
        up, dn = dict(VALS), dict(VALS)
        x_up = x_dn = -0.2
        if k < 3:
            name = ["w2", "c", "b"][k]
            up[name] += step
            dn[name] -= step
        else:
            x_up, x_dn = -0.2 + step, -0.2 - step
        yp = _jacobian(plain, u, dt, up, x_up)[0]
        ym = _jacobian(plain, u, dt, dn, x_dn)[0]
        cols.append(((yp - ym) / (2 * step)).ravel())
    J_cd = np.column_stack(cols)
    err = np.max(np.abs(J - J_cd)) / np.max(np.abs(J_cd))
    assert err < tol, err
    # the forward differences of the default route are ~1e-6 off, the sensitivities closer
    assert np.max(np.abs(J_fwd - J_cd)) / np.max(np.abs(J_cd)) < 1e-4


def test_sensitivity_estimate_equals_the_difference_estimate():
    dt = 0.05
    rng = np.random.default_rng(6)
    u = np.repeat(rng.standard_normal(16), 15)[:, None]
    y = _structure().simulate(u, dt=dt)
    y = y + 0.01 * rng.standard_normal(y.shape)
    data = sysid.IOData(u=u, y=y, dt=dt)
    start = {"w2": 8.0, "c": 0.3, "b": sysid.param(1.7, bounds=(0, 10))}
    fits = {}
    for name, kw in (("fd", dict(vectorized=True)),
                     ("sens", dict(dfdx=dfdx, dfdp=dfdp, dhdx=dhdx, dhdp=dhdp)),
                     ("sens-cd", dict(jacobian="sensitivity", vectorized=True))):
        s = sysid.NonlinearGreyBox(f, h, start, nx=2, x0=[0.5, -0.2],
                                   x0_free=[True, False], **kw)
        fits[name] = sysid.greyest(data, s)
    fd, sens = fits["fd"], fits["sens"]
    assert fd.info["jacobian"] == "fd" and sens.info["jacobian"] == "sensitivity"
    std = fd.parameters.std[:3]
    for other in (sens, fits["sens-cd"]):
        d = np.abs(other.parameters.value - fd.parameters.value)[:3] / std
        assert np.all(d < 1e-3), d
        np.testing.assert_allclose(other.parameters.std, fd.parameters.std, rtol=1e-3)
        assert abs(other.initial_states[0][0] - fd.initial_states[0][0]) < 1e-6
    z = (sens.parameters.value - [9.0, 0.4, 2.0]) / sens.parameters.std
    assert np.all(np.abs(z) < 4), z


def test_derivative_errors_name_the_problem():
    dt = 0.05
    u = np.ones((20, 1))
    data = sysid.IOData(u=u, y=_structure().simulate(u, dt=dt), dt=dt)
    bad = _structure(dfdx=lambda t, x, u, p: np.eye(3), dfdp=dfdp)
    with pytest.raises(DataError, match="d/dx"):
        sysid.greyest(data, bad)
    bad = _structure(dfdx=dfdx, dfdp=lambda t, x, u, p: {"nope": [0.0, 1.0]})
    with pytest.raises(DataError, match="nope"):
        sysid.greyest(data, bad)
    with pytest.raises(DataError, match="jacobian"):
        _structure(jacobian="exact")
    # "fd" ignores given derivatives
    assert _structure(dfdx=dfdx, dfdp=dfdp, jacobian="fd").jacobian_method == "fd"
