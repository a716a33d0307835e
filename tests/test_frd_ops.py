"""FRD indexing, arithmetic, frequency units and first-order std propagation.

The arithmetic is checked against state-space models whose series, parallel and feedback
connections are built by hand and evaluated directly; the propagated std against Monte Carlo
runs of independent noisy FRDs.
"""

from __future__ import annotations

import copy

import matplotlib
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import sysid
from sysid.errors import DataError, ShapeError

from conftest import random_system

matplotlib.use("Agg")

SETTINGS = settings(max_examples=30, deadline=None)
W = np.linspace(0.05, 3.0, 40)  # rad/s, below Nyquist at dt = 1
TOL = {"rtol": 1e-12, "atol": 1e-12}


def _ss(n, m, l, seed, feedthrough=True):
    a, b, c, d = random_system(n, m, l, np.random.default_rng(seed), feedthrough=feedthrough)
    return sysid.StateSpaceModel(a, b, c, d)


def _series(g1, g2):
    """G1 after G2 as one state-space model."""
    A = np.block([[g2.A, np.zeros((g2.A.shape[0], g1.A.shape[0]))], [g1.B @ g2.C, g1.A]])
    B = np.vstack([g2.B, g1.B @ g2.D])
    C = np.hstack([g1.D @ g2.C, g1.C])
    return sysid.StateSpaceModel(A, B, C, g1.D @ g2.D)


def _parallel(g1, g2):
    n1, n2 = g1.A.shape[0], g2.A.shape[0]
    A = np.block([[g1.A, np.zeros((n1, n2))], [np.zeros((n2, n1)), g2.A]])
    return sysid.StateSpaceModel(A, np.vstack([g1.B, g2.B]), np.hstack([g1.C, g2.C]),
                                 g1.D + g2.D)


def _feedback(g, k):
    """Negative feedback of G with a strictly proper K in the return path."""
    A = np.block([[g.A, -g.B @ k.C], [k.B @ g.C, k.A - k.B @ g.D @ k.C]])
    B = np.vstack([g.B, k.B @ g.D])
    C = np.hstack([g.C, -g.D @ k.C])
    return sysid.StateSpaceModel(A, B, C, g.D)


def _mimo():
    g = sysid.FRD(W, _ss(3, 2, 3, 1).freqresp(W), std=np.full((W.size, 3, 2), 0.1),
                  coherence=np.linspace(0.1, 0.9, W.size * 6).reshape(W.size, 3, 2),
                  output_names=["a", "b", "c"], input_names=["p", "q"])
    return g


# -- indexing ------------------------------------------------------------------------------


def test_indexing_shapes_values_and_bands():
    g = _mimo()
    for key, rows, cols in [((1, 0), [1], [0]), ((slice(None), 1), [0, 1, 2], [1]),
                            ((slice(1, None), slice(None, None, -1)), [1, 2], [1, 0]),
                            (("c", "p"), [2], [0]), ((["c", "a"], [1]), [2, 0], [1]),
                            ((-1, np.array([0, 1])), [2], [0, 1])]:
        s = g[key]
        assert s.response.shape == (W.size, len(rows), len(cols))
        np.testing.assert_array_equal(s.response, g.response[:, rows][:, :, cols])
        np.testing.assert_array_equal(s.std, g.std[:, rows][:, :, cols])
        np.testing.assert_array_equal(s.coherence, g.coherence[:, rows][:, :, cols])
        assert s.output_names == [g.output_names[i] for i in rows]
        assert s.input_names == [g.input_names[i] for i in cols]
        np.testing.assert_array_equal(s.omega, g.omega)
    assert g[0, 0].radius is not None and g[0, 0].confidence == g.confidence


@pytest.mark.parametrize("key", [0, (0,), (0, 0, 0), ("zz", 0), (5, 0), (slice(3, None), 0)])
def test_indexing_refuses_bad_keys(key):
    with pytest.raises(DataError):
        _mimo()[key]


# -- arithmetic against state-space models evaluated directly ------------------------------


