"""Names in what the polynomial estimators print and raise: a rank-deficient ``ivx`` fit names
``ivx`` (it said "iv4: ..."), and a polynomial model writes its equations with its own
channel names (``y0``, ``u0`` or the data's; it wrote ``y1``, ``u1`` for channels named
``y0``, ``u0``)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import ExcitationError


def test_ivx_rank_error_names_ivx():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(500)
    y = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]).simulate(u)
    with pytest.raises(ExcitationError, match=r"^ivx: .* give an x correlated with the "
                                              r"outputs"):
        sysid.ivx((u, y), 2, 2, 1, x=np.ones_like(y))


def test_iv4_rank_error_still_names_iv4():
    n = 500
    u = np.ones(n)
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.1 * ((t * 7919 % 13) - 6.0)
    with pytest.raises(ExcitationError, match=r"^iv4: "):
        sysid.iv4((u, y), 2, 4, 1)


def test_equations_use_the_default_channel_names():
    m = sysid.PolynomialModel([[[0.6], [1.0]], [[-0.9], [-1.2]]], [[[1.0]], [[0.5]]],
                              [[1], [1]], 1.0)
    text = repr(m)
    assert m.output_names == ["y0", "y1"] and m.input_names == ["u0"]
    assert "  y1: A10(q) y0(t) + A11(q) y1(t) = B0(q) u0(t-1) + e(t)" in text
    assert "A01(q) = 1 q^-1" in text and "A10(q) = -0.9 q^-1" in text
    assert "(y1's row of A, a 2x2 matrix polynomial" in text
    for stale in ("y2", "u1", "A21", "B1("):
        assert stale not in text


def test_equations_use_the_datas_channel_names():
    rng = np.random.default_rng(1)
    u = rng.standard_normal((300, 2))
    y = np.zeros((300, 1))
    for t in range(1, 300):
        y[t] = 0.5 * y[t - 1] + u[t - 1, 0] - 0.3 * u[t - 1, 1] + 0.01 * rng.standard_normal()
    d = sysid.IOData(u, y, 1.0, input_names=["flow", "heat"], output_names=["temp"])
    m = sysid.arx(d, 1, [[1, 1]], [[1, 1]])
    text = repr(m)
    assert "  temp: A(q) temp(t) = B0(q) flow(t-1) + B1(q) heat(t-1) + e(t)" in text
    assert m.summary().startswith(text)
