"""c2d/d2c methods MATLAB users expect beyond the holds: matched pole-zero, impulse invariant,
and Tustin with frequency prewarping (against scipy.signal.cont2discrete and python-control)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid

SETTINGS = settings(max_examples=30, deadline=None)


def _siso(seed: int, n: int, feedthrough: bool = True) -> sysid.ContinuousStateSpace:
    """A random stable SISO system, poles with |s| of order 1."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.3 + rng.random()) * np.eye(n)
    D = rng.standard_normal((1, 1)) if feedthrough else np.zeros((1, 1))
    return sysid.ContinuousStateSpace(A, rng.standard_normal((n, 1)),
                                      rng.standard_normal((1, n)), D)


def _grid(dt: float) -> np.ndarray:
    return np.linspace(0.0, 0.95 * np.pi / dt, 60)


def _root_dev(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance from a root of ``a`` to its match in ``b`` (greedy nearest)."""
    left, worst = list(np.asarray(b, complex)), 0.0
    assert len(left) == len(a)
    for r in np.asarray(a, complex):
        i = int(np.argmin(np.abs(np.asarray(left) - r)))
        worst = max(worst, abs(left.pop(i) - r))
    return worst


def _max_dev(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


# -- matched pole-zero --------------------------------------------------------------------


@SETTINGS
@given(seed=st.integers(0, 2**31), n=st.integers(1, 4), dt=st.floats(0.02, 0.5),
       feedthrough=st.booleans())
def test_matched_maps_poles_and_zeros_by_exp_and_keeps_the_dc_gain(
        seed: int, n: int, dt: float, feedthrough: bool) -> None:
    c = _siso(seed, n, feedthrough)
    d = sysid.c2d(c, dt, "matched")
    assert d.dt == dt and d.nstates == n and d.info["method"] == "c2d (matched)"
    assert _root_dev(d.poles(), np.exp(c.poles() * dt)) < 1e-9
    zc = c.zeros()
    np.testing.assert_allclose(d.dcgain(), c.dcgain(), rtol=1e-8,
                               atol=1e-10 * max(1.0, float(np.abs(c.dcgain()).max())))
    if zc.size and np.max(np.abs(zc * dt)) > 3:
        return  # e^{z dt} near 0 or huge: computed zeros and their logarithm lose digits
    # r - 1 of the r zeros at infinity go to the Nyquist frequency, as MATLAB's
    nyquist = -np.ones(max(n - zc.size - 1, 0))
    assert _root_dev(d.zeros(), np.r_[np.exp(zc * dt), nyquist]) < 1e-4
    back = sysid.d2c(d, "matched")  # the inverse gives the continuous model back
    w = np.linspace(0.0, 0.9 * np.pi / dt, 25)
    scale = max(1.0, float(np.abs(c.freqresp(w)).max()))
    assert _max_dev(back.freqresp(w), c.freqresp(w)) < 1e-7 * scale


@pytest.mark.parametrize("seed, n, dt", [(0, 1, 0.1), (1, 2, 0.05), (2, 3, 0.2), (3, 4, 0.3)])
def test_matched_agrees_with_python_control(seed: int, n: int, dt: float) -> None:
    control = pytest.importorskip("control")
    c = _siso(seed, n)
    ref = control.sample_system(control.ss2tf(control.ss(c.A, c.B, c.C, c.D)), dt,
                                method="matched")
    w = _grid(dt)
    mine = sysid.c2d(c, dt, "matched").freqresp(w)[:, 0, 0]
    # python-control leaves every zero at infinity there; MATLAB (and sysid) put all but one
    # at z = -1: the factor ((z + 1) / 2)^(r - 1), 1 at DC
    r = n - c.zeros().size
    theirs = control.frequency_response(ref, w).complex.ravel()
    theirs = theirs * ((np.exp(1j * w * dt) + 1) / 2) ** max(r - 1, 0)
    assert _max_dev(mine, theirs) < 1e-9 * max(1.0, float(np.abs(theirs).max()))


def test_matched_reproduces_matlabs_zero_at_the_nyquist_frequency() -> None:
    # MATLAB: c2d(tf(11, [1 1 0]), 0.1, 'matched') -> 0.052339 (z + 1) / ((z - 1)(z - 0.9048))
    # (MATLAB Answers 2175248, the zpk form of MATLAB's result)
    c = sysid.ContinuousStateSpace([[0.0, 1.0], [0.0, -1.0]], [[0.0], [11.0]], [[1.0, 0.0]])
    d = sysid.c2d(c, 0.1, "matched")
    np.testing.assert_allclose(d.zeros(), [-1.0], atol=1e-9)
    np.testing.assert_allclose(np.sort(d.poles().real), [np.exp(-0.1), 1.0], atol=1e-12)
    z = np.exp(0.7j)  # the gain: G(z) (z - 1)(z - e^-0.1) / (z + 1)
    g = d.freqresp([7.0])[0, 0, 0] * (z - 1) * (z - np.exp(-0.1)) / (z + 1)
    assert g.real == pytest.approx(0.052339, abs=5e-7) and abs(g.imag) < 1e-12
    back = sysid.d2c(d, "matched")  # the zero at z = -1 goes back to infinity
    assert back.zeros().size == 0
    assert _max_dev(back.freqresp([0.3, 3.0]), c.freqresp([0.3, 3.0])) < 1e-9


def test_matched_first_order_lag_and_the_integrator_asymptote() -> None:
    lag = sysid.ContinuousStateSpace([[-2.0]], [[1.0]], [[2.0]])  # 2 / (s + 2): DC gain 1
    d = sysid.c2d(lag, 0.1, "matched")  # (1 - e^-0.2) / (z - e^-0.2)
    a = np.exp(-0.2)
    assert d.A[0, 0] == pytest.approx(a)
    assert (d.C @ d.B)[0, 0] == pytest.approx(1 - a) and d.D[0, 0] == 0.0
    # 1 / (s (s + 2)): no DC gain; the low-frequency asymptote 1 / (2 s) <-> dt / (2 (z - 1))
    integ = sysid.ContinuousStateSpace([[0.0, 1.0], [0.0, -2.0]], [[0.0], [1.0]], [[1.0, 0.0]])
    di = sysid.c2d(integ, 0.1, "matched")
    np.testing.assert_allclose(np.sort(di.poles().real), [a, 1.0], atol=1e-12)
    w = 1e-5
    low = di.freqresp([w])[0, 0, 0] * (np.exp(1j * w * 0.1) - 1) / 0.1
    assert low == pytest.approx(0.5, rel=1e-5)
    back = sysid.d2c(di, "matched")
    assert _max_dev(back.freqresp([0.3, 3.0]), integ.freqresp([0.3, 3.0])) < 1e-10


def test_matched_rejects_mimo_and_zeros_with_no_continuous_equivalent() -> None:
    mimo = sysid.ContinuousStateSpace(-np.eye(2), np.eye(2), np.eye(2))
    with pytest.raises(sysid.DataError, match="one input-output channel.*method='zoh'"):
        sysid.c2d(mimo, 0.1, "matched")
    with pytest.raises(sysid.DataError, match="one input-output channel"):
        sysid.d2c(sysid.c2d(mimo, 0.1), "matched")
    # a zero on the negative real axis (not at z = -1, a zero at infinity): log is not real
    neg = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], [[1.0]], dt=0.1)  # zero at -0.5
    with pytest.raises(sysid.NumericalError, match="zero at z = -0.5.*method='tustin'"):
        sysid.d2c(neg, "matched")


# -- impulse invariant ---------------------------------------------------------------------


@pytest.mark.parametrize("seed, n, m, l", [(0, 1, 1, 1), (1, 3, 2, 2), (2, 5, 1, 3)])
def test_impulse_invariant_matches_scipy(seed: int, n: int, m: int, l: int) -> None:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) - 2 * np.eye(n)
    B, C, D = rng.standard_normal((n, m)), rng.standard_normal((l, n)), np.zeros((l, m))
    dt = 0.2
    d = sysid.c2d(sysid.ContinuousStateSpace(A, B, C, D), dt, "impulse")
    ref = scipy.signal.cont2discrete((A, B, C, D), dt, method="impulse")
    for mine, theirs in zip((d.A, d.B, d.C, d.D), ref[:4]):
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-13)


@SETTINGS
@given(seed=st.integers(0, 2**31), n=st.integers(1, 4), dt=st.floats(0.01, 0.5))
def test_impulse_invariant_response_is_dt_times_the_sampled_continuous_one(
        seed: int, n: int, dt: float) -> None:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    c = sysid.ContinuousStateSpace(A, rng.standard_normal((n, 2)), rng.standard_normal((2, n)))
    d = sysid.c2d(c, dt, "impulse")
    hc = c.impulse(40, dt=dt).y  # C e^{A k dt} B, k = 0..39
    hd = d.markov(40)  # Dd, Cd Bd, Cd Ad Bd, ...
    np.testing.assert_allclose(hd, dt * hc, rtol=0, atol=1e-11 * max(1.0, np.abs(hc).max()))


def test_impulse_invariant_keeps_a_feedthrough_on_top() -> None:
    c = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[2.0]], [[3.0]])
    d = c.c2d(0.5, "impulse")
    assert d.D[0, 0] == pytest.approx(3.0 + 2.0 * 0.5)  # D + dt C B
    assert d.B[0, 0] == pytest.approx(0.5 * np.exp(-0.5))
    with pytest.raises(sysid.DataError, match="method must be one of"):
        sysid.d2c(d, "impulse")  # MATLAB's d2c has no impulse inverse either


@pytest.mark.parametrize("seed, n, m, l", [(3, 1, 1, 1), (4, 3, 2, 2), (5, 4, 2, 3)])
def test_impulse_invariant_with_feedthrough_matches_scipy_plus_d(
        seed: int, n: int, m: int, l: int) -> None:
    """Random stable systems with D != 0: SciPy's map of the strictly proper part (it refuses
    D itself) to machine precision, with D added to the first sample."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, m)), rng.standard_normal((l, n))
    D = rng.standard_normal((l, m)) + 1.0
    dt = 0.2
    d = sysid.c2d(sysid.ContinuousStateSpace(A, B, C, D), dt, "impulse")
    ref = scipy.signal.cont2discrete((A, B, C, np.zeros((l, m))), dt, method="impulse")
    for mine, theirs in zip((d.A, d.B, d.C, d.D - D), ref[:4]):
        np.testing.assert_allclose(mine, theirs, rtol=1e-13, atol=1e-14)
    with pytest.raises(ValueError, match="strictly proper"):
        scipy.signal.cont2discrete((A, B, C, D), dt, method="impulse")