def test_series_equals_the_series_model():
    g1, g2 = _ss(3, 3, 2, 2), _ss(2, 2, 3, 3)  # G1: 2x3, G2: 3x2
    f1, f2 = sysid.FRD.from_model(g1, W), sysid.FRD.from_model(g2, W)
    want = _series(g1, g2).freqresp(W)
    for got in (f1 * f2, f1 @ f2, f1 * g2, g1 * f2):
        assert got.response.shape == (W.size, 2, 2)
        np.testing.assert_allclose(got.response, want, **TOL)
    assert (f1 * f2).output_names == f1.output_names
    with pytest.raises(ShapeError, match="after"):
        f2 * f2


def test_sum_difference_and_gains_equal_the_models():
    g1, g2 = _ss(3, 2, 2, 4), _ss(2, 2, 2, 5)
    f1, f2 = sysid.FRD.from_model(g1, W), sysid.FRD.from_model(g2, W)
    h1, h2 = g1.freqresp(W), g2.freqresp(W)
    np.testing.assert_allclose((f1 + f2).response, _parallel(g1, g2).freqresp(W), **TOL)
    np.testing.assert_allclose((f1 + g2).response, h1 + h2, **TOL)
    np.testing.assert_allclose((g2 + f1).response, h1 + h2, **TOL)
    np.testing.assert_allclose((f1 - f2).response, h1 - h2, **TOL)
    np.testing.assert_allclose((g2 - f1).response, h2 - h1, **TOL)
    np.testing.assert_allclose((-f1).response, -h1, **TOL)
    K = np.array([[1.0, 2.0], [0.5j, -1.0]])
    np.testing.assert_allclose((f1 * K).response, h1 @ K, **TOL)
    np.testing.assert_allclose((K * f1).response, K @ h1, **TOL)  # numpy gives way
    np.testing.assert_allclose((K @ f1).response, K @ h1, **TOL)
    np.testing.assert_allclose((f1 + K).response, h1 + K, **TOL)
    np.testing.assert_allclose((np.float64(2.0) * f1).response, 2 * h1, **TOL)
    np.testing.assert_allclose((1 - f1).response, 1 - h1, **TOL)
    np.testing.assert_allclose((f1 / 4).response, h1 / 4, **TOL)
    np.testing.assert_allclose((f1 / f2).response, h1 @ np.linalg.inv(h2), rtol=1e-10)
    np.testing.assert_allclose((1 / f2).response, np.linalg.inv(h2), rtol=1e-10)


def test_a_transfer_function_is_evaluated_on_the_grid():
    tf = sysid.TransferFunction([1.0], [1.0, 0.4, 1.0])  # continuous
    f = sysid.FRD.from_model(_ss(2, 1, 1, 6), W)
    np.testing.assert_allclose((f * tf).response, f.response * tf.freqresp(W), **TOL)
    np.testing.assert_allclose((tf + f).response, f.response + tf.freqresp(W), **TOL)


def test_inverse_and_feedback_equal_the_models():
    g, k = _ss(3, 2, 2, 7), _ss(2, 2, 2, 8, feedthrough=False)
    fg, fk = sysid.FRD.from_model(g, W), sysid.FRD.from_model(k, W)
    eye = np.broadcast_to(np.eye(2), (W.size, 2, 2))
    np.testing.assert_allclose((fg * fg.inv()).response, eye, atol=1e-12)
    np.testing.assert_allclose(fg.inv().inv().response, fg.response, rtol=1e-10)
    want = _feedback(g, k).freqresp(W)
    np.testing.assert_allclose(fg.feedback(fk).response, want, **TOL)
    np.testing.assert_allclose(fg.feedback(k).response, want, **TOL)
    h = fg.response
    np.testing.assert_allclose(fg.feedback(0.5, sign=+1).response,
                               np.linalg.solve(np.eye(2) - 0.5 * h, h), **TOL)
    with pytest.raises(ShapeError, match="square"):
        sysid.FRD(W, np.ones((W.size, 2, 3))).inv()
    with pytest.raises(DataError, match="singular"):
        sysid.FRD([1.0, 2.0], [1.0, 0.0]).inv()


