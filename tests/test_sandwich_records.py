"""The sandwich covariance for coloured simulation errors (``sysid.pem.sandwich``) beyond one
record from rest: several records, an estimated initial state, the noise weighting of
``pem`` and ``greyest``. Monte Carlo: the stated standard deviation of the static gain
against its spread over the runs, and the 95 % intervals' coverage."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import lfilter

import sysid
from sysid.pem.sandwich import gauss_newton


def _ar(rng: np.random.Generator, n: int, sigma: float, pole: float = 0.9) -> np.ndarray:
    return lfilter([1.0], [1.0, -pole], sigma * rng.standard_normal(n))


def _check(err: list[float], std: list[float], what: str) -> None:
    e, s = np.asarray(err), np.asarray(std)
    ratio = float(np.sqrt(np.mean(s ** 2)) / np.std(e, ddof=1))
    cover = float(np.mean(np.abs(e) <= 1.96 * s))
    assert 0.75 < ratio < 1.3, (what, ratio, cover)
    assert 0.88 <= cover <= 0.995, (what, ratio, cover)


def _quietly(fit, *args, **kwargs):  # type: ignore[no-untyped-def]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit(*args, **kwargs)


def test_two_records_oe_and_pem() -> None:
    """Two records of an output-error plant with an AR(1) disturbance: the records' terms
    add (before, with more than one record, the Gauss-Newton covariance: half the spread)."""
    plant = sysid.StateSpaceModel([[0.8]], [[0.5]], [[1.0]])
    err: dict[str, list[float]] = {"oe": [], "pem": [], "gauss-newton": []}
    std: dict[str, list[float]] = {"oe": [], "pem": [], "gauss-newton": []}
    for run in range(150):
        rng = np.random.default_rng(4100 + run)
        us = [rng.standard_normal((250, 1)) for _ in range(2)]
        ys = [plant.simulate(u) + _ar(rng, 250, 0.1, 0.8)[:, None] for u in us]
        d = sysid.IOData(us, ys, 1.0)
        fits = {"oe": (sysid.oe, (d, 1, 1, 1), {})}
        if run < 80:
            fits["pem"] = (sysid.pem, (d, plant), {"focus": "simulation"})
        for k, (fit, args, kwargs) in fits.items():
            m = _quietly(fit, *args, **kwargs)
            if k == "oe":
                gn = gauss_newton(m.uncertainty).propagate(lambda g: g.dcgain().ravel())
                err["gauss-newton"].append(float(gn.value[0]) - 2.5)
                std["gauss-newton"].append(float(gn.std[0]))
            g, s = m.dcgain(std=True)
            err[k].append(float(np.ravel(g)[0]) - 2.5)
            std[k].append(float(np.ravel(s)[0]))
            note = m.info["covariance"] if k == "oe" else m.info["pem"]["covariance"]
            assert note.startswith("sandwich for coloured simulation errors on 2 records"), note
    for k in ("oe", "pem"):
        _check(err[k], std[k], k)
    e, s = np.asarray(err["gauss-newton"]), np.asarray(std["gauss-newton"])
    assert np.sqrt(np.mean(s ** 2)) < 0.7 * np.std(e, ddof=1)


@pytest.mark.parametrize("focus", ["simulation", "prediction"])
def test_greyest_simulation_focus(focus: str) -> None:
    """``greyest(focus="simulation")`` with an AR(1) output disturbance: the sandwich
    (before, the Gauss-Newton covariance: a third of the spread). The same for the default
    ``focus="prediction"`` of a structure without ``K``: its prediction errors are the
    simulation errors (before, also a third of the spread, intervals covering 40 %)."""
    def first_order(p, dt=None):  # type: ignore[no-untyped-def]
        return [[-p.a]], [[p.b]], [[1.0]], [[0.0]]

    u = np.repeat(np.random.default_rng(1).choice([-1.0, 1.0], 31), 10)[:300, None]
    y0 = sysid.GreyBox(first_order, {"a": 1.0, "b": 2.0}).model(dt=0.1).simulate(u)
    err: list[float] = []
    std: list[float] = []
    for run in range(120):
        v = _ar(np.random.default_rng(5200 + run), 300, 0.02)[:, None]
        fit = _quietly(sysid.greyest, sysid.IOData(u, y0 + v, 0.1),
                       sysid.GreyBox(first_order, {"a": 1.0, "b": 2.0}),
                       focus=focus, x0="zero")
        assert fit.info["covariance"].startswith("sandwich for coloured"), fit.info
        g, s = fit.model.dcgain(std=True)
        err.append(float(np.ravel(g)[0]) - 2.0)
        std.append(float(np.ravel(s)[0]))
        assert np.isclose(fit.parameters["b"]["std"], np.sqrt(fit.covariance[1, 1]))
    _check(err, std, "greyest")


def test_pem_noise_weighting_two_outputs() -> None:
    """``pem(focus="simulation", weighting="noise")`` on two outputs with coloured
    disturbances: the sandwich on the errors weighted by their inverse covariance (before,
    the Gauss-Newton covariance: 0.4 of the spread)."""
    plant = sysid.StateSpaceModel([[0.7, 0.0], [0.0, 0.5]], [[1.0, 0.0], [0.5, 1.0]],
                                  [[1.0, 0.0], [0.0, 1.0]])
    err: list[float] = []
    std: list[float] = []
    for run in range(80):
        rng = np.random.default_rng(6300 + run)
        u = rng.standard_normal((300, 2))
        v = np.column_stack([_ar(rng, 300, 0.1, 0.8), _ar(rng, 300, 0.05, 0.8)])
        m = _quietly(sysid.pem, sysid.IOData(u, plant.simulate(u) + v), plant,
                     focus="simulation", weighting="noise")
        g, s = m.dcgain(std=True)
        err.append(float(g[1, 0]) - 1.0)
        std.append(float(s[1, 0]))
    assert m.info["pem"]["covariance"].startswith("sandwich for coloured")
    _check(err, std, "pem noise weighting")


def test_tfest_estimated_initial_state() -> None:
    """``tfest(initial_state="estimate")`` with an AR(1) disturbance: the sandwich on the
    model's parameters, the initial state refitted for each (before: the Gauss-Newton
    covariance, half the spread)."""
    G = sysid.TransferFunction([2.0], [1.0, 1.0])
    u = np.repeat(np.random.default_rng(2).choice([-1.0, 1.0], 61), 10)[:600]
    y0 = G.simulate(u, dt=0.1)[:, 0]
    err: list[float] = []
    std: list[float] = []
    for run in range(120):
        v = _ar(np.random.default_rng(7400 + run), 600, 0.03, 0.8)
        m = _quietly(sysid.tfest, sysid.IOData(u, y0 + v, 0.1), 1, 0, init=G,
                     initial_state="estimate")
        g, s = m.dcgain(std=True)
        err.append(float(np.ravel(g)[0]) - 2.0)
        std.append(float(np.ravel(s)[0]))
    assert m.info["covariance"].startswith("sandwich for coloured"), m.info["covariance"]
    _check(err, std, "tfest initial_state='estimate'")


def _naive_free_response(A, C, N):
    out, X = np.empty((N, C.shape[0], A.shape[0])), np.eye(A.shape[0])
    with np.errstate(all="ignore"):
        for t in range(N):
            out[t], X = C @ X, A @ X
    return out


def test_the_free_response_is_the_recursion_s_and_stops_where_it_has_decayed():
    from sysid.pem.sandwich import DECAYED, free_response

    rng = np.random.default_rng(0)
    Q = np.linalg.qr(rng.standard_normal((4, 4)))[0]
    slow = Q @ np.diag([0.96, -0.9, 0.5, 0.1]) @ Q.T  # sinks into subnormals over 20 000
    shear = np.array([[0.9, 50.0], [0.0, 0.9]])  # a transient 20 times its start first
    C = rng.standard_normal((2, 4))
    for A, c in ((slow, C), (shear, C[:, :2])):
        ref, got = _naive_free_response(A, c, 20000), free_response(A, c, 20000)
        scale = np.max(np.abs(ref))
        assert np.max(np.abs(got - ref)) <= 1e-12 * scale
        # past the decay the response is zero, not subnormal (a run on there was 40x slower)
        last = int(np.max(np.flatnonzero(np.any(got != 0, axis=(1, 2)))))
        assert last < 5000 and np.max(np.abs(ref[last + 1:])) < DECAYED * scale
    # an unstable A overflows: not finite, as the callers check
    assert not np.all(np.isfinite(free_response(np.array([[1.5]]), np.array([[1.0]]), 5000)))


def test_huge_jacobian_does_not_overflow() -> None:
    """The correction is scale-free: simulation and record scaled by 1e100 (a process model's
    Jacobian along a time constant at its bound reached 6e180) give the covariance of the
    unscaled ones (before: ``sigma2 ** 2`` of a Python float raised OverflowError, out of
    ``model.std``, ``summary()`` and ``compare``)."""
    from sysid.pem.sandwich import sandwich_covariance

    rng = np.random.default_rng(3)
    u = rng.standard_normal(800)
    y = lfilter([0.0, 0.5], [1.0, -0.8], u) + _ar(rng, 800, 0.1)
    m = _quietly(sysid.oe, sysid.IOData(u, y, 1.0), 1, 1, 1)
    gn = gauss_newton(m.uncertainty)
    base, note = sandwich_covariance(gn, lambda g: g.simulate(u), y)
    big, note_big = sandwich_covariance(gn, lambda g: 1e100 * g.simulate(u), 1e100 * y)
    assert note.startswith("sandwich") and note_big.startswith("sandwich")
    np.testing.assert_allclose(big.covariance, base.covariance, rtol=1e-6)
