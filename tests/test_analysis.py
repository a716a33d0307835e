"""Model analysis: zeros, damping, rank tests, responses, c2d/d2c, conversions."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

import sysid
from sysid.analysis.lti import ContinuousStateSpace

try:  # python-control is an optional oracle
    import control
except ImportError:  # pragma: no cover
    control = None
needs_control = pytest.mark.skipif(control is None, reason="python-control is not installed")


def random_continuous(seed: int, n: int = 4, m: int = 2, l: int = 3) -> ContinuousStateSpace:
    rng = np.random.default_rng(seed)
    # stable, distinct poles: real parts in [-3, -0.2], a few oscillatory pairs
    A = rng.standard_normal((n, n))
    A = A - (np.max(np.linalg.eigvals(A).real) + rng.uniform(0.2, 1.0)) * np.eye(n)
    return ContinuousStateSpace(A, rng.standard_normal((n, m)), rng.standard_normal((l, n)),
                                rng.standard_normal((l, m)))


# -- the thesis example (seed 002, appendix B.19-B.22, Ts = 4 ms) --------------------
A_PULSE1 = np.array([
    [0.9396, -0.1076, -0.1926, 0.2289, 0.1112, 0.0143],
    [0.0843, 0.9275, -0.3058, -0.1376, -0.0802, -0.0012],
    [0.1851, 0.2925, 0.9122, 0.1300, 0.0510, -0.0126],
    [-0.2200, 0.1624, -0.0791, 0.8958, -0.0134, 0.0404],
    [-0.1099, 0.0774, -0.0342, -0.0570, 0.9740, 0.0615],
    [-0.2038, -0.2027, -0.1052, 0.4774, -0.2319, 0.5055],
])
B_PULSE1 = np.array([[0.0795], [0.2898], [0.5659], [-0.7335], [-0.1450], [2.8114]])
C_PULSE1 = np.array([[0.0982, 0.0359, 0.5388, -0.6955, -0.3720, 0.4386]])


def test_thesis_poles_in_hz():
    m = sysid.StateSpaceModel(A_PULSE1, B_PULSE1, C_PULSE1, dt=0.004)
    table = sysid.damp(m)
    osc = table.poles.imag > 0
    # the thesis quotes the oscillation frequencies angle(z) / (2 pi Ts): 15.46 and 12.75 Hz
    assert sorted(np.round(table.wd_hz[osc], 2)) == [12.75, 15.46]
    # natural frequencies |log z| / (2 pi Ts) are slightly higher (damping 0.02 and 0.04)
    assert sorted(np.round(table.wn_hz[osc], 2)) == [12.76, 15.46]
    assert np.all(table.zeta[osc] > 0.01) and np.all(table.zeta[osc] < 0.05)
    # rad/s and Hz are consistent, and the representation is a table
    np.testing.assert_allclose(table.wn, 2 * np.pi * table.wn_hz)
    assert "15.46" in repr(table) and len(table) == 6


def test_damp_continuous_and_real_poles():
    sys = ContinuousStateSpace([[-2.0, 0.0], [0.0, -0.5]], [[1.0], [1.0]], [[1.0, 1.0]])
    t = sysid.damp(sys)
    np.testing.assert_allclose(t.wn, [0.5, 2.0])
    np.testing.assert_allclose(t.zeta, [1.0, 1.0])
    np.testing.assert_allclose(t.tau, [2.0, 0.5])
    # a discrete pole at the origin is infinitely fast, not a NaN
    t0 = sysid.damp(sysid.StateSpaceModel([[0.0]], [[1.0]], [[1.0]]))
    assert np.isinf(t0.wn[0]) and t0.zeta[0] == 1.0


@needs_control
def test_damp_matches_control():
    m = sysid.c2d(random_continuous(3), 0.05)
    wn, zeta, _ = control.damp(sysid.to_control(m), doprint=False)
    t = sysid.damp(m)
    np.testing.assert_allclose(np.sort(t.wn), np.sort(wn), rtol=1e-10)
    np.testing.assert_allclose(np.sort(t.zeta), np.sort(zeta), rtol=1e-8, atol=1e-12)


# -- zeros ---------------------------------------------------------------------------
@needs_control
def test_zeros_square_match_control():
    sys = random_continuous(1, n=5, m=2, l=2)
    m = sysid.c2d(sys, 0.1)
    expected = control.zeros(sysid.to_control(m))
    got = sysid.zeros(m)
    assert got.size == expected.size
    np.testing.assert_allclose(np.sort_complex(got), np.sort_complex(expected), rtol=1e-8)


def test_zeros_siso_are_numerator_roots():
    m = sysid.c2d(random_continuous(2, n=4, m=1, l=1), 0.1)
    num, _ = scipy.signal.ss2tf(m.A, m.B, m.C, m.D)
    roots = np.roots(np.trim_zeros(num[0], "f"))
    # sorted by rounded real part, then imaginary part: a conjugate pair whose real parts
    # differ in the last bits must not swap places
    def order(z):
        return z[np.lexsort((z.imag, np.round(z.real, 9)))]

    np.testing.assert_allclose(order(sysid.zeros(m)), order(roots), rtol=1e-7)


def test_zeros_non_square():
    # two outputs sharing the zero at 0.35 (and a distinct one each): only 0.35 is common
    A = np.diag([0.5, 0.2])
    B = np.array([[1.0], [1.0]])
    C = np.array([[1.0, 1.0], [2.0, 2.0]])
    z = sysid.zeros(sysid.StateSpaceModel(A, B, C))
    np.testing.assert_allclose(z, [0.35], atol=1e-10)
    # a tall system with no common zero has none
    C2 = np.array([[1.0, 1.0], [1.0, 0.0]])
    assert sysid.zeros(sysid.StateSpaceModel(A, B, C2)).size == 0


# -- controllability / observability -------------------------------------------------
def test_rank_tests():
    m = sysid.c2d(random_continuous(4), 0.1)
    assert sysid.is_controllable(m) and sysid.is_observable(m)
    assert np.linalg.matrix_rank(sysid.ctrb(m)) == 4
    assert sysid.obsv(m).shape == (4 * 3, 4)
    if control is not None:
        np.testing.assert_allclose(sysid.ctrb(m), control.ctrb(m.A, m.B))
        np.testing.assert_allclose(sysid.obsv(m), control.obsv(m.A, m.C))
    # add a mode that the input cannot reach and the output cannot see
    A = np.block([[m.A, np.zeros((4, 1))], [np.zeros((1, 4)), np.array([[0.3]])]])
    bad = sysid.StateSpaceModel(A, np.vstack([m.B, [[0, 0]]]), np.hstack([m.C, np.zeros((3, 1))]))
    assert not sysid.is_controllable(bad) and not sysid.is_observable(bad)
    # a weakly coupled mode passes only with a loose tolerance
    weak = sysid.StateSpaceModel(A, np.vstack([m.B, [[1e-9, 0]]]),
                                 np.hstack([m.C, np.ones((3, 1))]))
    assert sysid.is_controllable(weak, tol=1e-12) and not sysid.is_controllable(weak, tol=1e-6)


# -- responses -----------------------------------------------------------------------
def test_step_and_impulse():
    m = sysid.c2d(random_continuous(5, m=2, l=2), 0.1)
    s = sysid.step(m, 400)
    assert s.y.shape == (400, 2, 2)
    np.testing.assert_allclose(s.y[-1], m.dcgain(), rtol=1e-6, atol=1e-8)
    imp = sysid.impulse(m, 30)
    np.testing.assert_allclose(np.cumsum(imp.y, axis=0), s.y[:30], atol=1e-12)
    if control is not None:
        _, yc = control.step_response(sysid.to_control(m), T=np.arange(50) * 0.1)
        np.testing.assert_allclose(s.y[:50, 0, 0], yc[0, 0], atol=1e-10)
    assert sysid.step(m).y.shape[0] >= 20  # default length from the slowest pole
    with pytest.raises(sysid.DataError, match="n_samples"):
        sysid.step(m, 0)


# -- c2d / d2c -----------------------------------------------------------------------
@pytest.mark.parametrize("method,scipy_method", [("zoh", "zoh"), ("tustin", "bilinear")])
def test_c2d_matches_scipy_and_control(method, scipy_method):
    sys = random_continuous(6)
    dt = 0.07
    d = sysid.c2d(sys, dt, method)
    ref = scipy.signal.cont2discrete((sys.A, sys.B, sys.C, sys.D), dt, method=scipy_method)
    for got, want in zip((d.A, d.B, d.C, d.D), ref[:4]):
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)
    if control is None:
        return
    ct = control.sample_system(sysid.to_control(sys), dt, method=method)
    for got, want in zip((d.A, d.B, d.C, d.D), (ct.A, ct.B, ct.C, ct.D)):
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)
    assert d.dt == dt


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), dt=st.floats(0.01, 0.5),
       method=st.sampled_from(["zoh", "tustin"]))
def test_d2c_inverts_c2d(seed, dt, method):
    sys = random_continuous(seed)
    back = sysid.d2c(sysid.c2d(sys, dt, method), method)
    for got, want in zip((back.A, back.B, back.C, back.D), (sys.A, sys.B, sys.C, sys.D)):
        np.testing.assert_allclose(got, want, rtol=1e-8, atol=1e-8)


def test_d2c_frequency_response_tustin():
    sys = random_continuous(7, m=1, l=1)
    dt = 0.05
    d = sysid.c2d(sys, dt, "tustin")
    w = np.array([0.3, 2.0, 10.0])
    # the bilinear map sends continuous frequency (2/dt) tan(w dt / 2) to discrete w
    warped = 2 / dt * np.tan(w * dt / 2)
    np.testing.assert_allclose(d.freqresp(w), sys.freqresp(warped), rtol=1e-10)


def test_d2c_errors():
    with pytest.raises(sysid.NumericalError, match="pole at z = 0.*iodelay.*method='tustin'"):
        sysid.d2c(sysid.StateSpaceModel([[0.0]], [[1.0]], [[1.0]]))
    with pytest.raises(sysid.NumericalError, match="negative real axis.*'zoh' or 'tustin'"):
        sysid.d2c(sysid.StateSpaceModel([[-0.5]], [[1.0]], [[1.0]]), "foh")
    with pytest.raises(sysid.NumericalError, match="z = -1"):
        sysid.d2c(sysid.StateSpaceModel([[-1.0]], [[1.0]], [[1.0]]), "tustin")
    with pytest.raises(sysid.DataError, match="zoh"):
        sysid.d2c(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), "euler")
    with pytest.raises(sysid.DataError, match="dt"):
        sysid.c2d(ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]), -1.0)


# -- conversions ---------------------------------------------------------------------
@needs_control
def test_control_round_trip():
    m = sysid.StateSpaceModel(A_PULSE1, B_PULSE1, C_PULSE1, dt=0.004, input_names=["force"],
                              output_names=["x"])
    ct = sysid.to_control(m)
    assert ct.dt == 0.004 and ct.input_labels == ["force"]
    back = sysid.from_control(ct)
    assert isinstance(back, sysid.StateSpaceModel) and back.output_names == ["x"]
    np.testing.assert_array_equal(back.A, m.A)
    w = np.linspace(0.1, 700, 7)
    np.testing.assert_allclose(
        ct.frequency_response(w).complex.reshape(-1), m.freqresp(w)[:, 0, 0], rtol=1e-10)
    cont = sysid.from_control(control.tf([1.0], [1.0, 2.0]))
    assert isinstance(cont, ContinuousStateSpace)
    np.testing.assert_allclose(cont.dcgain(), [[0.5]])


def test_scipy_round_trip():
    m = sysid.StateSpaceModel(A_PULSE1, B_PULSE1, C_PULSE1, dt=0.004)
    sp = sysid.to_scipy(m)
    assert sp.dt == 0.004
    back = sysid.from_scipy(sp)
    np.testing.assert_array_equal(back.C, m.C)
    cont = sysid.from_scipy(scipy.signal.TransferFunction([1.0], [1.0, 3.0]))
    np.testing.assert_allclose(cont.dcgain(), [[1 / 3]])
    d = sysid.from_scipy(scipy.signal.dlti([1.0], [1.0, -0.5], dt=0.2))
    assert isinstance(d, sysid.StateSpaceModel) and d.dt == 0.2
    np.testing.assert_allclose(d.dcgain(), [[2.0]])
    with pytest.raises(sysid.DataError, match="scipy.signal"):
        sysid.from_scipy("not a system")


def test_wrong_types():
    with pytest.raises(sysid.DataError, match="StateSpaceModel"):
        sysid.step(np.eye(2))
    with pytest.raises(sysid.DataError, match="ContinuousStateSpace"):
        sysid.c2d(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]), 0.1)


def test_plots_of_responses():
    plt = pytest.importorskip("matplotlib.pyplot")
    m = sysid.StateSpaceModel(A_PULSE1, B_PULSE1, C_PULSE1, dt=0.004)
    fig = sysid.step(m, 50).plot()
    assert len(fig.axes) == 1
    from sysid.plot.model import plot_bode, plot_pzmap, plot_sigma

    fig = plot_bode([m, m], labels=["a", "b"])
    assert len(fig.axes) == 2
    ax = plot_pzmap(m)
    assert len(ax.lines) >= 3  # circle, poles, zeros
    ax2 = plot_sigma(m)
    assert len(ax2.lines) == 1
    plt.close("all")


def test_model_shortcuts(tmp_path):
    m = sysid.StateSpaceModel(A_PULSE1, B_PULSE1, C_PULSE1, dt=0.004)
    np.testing.assert_array_equal(m.zeros(), sysid.zeros(m))
    np.testing.assert_array_equal(m.damp().wn_hz, sysid.damp(m).wn_hz)
    np.testing.assert_array_equal(m.step(20).y, sysid.step(m, 20).y)
    np.testing.assert_array_equal(m.impulse(20).y, m.markov(20))
    m.save(tmp_path / "m.npz")
    np.testing.assert_array_equal(sysid.load_model(tmp_path / "m.npz").A, m.A)


def test_plots_of_continuous_models():
    plt = pytest.importorskip("matplotlib.pyplot")
    from sysid.plot.model import plot_bode, plot_pzmap

    sys = random_continuous(8, m=1, l=1)
    fig = plot_bode(sys)
    x = fig.axes[0].lines[0].get_xdata()
    wn = np.abs(sys.poles())
    assert x.min() < wn.min() / (2 * np.pi) < wn.max() / (2 * np.pi) < x.max()
    ax = plot_pzmap(sys)
    assert ax.get_xlabel() == "Re s"
    plt.close("all")


def test_minreal_keeps_the_noise_model():
    # minreal dropped K: on a minimal 3-state model the 1-step fit fell from 99.2 to 91.5 %
    A = np.diag([0.9, 0.5, 0.2])
    m = sysid.StateSpaceModel(A, [[1.0], [1.0], [0.0]], [[1.0, 1.0, 1.0]],
                              K=[[0.3], [0.1], [0.6]], dt=1.0, noise_cov=[[0.04]])
    r = sysid.minreal(m)
    assert r.nstates == 3 and r.K is not None  # the third state is reached by the noise only
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal((200, 1)), rng.standard_normal((200, 1))
    np.testing.assert_allclose(r.predict(u, y, 1), m.predict(u, y, 1), atol=1e-10)
    np.testing.assert_allclose(r.noise_cov, m.noise_cov)
    det = sysid.minreal(sysid.StateSpaceModel(A, [[1.0], [1.0], [0.0]], [[1.0, 1.0, 1.0]]))
    assert det.nstates == 2 and det.K is None


def test_minreal_keeps_the_parameter_uncertainty():
    # minreal returned models without uncertainty: poles(std=True) raised on the result
    P = np.array([[4e-4, 1e-4], [1e-4, 9e-4]])

    def tf(t):  # t1 (s + 1) / ((s + 1)(s + t0)): the pair at -1 cancels in every draw
        return sysid.TransferFunction(t[1] * np.array([1.0, 1.0]), np.poly([-1.0, -t[0]]))

    G = tf(np.array([2.0, 3.0]))
    G.uncertainty = sysid.ParameterUncertainty([2.0, 3.0], P, tf)
    R = sysid.minreal(G)
    assert R.den[0][0].size == 2 and R.uncertainty is not None
    np.testing.assert_allclose(R.poles(std=True)[1].real, [0.02], rtol=1e-5)
    np.testing.assert_allclose(R.dcgain(std=True)[1], G.dcgain(std=True)[1], rtol=1e-5)

    def ss(t):  # the second state is not reached by the input in any draw
        return sysid.StateSpaceModel(np.diag([t[0], 0.3]), [[t[1]], [0.0]], [[1.0, 1.0]])

    m = ss(np.array([0.5, 1.0]))
    m.uncertainty = sysid.ParameterUncertainty([0.5, 1.0], P, ss)
    r = sysid.minreal(m)
    assert r.nstates == 1 and r.uncertainty is not None
    np.testing.assert_allclose(r.poles(std=True)[1].real, [0.02], rtol=1e-5)
    np.testing.assert_allclose(r.dcgain(std=True)[1], m.dcgain(std=True)[1], rtol=1e-5)


def test_integrators_give_sysid_answers_not_numpy_errors():
    # ContinuousStateSpace.dcgain and stepinfo of a discrete integrator raised numpy's
    # LinAlgError; stepinfo reported a peak of 2 at 3.33 s for an unbounded ramp
    ci = sysid.ContinuousStateSpace([[0.0, 1.0], [0.0, -3.0]], [[0.0], [2.0]], [[1.0, 0.0]])
    with pytest.raises(sysid.NumericalError, match="pole\\(s\\) at s = 0"):
        ci.dcgain()
    for sys in (ci, sysid.c2d(ci, 0.1), sysid.TransferFunction([2.0], [1.0, 3.0, 0.0])):
        info = sysid.stepinfo(sys)
        assert np.isinf(info.steady_state) and np.isinf(info.peak) and np.isinf(info.peak_time)
        assert np.isnan(info.rise_time)


def test_d2c_doubles_poles_on_the_negative_real_axis_as_matlab():
    # d2c refused any model with a pole on the negative real axis (ssest's order-4 model of
    # the winding record has one at z = -0.09); MATLAB doubles each into a complex pair at
    # the Nyquist frequency. Its documented example: G = (z + 0.5) / ((z + 2)(z - 5)),
    # dt = 0.1 -> 2.6663 (s^2 + 14.28 s + 780.9) / ((s - 16.09)(s^2 - 13.86 s + 1035))
    G = sysid.TransferFunction([1.0, 0.5], [1.0, -3.0, -10.0], dt=0.1)
    with pytest.warns(sysid.SysidWarning, match="order 2 -> 3"):
        c = sysid.d2c(G)
    assert c.nstates == 3
    den = np.real(np.poly(c.poles()))
    a, b = np.log(2) / 0.1, np.pi / 0.1      # z = -2 -> (log 2 +- i pi) / dt: 6.93 +- 31.4i
    np.testing.assert_allclose(den, np.polymul([1, -np.log(5) / 0.1],
                                               [1, -2 * a, a * a + b * b]), rtol=1e-12)
    num = np.real(np.poly(sysid.zeros(c)))
    np.testing.assert_allclose(num, [1.0, 14.28, 780.9], rtol=2e-3)
    assert float(c.dcgain()[0, 0]) == pytest.approx(-0.125)       # G(1) = 1.5 / (3 * -4)
    # sampled back with the same hold it is the discrete model, at every frequency
    w = np.linspace(0.1, np.pi / 0.1, 40)
    np.testing.assert_allclose(sysid.c2d(c, 0.1).freqresp(w), G.freqresp(w), atol=1e-12)
    # MIMO, several such poles and a coupled block: still the same sampled model
    rng = np.random.default_rng(3)
    V = rng.standard_normal((5, 5))
    A = V @ np.diag([-0.6, -0.2, 0.3, 0.8, 0.5]) @ np.linalg.inv(V)
    A[:, 4] += 0.05 * rng.standard_normal(5)
    m = sysid.StateSpaceModel(A, rng.standard_normal((5, 2)), rng.standard_normal((3, 5)),
                              rng.standard_normal((3, 2)), dt=0.2)
    k = int(np.sum((np.abs(m.poles().imag) < 1e-12) & (m.poles().real < 0)))
    with pytest.warns(sysid.SysidWarning, match="negative real axis"):
        c = sysid.d2c(m)
    assert c.nstates == 5 + k and np.isrealobj(c.A)
    w = np.linspace(0.05, np.pi / 0.2, 30)
    np.testing.assert_allclose(sysid.c2d(c, 0.2).freqresp(w), m.freqresp(w), atol=1e-10)


def test_stepinfo_of_an_unstable_model_is_nan_with_an_infinite_peak():
    # an unstable model's step diverges; stepinfo took its DC gain as the final value and
    # reported a settling band, a peak and an undershoot of 1580 % (ball and beam, n4sid
    # order 4, pole 1.016); MATLAB: every characteristic NaN, Peak and PeakTime Inf
    for sys in (sysid.StateSpaceModel([[1.02, 0.0], [0.1, 0.5]], [[1.0], [0.0]], [[0.0, 1.0]],
                                      dt=0.1),
                sysid.TransferFunction([1.0], [1.0, 1.0, -0.5]),
                sysid.ContinuousStateSpace([[0.2]], [[1.0]], [[1.0]])):
        info = sysid.stepinfo(sys)
        assert np.isinf(info.peak) and np.isinf(info.peak_time)
        for k in ("rise_time", "settling_time", "settling_min", "overshoot", "undershoot"):
            assert np.isnan(getattr(info, k)), k
    # a stable model still has its characteristics
    ok = sysid.stepinfo(sysid.StateSpaceModel([[0.9]], [[0.1]], [[1.0]], dt=0.1))
    assert ok.steady_state == pytest.approx(1.0) and np.isfinite(ok.settling_time)


def test_margin_and_nyquist_of_a_frequency_response_use_its_lines():
    # margin(frd) and nyquist(frd) built a grid from the poles an FRD does not have, then
    # refused it as outside the measured range
    g = sysid.StateSpaceModel([[1.5, -0.7], [1, 0]], [[1.0], [0]], [[1.0, 0.5]], dt=0.1)
    fr = sysid.FRD.from_model(g, np.linspace(0.05, np.pi / 0.1, 400))
    a, b = sysid.margin(g), sysid.margin(fr)
    assert b.gain_margin == pytest.approx(a.gain_margin, rel=1e-3)
    assert b.phase_margin == pytest.approx(a.phase_margin, abs=0.1)
    assert sysid.nyquist(fr).encirclements == sysid.nyquist(g).encirclements


def test_conversions_of_static_gains_and_transfer_functions():
    # from_control of a static gain raised a raw ValueError; from_scipy called one UNSTABLE
    # (SciPy's idle state at s = 0); to_control refused a TransferFunction
    control = pytest.importorskip("control")
    for sys in (control.ss(control.tf(2, 1)), control.ss(control.tf(2, 1, 0.1))):
        m = sysid.from_control(sys)
        assert m.nstates == 0 and m.is_stable()
        np.testing.assert_allclose(m.D, [[2.0]])
    s = sysid.from_scipy(scipy.signal.lti([2.0], [1.0]))
    assert s.nstates == 0 and s.is_stable()
    G = sysid.TransferFunction([1.0], [1.0, 1.0])
    c = sysid.to_control(G)
    np.testing.assert_allclose(np.asarray(control.dcgain(c)), 1.0)


def test_frd_of_a_continuous_model_has_no_sample_time():
    # FRD.from_model(continuous) stored dt = 0, and frd_subspace then asked "is it zero?"
    w = np.geomspace(0.01, 100, 50)
    fr = sysid.FRD.from_model(sysid.TransferFunction([1.0], [1.0, 1.0]), w)
    assert fr.dt is None
    with pytest.raises(sysid.DataError, match="needs frd.dt"):
        sysid.frd_subspace(fr, 1)
    np.testing.assert_allclose(sysid.frd_subspace(fr, 1, continuous=True).poles(), [-1.0],
                               atol=1e-6)


def test_band_limited_inputs_refuse_a_band_without_lines():
    # random_binary returned a constant and random_gaussian NaN for a band narrower than one
    # frequency line of the signal
    for f in (sysid.random_binary, sysid.random_gaussian):
        with pytest.raises(sysid.DataError, match="holds no frequency line"):
            f(100, band=(0.0, 0.015), seed=0)