def test_operand_shapes_and_types_are_checked():
    f = sysid.FRD.from_model(_ss(2, 2, 2, 9), W)
    with pytest.raises(ShapeError, match="same"):
        f + np.ones((3, 2))
    with pytest.raises(ShapeError, match="constant"):
        f * np.ones(W.size)
    with pytest.raises(TypeError):
        f + "a"
    with pytest.raises(ShapeError, match="K must be 2x2"):
        f.feedback(np.ones((2, 3)))


def test_a_different_grid_is_refused_naming_the_fix():
    a = sysid.FRD.from_model(_ss(2, 1, 1, 10), W)
    b = sysid.FRD.from_model(_ss(2, 1, 1, 11), np.linspace(W[0], W[-1], 57))
    for op in (lambda: a + b, lambda: a - b, lambda: a * b, lambda: a / b,
               lambda: a.feedback(b)):
        with pytest.raises(DataError, match=r"different frequency grids.*from_model\(b, a.omega"):
            op()
    with pytest.raises(DataError, match="different frequency grids"):
        a.compare(b)  # compare names its own way out
    # the fix it names works
    s = a + sysid.FRD.from_model(b, a.omega)
    np.testing.assert_allclose(s.response, a.response + b.freqresp(W), **TOL)


# -- frequency units -----------------------------------------------------------------------


def test_units_round_trip_and_defaults():
    hz = np.array([0.5, 1.0, 4.0])
    g = np.array([1.0, 1j, -1.0])
    f = sysid.FRD(hz, g, units="Hz")
    np.testing.assert_allclose(f.omega, 2 * np.pi * hz, rtol=1e-15)
    np.testing.assert_allclose(f.frequencies, hz, rtol=1e-15)
    back = sysid.FRD(f.frequencies_in("rad/s"), g, units="rad/s")
    np.testing.assert_allclose(back.frequencies_in("Hz"), hz, rtol=1e-15)
    np.testing.assert_allclose(sysid.FRD(back.frequencies_in("Hz"), g, units="hz").omega,
                               f.omega, rtol=1e-15)
    assert repr(f) == "FRD: 3 frequencies 0.5..4 Hz, 1 output x 1 input"
    # no units: rad/s as before
    d = sysid.FRD(hz, g)
    assert d.units is None and repr(d).endswith("0.5..4 rad/s, 1 output x 1 input")
    np.testing.assert_array_equal(d.omega, hz)
    np.testing.assert_array_equal(d.frequencies, hz)
    # combined, indexed, sampled: the units stay; the grid compares in rad/s
    for h in (f + sysid.FRD(2 * np.pi * hz, g), f[0, 0], -f, f.inv(), 2 * f, f.feedback(0.5),
              sysid.FRD(2 * np.pi * hz, g) * f):
        assert h.units == "Hz"
        np.testing.assert_array_equal(h.omega, f.omega)
    m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    fm = sysid.FRD.from_model(m, hz / 10, units="Hz")
    np.testing.assert_allclose(fm.response, m.freqresp(2 * np.pi * hz / 10), **TOL)
    with pytest.raises(DataError, match="units"):
        sysid.FRD(hz, g, units="rpm")
    with pytest.raises(DataError, match="0.5 Hz more than once"):
        sysid.FRD([0.5, 0.5], [1.0, 2.0], units="Hz")


@pytest.mark.parametrize("units, label, x", [(None, "frequency [Hz]", 1 / (2 * np.pi)),
                                            ("Hz", "frequency [Hz]", 1.0),
                                            ("rad/s", "frequency [rad/s]", 1.0)])
def test_plot_axis_follows_the_units(units, label, x):
    import matplotlib.pyplot as plt

    f = sysid.FRD([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], units=units)
    fig = f.plot()
    ax = fig.axes[-1]
    assert ax.get_xlabel() == label
    np.testing.assert_allclose(ax.get_lines()[0].get_xdata(), np.array([1.0, 2.0, 3.0]) * x)
    plt.close(fig)
    assert ("Hz" if units == "Hz" else "rad/s") in f._repr_html_()


