"""compare's note on an error that is mostly a constant level (a sensor offset that differs
between records): the fit then measures the level, not the response (realdata_fresh8.md: a
test tower's accelerometers read 0.8 and 2.8 output standard deviations apart on two runs,
and every model's fit read -13 % and -188 % on those floors)."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import SysidWarning


def _record(offset: float, seed: int = 0):
    rng = np.random.default_rng(seed)
    m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=1.0)
    u = rng.standard_normal((600, 1))
    y = m.simulate(u) + 0.2 * rng.standard_normal((600, 1))
    return m, sysid.IOData(u=u, y=y + offset * y.std(), dt=1.0)


def test_a_level_the_input_does_not_cause_is_named_with_the_fit_without_it():
    m, data = _record(3.0)  # a sensor offset of 3 output standard deviations
    with pytest.warns(SysidWarning, match="mostly a constant level") as said:
        r = sysid.compare(data, m)
    assert r.levels == [(0, 0)]
    assert r.fit[0, 0] < -100  # the level dominates the fit ...
    note = r.notes[0]
    without = float(note.split("without that level it would be ")[1].split(" %")[0])
    assert without > r.fit[0, 0] + 150  # ... the response itself is simulated well
    assert "3.0 times the output's standard deviation" in str(said[0].message)


def test_no_note_without_a_level_or_for_a_small_one_on_a_good_fit():
    for offset in (0.0, 0.05):
        m, data = _record(offset)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            r = sysid.compare(data, m)
        assert r.levels == [] and r.notes == []
        assert r.fit[0, 0] > 80


def test_a_positive_fit_with_a_level_keeps_the_note_without_a_warning():
    m, data = _record(0.6)  # a level that costs points but leaves the fit above zero
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = sysid.compare(data, m)
    assert r.fit[0, 0] > 0 and r.levels == [(0, 0)]
    assert "constant level" in r.summary()


def test_a_growing_error_is_not_a_level():
    # an unstable model's error grows (its mean exceeds its spread too): not a level
    rng = np.random.default_rng(1)
    u = rng.standard_normal((300, 1))
    y = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1).simulate(u)
    bad = sysid.StateSpaceModel([[1.01]], [[1.0]], [[1.0]], dt=0.1)
    with pytest.warns(sysid.StabilityWarning):
        r = sysid.compare(sysid.IOData(u=u, y=y, dt=0.1), bad, x0="zero")
    assert r.levels == [] and r.fit[0, 0] < 0
