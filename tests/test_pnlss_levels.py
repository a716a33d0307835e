"""PNLSS on inputs of few levels: powers of an input that its levels do not determine are left
out of the monomials, said, and the model fits as well without them."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.data.levels import input_levels
from sysid.errors import ExcitationWarning, IterationLimitWarning


def _bilinear(levels, seed=3, n=800):
    # x+ = 0.7 x + 0.5 u + 0.2 x u, y = x + 0.1 x^2: a PRBS of two levels (or more) in
    rng = np.random.default_rng(seed)
    u = rng.choice(levels, size=(n // 8, 1)).repeat(8, axis=0)
    x, y = 0.0, np.empty((n, 1))
    for t in range(n):
        y[t, 0] = x + 0.1 * x * x
        x = 0.7 * x + 0.5 * u[t, 0] + 0.2 * x * u[t, 0]
    return sysid.IOData(u, y, 1.0)


def test_powers_a_binary_input_does_not_determine_are_left_out_and_said():
    d = _bilinear([0.0, 1.0])
    with pytest.warns(ExcitationWarning, match=r"u0 takes 2 levels.*info\['undetermined"):
        m = sysid.pnlss(d, 1, degree=2, progress=False, tol=1e-12, max_iter=200)
    # x0 u0 stays (it is determined: x moves at both levels); u0^2 goes from both equations
    z = [sorted(t) for t in m.zeta]
    assert [0, 1] in z and [1, 1] not in z and all(t.count(1) < 2 for t in m.eta)
    assert m.info["undetermined_monomials"] == {"levels": [2], "monomials": 2, "kept": 4}
    # the data are fitted as well as with every monomial: the system is in the kept class
    # (simulated from the scaled origin: compared after its transient)
    y, yh = d.y[100:], m.simulate(d.u)[100:]
    assert np.max(np.abs(yh - y)) < 1e-6 * np.max(np.abs(y))


def test_an_input_of_three_levels_keeps_its_squares_not_its_cubes():
    d3 = _bilinear([0.0, 0.5, 1.0])
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        m = sysid.pnlss(d3, 1, degree=2, progress=False, max_iter=0)
        m3 = sysid.pnlss(d3, 1, degree=3, progress=False, max_iter=0)
    assert {w.category for w in said} == {IterationLimitWarning, ExcitationWarning}
    assert [1, 1] in [sorted(t) for t in m.zeta]
    assert "undetermined_monomials" not in m.info
    # degree 3: u0^3 is not determined by three levels, u0^2 x0 is
    (w,) = [w for w in said if w.category is ExcitationWarning]
    assert "u0 takes 3 levels, so its powers from 3 up" in str(w.message)
    z3 = [sorted(t) for t in m3.zeta]
    assert [1, 1, 1] not in z3 and [0, 1, 1] in z3


def test_input_levels_counts_over_records_and_ignores_rounding_only():
    u = np.repeat([[1.0], [5.0]], 10, axis=0)
    assert input_levels([u, u + 1e-12]).tolist() == [2]
    assert input_levels(u + 1e-3 * np.arange(20)[:, None], cap=4).tolist() == [4]


def test_the_dryers_binary_input_is_said_also_when_the_fit_is_held_stable():
    # the DaISy dryer's heater input is a binary PRBS; at order 4 the free search's linear
    # part leaves the unit circle and the fit is continued held stable: the monomials left
    # out are still recorded and said
    d = np.loadtxt(sysid.datasets.path("dryer"))
    est = sysid.IOData(u=d[:500, :1], y=d[:500, 1:2], dt=0.08)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        m = sysid.pnlss(est, 4, degree=2, progress=False)
    assert "held_stable" in m.info["fit"]
    assert m.info["undetermined_monomials"]["levels"] == [2]
    assert ExcitationWarning in {w.category for w in said}