# -- uncertainty ---------------------------------------------------------------------------


def _noisy(truth, std, rng):
    e = (rng.standard_normal(truth.shape) + 1j * rng.standard_normal(truth.shape)) / np.sqrt(2)
    return truth + std * e


def _monte_carlo(op, runs=400, seed=0):
    """Sample std over ``runs`` of ``op(A, B)`` for independent noisy FRDs, and the mean
    propagated std: their ratio per frequency and pair."""
    rng = np.random.default_rng(seed)
    w = W[::8]
    ta = sysid.FRD.from_model(_ss(3, 2, 2, 12), w).response
    tb = sysid.FRD.from_model(_ss(3, 2, 2, 17), w).response
    sa = 0.03 * np.abs(ta).mean() * (1 + rng.random(ta.shape))
    sb = 0.03 * np.abs(tb).mean() * (1 + rng.random(tb.shape))
    vals, stds = [], []
    for _ in range(runs):
        r = op(sysid.FRD(w, _noisy(ta, sa, rng), std=sa),
               sysid.FRD(w, _noisy(tb, sb, rng), std=sb))
        vals.append(r.response)
        stds.append(r.std)
    vals = np.array(vals)
    sample = np.sqrt(np.mean(np.abs(vals - vals.mean(0)) ** 2, axis=0))
    return sample / np.mean(stds, axis=0)


@pytest.mark.parametrize("name, op", [
    ("sum", lambda a, b: a + b), ("difference", lambda a, b: a - b),
    ("product", lambda a, b: a * b), ("inverse", lambda a, b: a.inv()),
    ("feedback", lambda a, b: a.feedback(b)), ("quotient", lambda a, b: a / b),
    ("gain over", lambda a, b: np.array([[1.0, 2.0], [0.5, -1j]]) / b),
    ("gain times", lambda a, b: np.array([[1.0, 2.0], [0.5, -1j]]) @ b + 3)])
def test_propagated_std_matches_monte_carlo(name, op):
    ratio = _monte_carlo(op)
    assert np.all(np.abs(ratio - 1) < 0.15), (name, ratio.min(), ratio.max())


def test_std_rules_exact_cases():
    a = sysid.FRD([1.0, 2.0], [3.0, 4j], std=[0.3, 0.4], dof=20)
    b = sysid.FRD([1.0, 2.0], [1.0, 2.0], std=[0.4, 0.3])
    np.testing.assert_allclose((a + b).std[:, 0, 0], [0.5, 0.5])
    np.testing.assert_allclose((a * b).std[:, 0, 0], np.hypot([3 * 0.4, 4 * 0.3],
                                                               [1 * 0.3, 2 * 0.4]))
    np.testing.assert_allclose((2j * a).std[:, 0, 0], [0.6, 0.8])
    np.testing.assert_array_equal((-a).std, a.std)
    np.testing.assert_allclose(a.inv().std[:, 0, 0], [0.3 / 9, 0.4 / 16])
    assert (a + b).dof is None and (a + 1).dof == 20 and (a * 2).dof == 20
    np.testing.assert_array_equal((a + 1).std, a.std)
    exact = sysid.FRD([1.0, 2.0], [1.0, 2.0])
    assert (exact + exact).std is None and (exact * 3).std is None
    c = sysid.FRD([1.0, 2.0], [1.0, 2.0], coherence=[0.5, 0.9])
    assert (2 * c).coherence is not None and (c + c).coherence is None


# -- invariances ---------------------------------------------------------------------------

_entries = hnp.arrays(np.float64, (3, 2, 2, 2), elements=st.floats(-5, 5))
_stds = hnp.arrays(np.float64, (3, 2, 2), elements=st.floats(0, 2))


def _frd(x, s=None):
    return sysid.FRD([0.1, 1.0, 2.0], x[..., 0] + 1j * x[..., 1], std=s)


