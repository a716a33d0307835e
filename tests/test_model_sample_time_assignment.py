"""A model's sample time is checked whenever it is written, with the constructor's own check
(:func:`sysid._checks.as_dt`), not only in the constructor.

Before: ``m.dt = np.nan`` gave a NaN frequency response without a word, ``m.dt = 0.0``
made ``damp`` read the discrete poles as continuous (wn 0.5 instead of 6.93 rad/s), and
``m.dt = -0.1`` gave negative step times and a file ``load_model`` refused; a
``ContinuousStateSpace``'s ``dt``, 0 by design, could be set to anything, and an ``FRD``'s
to NaN or a negative number.
"""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError

BAD = [np.nan, np.inf, 0.0, -0.1, None, "0.1", True]


def model():
    return sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)


@pytest.mark.parametrize("value", BAD)
def test_statespace_refuses_what_its_constructor_refuses(value):
    with pytest.raises(DataError):
        sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=value)
    m = model()
    with pytest.raises(DataError, match="dt must be a positive number of seconds.*"
                       "discrete-time.*ContinuousStateSpace.*d2c"):
        m.dt = value
    assert m.dt == 0.1                            # the model is left as it was
    assert sysid.damp(m).wn[0] == pytest.approx(np.log(2) / 0.1)


def test_out_of_range_says_which_units():
    with pytest.raises(DataError, match="lies outside.*other units"):
        model().dt = 1e-300


def test_the_cases_of_the_audit():
    m = model()
    for value in (np.nan, 0.0, -0.1):
        with pytest.raises(DataError):
            m.dt = value
    assert np.isfinite(m.freqresp([1.0])).all()
    assert sysid.damp(m).wn[0] == pytest.approx(6.931, abs=1e-3)
    assert (m.step(5).t >= 0).all()


def test_a_valid_sample_time_is_taken_and_saved(tmp_path):
    m = model()
    m.dt = np.float32(0.2)                        # as the constructor: the decimal 0.2
    assert m.dt == 0.2 and type(m.dt) is float
    assert sysid.damp(m).wn[0] == pytest.approx(np.log(2) / 0.2)
    m.save(tmp_path / "m.json")
    assert sysid.load_model(tmp_path / "m.json").dt == 0.2


def test_continuous_model_dt_stays_zero():
    c = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    c.dt = 0
    c.dt = None
    assert c.dt == 0.0 and sysid.ContinuousStateSpace.dt == 0.0
    for value in (0.1, np.nan, -1.0, "0"):
        with pytest.raises(DataError, match="continuous-time: its dt stays 0.*sysid.c2d"):
            c.dt = value
    assert c.dt == 0.0 and c.is_stable() and sysid.damp(c).wn[0] == pytest.approx(1.0)


def test_frd_sample_time_is_checked_on_assignment():
    f = sysid.FRD([1.0, 2.0], [1.0, 0.5], dt=0.1)
    for value in (np.nan, -0.1, "0.1"):
        with pytest.raises(DataError, match=r"positive number of seconds.*FRD.dt is the "
                           r"sample time.*or 0 \(None\) for continuous time"):
            f.dt = value
        with pytest.raises(DataError):
            sysid.FRD([1.0, 2.0], [1.0, 0.5], dt=value)
    assert f.dt == 0.1
    f.dt = 0
    assert f.dt is None                          # 0: continuous, as the constructor
    f.dt = 0.2
    assert f.dt == 0.2


def test_sampled_continuous_samples_again_at_a_new_dt():
    c = sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]])
    s = c.sampled(0.5)
    s.dt = 0.1
    assert s.A[0, 0] == pytest.approx(np.exp(-0.1))   # its realisation follows dt
    with pytest.raises(DataError):
        s.dt = -1.0
    assert s.dt == 0.1
