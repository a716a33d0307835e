"""PolynomialModel(...) refuses malformed coefficients, delays and variances with a DataError
that names the argument and the shape it should have (it rounded fractional delays,
ignored extra C entries, kept a wrong noise_variance until to_statespace, and raised numpy's
reshape error, an IndexError at simulate or a TypeError)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError

P = sysid.PolynomialModel
A, B = [[[-0.5]]], [[[1.0]]]


@pytest.mark.parametrize("nk", [[[1.7]], [[0.6]], [[np.float64(2.5)]], [[True]], [["1"]]])
def test_fractional_delays_are_refused(nk):
    """nk=[[1.7]] became 1 and [[0.6]] became 0, silently."""
    with pytest.raises(DataError, match="nk must hold delays >= 0 in whole samples"):
        P(A, B, nk, 1.0)


def test_integer_valued_delays_are_taken():
    assert P(A, B, [[2.0]], 1.0).nk.tolist() == [[2]]
    assert P(A, B, np.array([[3]]), 1.0).nk.dtype.kind == "i"
    assert P(A, [[[1.0], [2.0]]], 1, 1.0).nk.tolist() == [[1, 1]]  # one number for all
    assert P(A, [[]], [[]], 1.0).nk.shape == (1, 0)  # a time series
    assert P(A, [[]], np.zeros((1, 0)), 1.0).nk.shape == (1, 0)


def test_delays_of_another_shape_name_the_shape():
    """nk=[[1]] for two inputs raised numpy's "cannot reshape array of size 1"."""
    with pytest.raises(DataError, match=r"nk has shape \(1, 1\) but should be \(1, 2\)"):
        P(A, [[[1.0], [2.0]]], [[1]], 1.0)


@pytest.mark.parametrize("name", ["c", "d"])
def test_noise_polynomials_one_per_output(name):
    """c=[[0.1], [0.2]] on a one-output model was taken (the second ignored)."""
    with pytest.raises(DataError, match=rf"{name} must hold one coefficient array per output "
                                        r"\(1"):
        P(A, B, [[1]], 1.0, **{name: [[0.1], [0.2]]})
    assert P(A, B, [[1]], 1.0, **{name: [[0.1]]}).n_parameters == 3


def test_noise_variance_one_per_output():
    """A noise_variance of the wrong size was accepted until to_statespace failed."""
    with pytest.raises(DataError, match=r"noise_variance has shape \(2,\) but should be "
                                        r"\(1,\)"):
        P(A, B, [[1]], 1.0, noise_variance=[1.0, 2.0])
    np.testing.assert_array_equal(P(A, B, [[1]], 1.0, noise_variance=0.3).noise_variance,
                                  [0.3])
    m = P([[[-0.5], []], [[], [-0.2]]], [[[1.0]], [[1.0]]], [[1], [1]], 1.0,
          noise_variance=[0.1, 0.2])
    m.to_statespace()  # the variances fit the outputs
    with pytest.raises(DataError, match="noise_variance must be finite and >= 0"):
        P(A, B, [[1]], 1.0, noise_variance=[-1.0])


def test_f_with_too_few_entries():
    """f=[[[0.2]]] for two inputs raised an IndexError at simulate."""
    with pytest.raises(DataError, match=r"f has 1 row\(s\) of \[1\] entries but should be "
                                        r"1 x 2"):
        P([[[]]], [[[1.0], [1.0]]], [[1, 1]], 1.0, f=[[[0.2]]])


@pytest.mark.parametrize("a, b, match", [
    ([-0.5], B, r"a must be nested lists of coefficient arrays \(outputs x outputs"),
    (A, [1.0], r"b must be nested lists of coefficient arrays \(outputs x inputs"),
    (-0.5, B, "a must be nested lists"),
    ([[[-0.5]], [[0.1]]], [[[1.0]], [[1.0]]], r"a has 2 row\(s\) of \[1, 1\] entries but "
                                              r"should be 2 x 2"),
    (A, [[[1.0]], [[1.0]]], r"b has 2 row\(s\) of \[1, 1\] entries but should be 1 x 1"),
    ([[["x"]]], B, r"a\[0\]\[0\] must be a real numeric array"),
])
def test_flat_or_ragged_coefficients(a, b, match):
    """A flat a=[-0.5] raised "TypeError: 'float' object is not iterable"."""
    with pytest.raises(DataError, match=match):
        P(a, b, [[1]], 1.0)


def test_well_formed_models_are_unchanged():
    m = P([[np.array([-0.5])]], [[np.array([1.0, 0.3])]], [[1]], 1.0, c=[np.array([0.2])],
          d=[[0.1]], f=[[np.array([-0.4])]], noise_variance=[0.5])
    assert m.n_parameters == 6 and m.nk.tolist() == [[1]]
    np.testing.assert_allclose(m.simulate(np.ones((3, 1)))[:, 0], [0.0, 1.0, 2.2])
    again = P.from_dict(m.to_dict())
    assert repr(again) == repr(m)