@SETTINGS
@given(_entries, _entries, _entries, _stds, _stds)
def test_algebra_invariances(x, y, z, sa, sb):
    A, B, C = _frd(x, sa), _frd(y, sb), _frd(z)
    close = {"rtol": 1e-9, "atol": 1e-9}
    np.testing.assert_allclose(((A + B) - B).response, A.response, **close)
    minus = -A
    np.testing.assert_allclose((-minus).response, A.response)
    np.testing.assert_allclose((A * (B + C)).response, (A * B + A * C).response, **close)
    np.testing.assert_allclose(((A * B) * C).response, (A * (B * C)).response, **close)
    np.testing.assert_allclose((A + B).std, (B + A).std)
    np.testing.assert_allclose((A + B)[1, 0].response, (A[1, 0] + B[1, 0]).response)
    np.testing.assert_allclose((A + B)[1, 0].std, (A[1, 0] + B[1, 0]).std)
    np.testing.assert_allclose(((A + B) - B).std ** 2, A.std ** 2 + 2 * B.std ** 2, **close)
    D = A + 25 * np.eye(2)  # diagonally dominant: well conditioned
    np.testing.assert_allclose(D.inv().inv().response, D.response, **close)
    K = B * (0.01 / (1 + np.abs(B.response).max()))  # |D K| < 1: a well-posed loop
    np.testing.assert_allclose(D.feedback(K).response,
                               (D * (np.eye(2) + K * D).inv()).response, **close)


# -- one response used twice (fully correlated operands) -------------------------------------


def _monte_carlo_same(op, runs=400, seed=3, siso=False):
    """Sample std over ``runs`` of ``op(G)`` (G entering twice, one error), the mean propagated
    std and the relative tolerance of their ratio: the sample std of ``runs`` circular draws
    has relative std ``1 / (2 sqrt(runs))``; five of those, plus 0.03 for the second-order
    terms the first-order std leaves out (errors of 1-2 % of |G|)."""
    rng = np.random.default_rng(seed)
    w = W[::8]
    t = sysid.FRD.from_model(_ss(3, 2, 2, 12), w).response
    t = t[:, :1, :1] if siso else t
    s = 0.01 * np.abs(t).mean() * (1 + rng.random(t.shape))
    vals, stds = [], []
    for _ in range(runs):
        r = op(sysid.FRD(w, _noisy(t, s, rng), std=s))
        vals.append(r.response)
        stds.append(r.std)
    vals = np.array(vals)
    sample = np.sqrt(np.mean(np.abs(vals - vals.mean(0)) ** 2, axis=0))
    return sample / np.mean(stds, axis=0), 5 / (2 * np.sqrt(runs)) + 0.03


@pytest.mark.parametrize("name, op, siso", [
    ("G + G", lambda g: g + g, False), ("G * G siso", lambda g: g * g, True),
    ("G @ G", lambda g: g @ g, False), ("G * G", lambda g: g * g, False),
    ("feedback(G, G)", lambda g: g.feedback(g), False),
    ("positive feedback(G, G)", lambda g: g.feedback(g, sign=1), False),
    ("shallow copy", lambda g: g * copy.copy(g), False)])
def test_same_operand_std_matches_monte_carlo(name, op, siso):
    ratio, tol = _monte_carlo_same(op, siso=siso)
    assert np.all(np.abs(ratio - 1) < tol), (name, ratio.min(), ratio.max(), tol)