# -- Tustin with prewarping ----------------------------------------------------------------


@SETTINGS
@given(seed=st.integers(0, 2**31), n=st.integers(1, 4), dt=st.floats(0.01, 0.5),
       frac=st.floats(0.01, 0.95))
def test_prewarped_tustin_is_exact_at_the_prewarp_frequency(
        seed: int, n: int, dt: float, frac: float) -> None:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.3) * np.eye(n)
    c = sysid.ContinuousStateSpace(A, rng.standard_normal((n, 2)), rng.standard_normal((1, n)),
                                   rng.standard_normal((1, 2)))
    w = frac * np.pi / dt
    d = sysid.c2d(c, dt, "tustin", prewarp=w)
    hc = c.freqresp([w])
    assert _max_dev(d.freqresp([w]), hc) < 1e-9 * max(1.0, float(np.abs(hc).max()))
    back = sysid.d2c(d, "tustin", prewarp=w)
    for mine, orig in zip((back.A, back.B, back.C, back.D), (c.A, c.B, c.C, c.D)):
        np.testing.assert_allclose(mine, orig, rtol=0, atol=1e-8 * max(1.0, np.abs(orig).max()))


def test_prewarped_tustin_matches_scipy_bilinear_and_python_control() -> None:
    rng = np.random.default_rng(4)
    n, dt, w = 4, 0.1, 12.0
    A = rng.standard_normal((n, n)) - 2.5 * np.eye(n)
    B, C, D = rng.standard_normal((n, 2)), rng.standard_normal((3, n)), rng.standard_normal((3, 2))
    d = sysid.c2d(sysid.ContinuousStateSpace(A, B, C, D), dt, "bilinear", prewarp=w)
    assert d.dt == dt and "prewarp 12 rad/s" in d.info["method"]
    h = 2 * np.tan(w * dt / 2) / w  # scipy's bilinear transform at the warped step
    ref = scipy.signal.cont2discrete((A, B, C, D), h, method="bilinear")
    for mine, theirs in zip((d.A, d.B, d.C, d.D), ref[:4]):
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-13)
    control = pytest.importorskip("control")
    pc = control.sample_system(control.ss(A, B, C, D), dt, method="tustin", prewarp_frequency=w)
    for mine, theirs in zip((d.A, d.B, d.C, d.D), (pc.A, pc.B, pc.C, pc.D)):
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-13)
    # prewarp 0 is MATLAB's default: plain Tustin
    plain = sysid.c2d(sysid.ContinuousStateSpace(A, B, C, D), dt, "tustin", prewarp=0.0)
    np.testing.assert_array_equal(plain.A, sysid.c2d(sysid.ContinuousStateSpace(A, B, C, D),
                                                     dt, "tustin").A)


def test_bad_prewarp_and_sample_times_say_what_to_do() -> None:
    c = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    with pytest.raises(sysid.DataError, match=r"beyond the Nyquist frequency pi/dt = 31.4159"):
        sysid.c2d(c, 0.1, "tustin", prewarp=40.0)
    with pytest.raises(sysid.DataError, match="below 31.4159 rad/s or a smaller dt"):
        sysid.c2d(c, 0.1, "tustin", prewarp=np.pi / 0.1)
    with pytest.raises(sysid.DataError, match="non-negative frequency"):
        sysid.c2d(c, 0.1, "tustin", prewarp=-1.0)
    with pytest.raises(sysid.DataError, match="prewarp applies to method='tustin' only"):
        sysid.c2d(c, 0.1, "zoh", prewarp=1.0)
    with pytest.raises(sysid.DataError, match="beyond the Nyquist"):
        sysid.d2c(sysid.c2d(c, 0.1, "tustin"), "tustin", prewarp=100.0)
    for dt in (0.0, -0.1):
        for method in ("matched", "impulse"):
            with pytest.raises(sysid.DataError, match="positive number of seconds"):
                sysid.c2d(c, dt, method)
