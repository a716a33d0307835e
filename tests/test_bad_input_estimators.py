"""Bad input to the estimators: a clear sysid error naming the problem and the fix (found by
fuzzing): a record without outputs, channels out of double precision's range, arrays given
to detrend, non-finite orders, an impossible delay, a constant output in tfest, and a start
model of another sample time or with NaN entries in pem."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, NonFiniteError, ShapeError

from conftest import first_order_record


@pytest.fixture(scope="module")
def record():
    _, u, y, d = first_order_record()
    return u, y, d


# ---------------------------------------------------------------- 1. no output channel


def test_iodata_refuses_no_output_channel(record):
    u, _, _ = record
    with pytest.raises(ShapeError, match=r"shape \(400, 0\): no output channel"):
        sysid.IOData(u=u, y=np.zeros((400, 0)), dt=0.1)


def test_iodata_keeps_no_input_channel(record):
    _, y, _ = record
    assert sysid.IOData(u=np.zeros((400, 0)), y=y, dt=0.1).n_inputs == 0
    assert sysid.IOData(u=None, y=y, dt=0.1).n_inputs == 0


# ---------------------------------------------------------------- 2. magnitudes


CALLS = {
    "arx": lambda d: sysid.arx(d, 1, 1, 1),
    "armax": lambda d: sysid.armax(d, 1, 1, 1, 1),
    "oe": lambda d: sysid.oe(d, 1, 1, 1),
    "bj": lambda d: sysid.bj(d, 1, 1, 1, 1, 1),
    "n4sid": lambda d: sysid.n4sid(d, 1),
    "ssest": lambda d: sysid.ssest(d, 1),
    "tfest": lambda d: sysid.tfest(d, 1, 0),
    "pem": lambda d: sysid.pem(d, sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)),
    "nlhw": lambda d: sysid.nlhw(d, 1, 1, 1),
}


@pytest.mark.parametrize("scale", [1e300, 1e200, 1e-300])
@pytest.mark.parametrize("name", sorted(CALLS))
def test_out_of_range_channels_refused(record, name, scale):
    u, y, _ = record
    with pytest.raises(DataError, match="output y0 has values of order .*rescale the channel"):
        CALLS[name](sysid.IOData(u=u * scale, y=y * scale, dt=0.1))


@pytest.mark.parametrize("scale", [1e300, 1e-300])
def test_out_of_range_time_series_refused(record, scale):
    _, y, _ = record
    with pytest.raises(DataError, match="output y0 has values of order .*rescale"):
        sysid.ar(sysid.IOData(y=y * scale, dt=0.1), 2)


def test_out_of_range_input_named(record):
    u, y, _ = record
    with pytest.raises(DataError, match=r"input u0 has values of order 4e\+200"):
        sysid.arx(sysid.IOData(u=u * 1e200, y=y, dt=0.1), 1, 1, 1)


@pytest.mark.parametrize("scale", [1e-12, 1e12])
def test_realistic_magnitudes_accepted(record, scale):
    u, y, _ = record
    d = sysid.IOData(u=u * scale, y=y * scale, dt=0.1)
    for m in (sysid.arx(d, 1, 1, 1), sysid.n4sid(d, 1)):
        assert abs(m.poles()[0] - 0.8) < 0.05


def test_constant_tiny_output_keeps_its_error(record):
    u, _, _ = record
    d = sysid.IOData(u=u, y=np.full((400, 1), 1e-200), dt=0.1)
    with pytest.raises(DataError, match="in every sample"):
        sysid.arx(d, 1, 1, 1)
    with pytest.raises(DataError, match="is constant"):
        sysid.n4sid(d, 1)


# ---------------------------------------------------------------- 3. detrend of an array


def test_detrend_of_array_names_iodata(record):
    u, _, _ = record
    with pytest.raises(DataError, match="detrend takes an IOData record, got ndarray"):
        sysid.detrend(u)
    with pytest.raises(DataError, match="scale takes an IOData record"):
        sysid.scale(u)


# ---------------------------------------------------------------- 4. orders and delays


@pytest.mark.parametrize("order", [float("inf"), float("nan"), 2.5])
@pytest.mark.parametrize("name", ["n4sid", "moesp", "cva", "ssest"])
def test_non_finite_order_refused(record, name, order):
    with pytest.raises(DataError, match="order must be a positive integer"):
        getattr(sysid, name)(record[2], order)


def test_ssest_non_finite_order_with_auto_feedthrough(record):
    with pytest.raises(DataError, match="order must be a positive integer"):
        sysid.ssest(record[2], float("inf"), feedthrough="auto")


@pytest.mark.parametrize("order", [float("inf"), float("nan")])
def test_tfest_non_finite_poles_refused(record, order):
    with pytest.raises(DataError, match="n_poles must be a whole number"):
        sysid.tfest(record[2], order)


def test_tfest_delay_beyond_record(record):
    with pytest.raises(DataError, match="iodelay = 1e\\+09 s exceeds what the record allows"):
        sysid.tfest(record[2], 2, 1, iodelay=1e9)


# ---------------------------------------------------------------- 5. constant output in tfest


def test_tfest_constant_output_refused(record):
    u, _, _ = record
    d = sysid.IOData(u=u, y=np.full((400, 1), 3.0), dt=0.1)
    with pytest.raises(DataError, match="output y0 is 3 in every sample: tfest"):
        sysid.tfest(d, 2, 1)


# ---------------------------------------------------------------- 6. start models


def test_pem_start_of_another_sample_time(record):
    start = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=1.0)
    with pytest.raises(DataError, match="sampled every 0.1 s but the start model every 1 s"):
        sysid.pem(record[2], start)


def test_pem_start_with_nan_matrix(record):
    start = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
    with pytest.raises(ValueError, match="read-only"):  # the matrices are read-only now
        start.A[0, 0] = np.nan
    start.__dict__["_matrix_A"] = np.array([[np.nan]])  # made NaN behind their back
    with pytest.raises(NonFiniteError, match="start model's A has non-finite entries"):
        sysid.pem(record[2], start)
    with pytest.raises(NonFiniteError, match="start model's A has non-finite entries"):
        sysid.ssest(record[2], start)  # MATLAB's ssest(data, init_sys): pem's checks
    with pytest.raises(DataError, match="ssest takes an order, a sysid.StateSpaceModel"):
        sysid.ssest(record[2], sysid.ContinuousStateSpace([[-1.0]], [[1.0]], [[1.0]]))


def test_channel_statistics_of_no_channel_or_no_sample_do_not_panic():
    # the compiled kernel split each row into lanes of width 8 x channels: with no channel
    # that width was zero and Rust panicked across the boundary (PanicException)
    from sysid import _sysid

    abs_max, mean, std = _sysid.channel_stats([np.zeros((10, 0))])
    assert abs_max.size == mean.size == std.size == 0
    with pytest.raises(DataError, match="no samples"):
        _sysid.channel_stats([np.zeros((0, 3))])
