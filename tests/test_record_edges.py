"""Record handling at the edges: a trend past the last old sample after upsampling, a short
gap next to a cut, and a sample time given twice.

* ``resample`` held a recorded trend at its last value past the last old sample, so
  ``retrend()`` of an upsampled record was wrong at its end.
* ``repair_nan`` filled a short gap next to another channel's long gap (where the record is
  cut) by holding the last value: samples made up.
* ``ar(record, na, dt=...)`` replaced the record's own sample time silently.
"""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.data.raw import repair_nan

# ------------------------------------------------------------------ resample and trends


def test_upsampled_trend_continues_its_line_past_the_last_sample() -> None:
    lin = sysid.IOData(u=np.arange(10.0), y=2 * np.arange(10.0) + 1, dt=1.0)
    r = sysid.resample(sysid.detrend(lin, "linear"), 0.25)
    t = r.time
    # was [18.5, 19, 19, 19, 19]: the trend held past t = 9
    np.testing.assert_allclose(r.retrend().y[-5:, 0], [18.5, 19.0, 19.5, 20.0, 20.5])
    np.testing.assert_allclose(r.retrend().u[:, 0], t, atol=1e-9)  # u's trend is u itself


def test_piecewise_trend_extends_its_last_segment() -> None:
    # a time series (no inputs): resampling its detrended record raised a ValueError (the
    # empty input trend could not be stacked)
    k = np.arange(20.0)
    y = np.where(k < 10, k, 10 + 3 * (k - 10))  # slope 1, then 3 from sample 10
    d = sysid.detrend(sysid.IOData(u=None, y=y, dt=1.0), "piecewise", breakpoints=[10])
    r = sysid.resample(d, 0.5)
    trend = r.retrend().y[:, 0] - r.y[:, 0]
    t = r.time
    np.testing.assert_allclose(trend, np.where(t < 10, t, 10 + 3 * (t - 10)), atol=1e-9)


def test_downsampled_trend_is_unchanged() -> None:
    lin = sysid.IOData(u=np.arange(40.0), y=2 * np.arange(40.0) + 1, dt=1.0)
    r = sysid.resample(sysid.detrend(lin, "linear"), 2.0)
    np.testing.assert_allclose(r.retrend().y[:, 0] - r.y[:, 0], 2 * r.time + 1, atol=1e-9)


# ------------------------------------------------------------------ repair_nan next to a cut


def test_short_gap_next_to_a_cut_is_cut_not_held() -> None:
    k = np.arange(60.0)
    y = np.c_[k, 2 * k]
    y[10:12, 0] = np.nan   # short, but it runs into ...
    y[12:30, 1] = np.nan   # ... a long gap of the other channel, where the record is cut
    pieces = repair_nan(None, y, max_gap=5)
    first = pieces[0][1]
    # was 12 samples ending [9, 9, 9]: samples 10 and 11 of channel 0 made up
    assert [p[2] for p in pieces] == [0, 30] and first.shape[0] == 10
    np.testing.assert_array_equal(first[:, 0], k[:10])
    assert np.all(np.isfinite(np.vstack([p[1] for p in pieces])))


def test_cuts_reach_short_gaps_they_expose() -> None:
    # channel 1's gap 8:10 touches channel 0's gap 10:12 once that is cut (next to 12:30)
    k = np.arange(60.0)
    y = np.c_[k, 2 * k, 3 * k]
    y[10:12, 0] = np.nan
    y[8:10, 1] = np.nan
    y[12:30, 2] = np.nan
    pieces = repair_nan(None, y, max_gap=5)
    assert pieces[0][1].shape[0] == 8 and pieces[1][2] == 30
    np.testing.assert_array_equal(pieces[0][1], np.c_[k, 2 * k, 3 * k][:8])


def test_short_gap_between_good_samples_is_still_filled() -> None:
    k = np.arange(60.0)
    y = np.c_[k, 2 * k]
    y[5:7, 0] = np.nan     # good samples on both sides: interpolated
    y[12:30, 1] = np.nan
    pieces = repair_nan(None, y, max_gap=5)
    np.testing.assert_allclose(pieces[0][1][:, 0], k[:12])


def test_from_raw_cuts_a_gap_next_to_a_cut() -> None:
    k = np.arange(60.0)
    y = np.c_[k, 2 * k]
    y[10:12, 0] = np.nan
    y[12:30, 1] = np.nan
    d = sysid.IOData.from_raw(None, y, 1.0, nan="interpolate", max_gap=5)
    assert d.lengths == [10, 30]


# ------------------------------------------------------------------ ar's sample time


def test_ar_refuses_a_dt_that_disagrees_with_the_record() -> None:
    y = np.random.default_rng(0).standard_normal(300)
    rec = sysid.IOData(None, y, 0.5)
    with pytest.raises(sysid.DataError, match=r"dt = 0.1 s disagrees with the record's dt = "
                                              r"0.5 s"):
        sysid.ar(rec, 2, dt=0.1)
    assert sysid.ar(rec, 2, dt=0.5).dt == 0.5   # the same sample time, repeated, is fine
    assert sysid.ar(rec, 2).dt == 0.5
    assert sysid.ar(y, 2, dt=0.1).dt == 0.1     # an array takes it
