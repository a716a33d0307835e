"""Errors a user meets on everyday model calls name the problem and what to do.

Before: ``m[0.0, 0]`` raised ``TypeError: 'float' object is not iterable``; ``m[[True,
False], 0]`` silently selected the outputs 1 and 0; ``simulate(None)`` on a model without
inputs said it "needs n_samples (or y)", which ``simulate`` does not take; a
``ContinuousStateSpace``'s matrices could be replaced unchecked (``c.A = [[nan]]`` gave
NumPy's error later, a ``B`` of the wrong shape a gufunc error).
"""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, NonFiniteError, ShapeError


@pytest.fixture
def two_by_two():
    return sysid.StateSpaceModel([[0.5]], [[1.0, 2.0]], [[1.0], [3.0]], dt=0.1)


@pytest.mark.parametrize("key, said", [
    ((0.0, 0), "output 0.0 is not a channel.*integer index.*use 0"),
    ((0, 1.0), "input 1.0 is not a channel.*use 1"),
    ((np.array([0.0, 1.0]), 0), "output 0.0 is not a channel.*use 0"),
    ((0.5, 0), "output 0.5 is not a channel: select outputs by integer index"),
    ((True, 0), "boolean reads as the index 1.*np.flatnonzero"),
    (([True, False], 0), "boolean reads as the index 1.*np.flatnonzero"),
    (({0}, 0), "not a channel"),
])
def test_index_of_another_kind_is_refused_clearly(two_by_two, key, said):
    with pytest.raises(DataError, match=said):
        two_by_two[key]


def test_valid_selections_still_work(two_by_two):
    m = two_by_two
    assert m[0, 1].dcgain()[0, 0] == pytest.approx(4.0)
    assert m[np.int64(1), "u0"].dcgain()[0, 0] == pytest.approx(6.0)
    assert m[np.array([1, 0]), :].output_names == ["y1", "y0"]
    assert m[range(2), (0,)].output_names == ["y0", "y1"]
    assert m.select(outputs=-1).output_names == ["y1"]
    with pytest.raises(DataError, match="output 0.0 is not a channel"):
        m.select(outputs=0.0)


def test_frd_channels_are_checked_the_same_way():
    f = sysid.FRD([1.0, 2.0], np.ones((2, 2, 2)))
    assert f[0, 1].output_names == ["y0"]
    with pytest.raises(DataError, match="output 0.0 is not a channel.*use 0"):
        f[0.0, 1]


def test_simulate_without_inputs_says_what_to_pass():
    ts = sysid.StateSpaceModel([[0.5]], np.zeros((1, 0)), [[1.0]], K=[[0.5]], dt=1.0)
    with pytest.raises(DataError, match=r"model has no inputs.*np.zeros\(\(n_samples, 0\)\)"):
        ts.simulate(None)
    # the advice works
    np.testing.assert_allclose(ts.simulate(np.zeros((3, 0)), x0=[1.0])[:, 0],
                               [1.0, 0.5, 0.25])


def test_continuous_matrices_are_checked_on_assignment():
    c = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    with pytest.raises(NonFiniteError, match="A has non-finite entries"):
        c.A = [[np.nan]]
    with pytest.raises(ShapeError, match=r"B has shape \(1, 2\).*another model.*"
                       r"sysid.ContinuousStateSpace\(A, B, C, D"):
        c.B = [[1.0, 2.0]]
    with pytest.raises(ShapeError):
        c.C = np.ones((2, 2))
    with pytest.raises(ValueError, match="read-only"):
        c.D[0, 0] = 1.0
    assert c.dcgain()[0, 0] == pytest.approx(1.0)         # left as it was
    c.A, c.D = [[-2.0]], [[1.0]]                          # a valid whole matrix is taken
    assert c.dcgain()[0, 0] == pytest.approx(1.5)
    assert c.step(3, dt=1.0).y[-1, 0, 0] == pytest.approx(1 + (1 - np.exp(-4.0)) / 2)