def test_same_operand_exact_cases():
    g = sysid.FRD([1.0, 2.0], [3.0, 4j], std=[0.3, 0.4], dof=20)
    np.testing.assert_array_equal((g - g).std, 0.0)
    np.testing.assert_array_equal((g / g).std, 0.0)
    np.testing.assert_allclose((g + g).std[:, 0, 0], [0.6, 0.8])
    np.testing.assert_allclose((g * g).std[:, 0, 0], [2 * 3 * 0.3, 2 * 4 * 0.4])
    np.testing.assert_allclose((g @ g).std, (g * g).std)
    # T = G / (1 + G^2): dT/dG = (1 - G^2) / (1 + G^2)^2
    G = g.response[:, 0, 0]
    np.testing.assert_allclose(g.feedback(g).std[:, 0, 0],
                               np.abs((1 - G**2) / (1 + G**2) ** 2) * [0.3, 0.4])
    assert (g + g).dof == 20 and (g * g).dof == 20  # one uncertain response: its dof stays
    m = _mimo()  # 3x2: G - G and G + G on a non-square response
    np.testing.assert_array_equal((m - m).std, 0.0)
    np.testing.assert_allclose((m + m).std, 2 * m.std)
    sq = sysid.FRD(W, _ss(3, 2, 2, 5).freqresp(W), std=np.full((W.size, 2, 2), 0.01))
    assert np.abs((sq / sq).std).max() < 1e-12 and np.abs((sq - copy.copy(sq)).std).max() == 0


def test_equal_but_separate_frds_are_independent():
    g = sysid.FRD([1.0, 2.0], [3.0, 4j], std=[0.3, 0.4])
    h = sysid.FRD(g.omega, g.response, std=g.std)  # copies: a second, independent estimate
    np.testing.assert_allclose((g - h).std[:, 0, 0], np.sqrt(2) * np.array([0.3, 0.4]))
    np.testing.assert_allclose((g - g[0, 0]).std[:, 0, 0], np.sqrt(2) * np.array([0.3, 0.4]))


def test_fselect_keeps_a_band_with_its_std_and_coherence_for_a_band_limited_fit():
    # MATLAB's fselect(G, fmin, fmax): no way to keep a band of an FRD (users rebuilt it by
    # hand, losing its std and coherence)
    rng = np.random.default_rng(3)
    true = sysid.StateSpaceModel([[0.9, 0.3], [-0.3, 0.9]], [[1.0], [0.0]], [[1.0, 0.0]],
                                 dt=0.1, input_names=["f"], output_names=["a"])
    u = rng.standard_normal((4000, 1))
    d = sysid.IOData(u, true.simulate(u) + 0.05 * rng.standard_normal((4000, 1)), 0.1,
                     input_names=["f"], output_names=["a"])
    g = sysid.spa(d)
    band = g.fselect(1.0, 10.0)  # rad/s, the FRD's units
    keep = (g.omega >= 1.0) & (g.omega <= 10.0)
    np.testing.assert_array_equal(band.omega, g.omega[keep])
    np.testing.assert_array_equal(band.response, g.response[keep])
    np.testing.assert_array_equal(band.std, g.std[keep])
    np.testing.assert_array_equal(band.coherence, g.coherence[keep])
    assert (band.input_names, band.output_names, band.dt) == (["f"], ["a"], 0.1)
    hz = g.fselect(1.0 / (2 * np.pi), 10.0 / (2 * np.pi), units="Hz")
    np.testing.assert_array_equal(hz.omega, band.omega)
    np.testing.assert_array_equal(g.fselect(np.flatnonzero(keep)).omega, band.omega)
    np.testing.assert_array_equal(g.fselect(keep).omega, band.omega)
    # a frequency-domain fit of the band sees only the band: there it fits the estimate far
    # better than a fit of every line (0.76 against 2.4 mean error here)
    def err(m):
        return np.abs(m.freqresp(band.omega) - band.response).mean()
    assert err(sysid.tfest(band, 2, 1)) < 0.5 * err(sysid.tfest(g, 2, 1))
    with pytest.raises(sysid.DataError, match=r"no frequency from 50 to 60 rad/s: the FRD "
                                              r"spans .* rad/s"):
        g.fselect(50, 60)
    with pytest.raises(sysid.DataError, match="lo <= hi"):
        g.fselect(5, 1)
    with pytest.raises(sysid.ShapeError, match="one per frequency"):
        g.fselect(np.ones(3, bool))
    with pytest.raises(sysid.DataError, match="integers from 0 to"):
        g.fselect([0.5, 1.5])
