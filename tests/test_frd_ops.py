"""FRD indexing and frequency units."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from hypothesis import settings

import sysid
from sysid.errors import DataError

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
    # indexed, sampled: the units stay
    for h in (f[0, 0], f[:, :]):
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


