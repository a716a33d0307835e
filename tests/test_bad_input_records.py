"""A bare array where a record (or a list) belongs gets a DataError naming the function and
the fix, never an AttributeError or TypeError from inside the package (found by calling
every public function with a (50, 2) array: ssregest, advice, the filters, resample,
decimate, repair_nan, augment_inputs, augmented_fit, era_stabilization)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, ShapeError

ARR = np.ones((50, 2))
REC = sysid.IOData(u=np.arange(60.0) % 7, y=np.sin(np.arange(60.0)), dt=1.0)


@pytest.mark.parametrize("call, who", [
    (lambda: sysid.ssregest(ARR, 2), "ssregest"),
    (lambda: sysid.advice(ARR), "advice"),
    (lambda: sysid.lowpass(ARR, 0.1), "lowpass"),
    (lambda: sysid.highpass(ARR, 0.1), "highpass"),
    (lambda: sysid.bandpass(ARR, 0.1, 0.2), "bandpass"),
    (lambda: sysid.resample(ARR, 2.0), "resample"),
    (lambda: sysid.decimate(ARR, 2), "decimate"),
])
def test_a_bare_array_is_not_a_record(call, who):
    with pytest.raises(DataError, match=rf"{who} takes an IOData record.*got ndarray.*"
                                        rf"sysid\.{who}\(sysid\.IOData"):
        call()


def test_filters_do_not_guess_a_sample_time_from_a_pair():
    # cut-offs are in Hz: a (u, y) pair has no dt, so it is refused, not taken as dt = 1
    with pytest.raises(DataError, match="lowpass takes an IOData record, got tuple"):
        sysid.lowpass((ARR[:, :1], ARR[:, 1:]), 0.1)
    # the estimators take the pair (as ssest does)
    assert sysid.advice((REC.u, REC.y)).findings


def test_lists_and_shapes_are_named():
    with pytest.raises(DataError, match="functions must be a list"):
        sysid.augment_inputs(REC, 2)
    with pytest.raises(DataError, match="functions must be a list"):
        sysid.augmented_fit(REC, 2)
    assert sysid.augment_inputs(REC, "square").n_inputs == 2  # one name alone is a list
    with pytest.raises(DataError, match="orders must be an increasing sequence"):
        sysid.era_stabilization(np.ones((40, 1, 1)), 4)
    with pytest.raises(ShapeError, match="samples, channels"):
        sysid.repair_nan(ARR, 2)
    with pytest.raises(ShapeError, match="samples, channels"):
        sysid.repair_nan(np.ones(10), np.ones((10, 1)))


@pytest.mark.parametrize("call, match", [
    (lambda: sysid.augment_inputs(REC, [lambda u: u * 1j]),
     r"basis function <lambda> returned complex values.*np\.real"),
    (lambda: sysid.simsd(sysid.arx(REC, 1, 1, 1), REC.u + 1j, 2),
     r"u must be a real.*np\.real\(u\)"),
    (lambda: sysid.repair_nan(None, np.ones((10, 1)) * (1 + 1j)), r"pass np\.real\(y\)"),
    (lambda: sysid.repair_nan(np.ones((10, 1)) * 1j, np.ones((10, 1))), r"pass np\.real\(u\)"),
    (lambda: sysid.IOData(REC.u + 1j, REC.y, 1.0), r"complex values.*pass np\.real\(u\)"),
    (lambda: sysid.IOData.from_raw(REC.u, REC.y + 1j, 1.0), r"pass np\.real\(y\)"),
    (lambda: sysid.StateSpaceModel([[0.5j]], [[1.0]], [[1.0]]), r"pass np\.real\(A\)"),
])
def test_complex_arrays_are_refused_not_cast(call, match):
    # NumPy's cast drops the imaginary part with a ComplexWarning at most
    with pytest.raises(DataError, match=match):
        call()


def test_frequency_responses_stay_complex():
    frd = sysid.FRD([1.0, 2.0], np.array([1 + 1j, 0.5 - 0.2j]), dt=0.1)
    assert np.iscomplexobj(frd.response) and frd.response[1, 0, 0] == 0.5 - 0.2j


@pytest.mark.parametrize("call", [
    lambda recs: sysid.ssest(recs, 1),
    lambda recs: sysid.pem(recs, sysid.n4sid(REC, 1)),
    lambda recs: sysid.n4sid(recs, 1),
    lambda recs: sysid.arx(recs, 1, 1, 1),
    lambda recs: sysid.oe(recs, 1, 1, 1),
    lambda recs: sysid.tfest(recs, 1),
    lambda recs: sysid.spa(recs),
    lambda recs: sysid.identify(recs),
    lambda recs: sysid.compare(recs, sysid.n4sid(REC, 1)),
])
def test_a_list_of_records_names_merge(call):
    """ssest([est1, est2], 4) said only "got list": several records are one record's
    experiments, which a user makes with merge (MATLAB's merge(z1, z2))."""
    with pytest.raises(DataError, match=r"several experiments.*\.merge\(") as err:
        call([REC, REC])
    assert str(err.value).count("merge") == 2


def test_channels_first_arrays_are_refused_by_the_signal_tools_too():
    # IOData refused a (channels, samples) array with the fix, but crest_factor returned 500
    # "channels" of 2 samples each, detect_period searched a 2-sample record and repair_nan
    # interpolated across channels, silently
    from sysid.data.raw import repair_nan

    x = np.random.default_rng(0).standard_normal((2, 500))
    gap = x.copy()
    gap[1, 7] = np.nan
    for call in (lambda: sysid.crest_factor(x), lambda: sysid.detect_period(x),
                 lambda: repair_nan(None, gap)):
        with pytest.raises(sysid.ShapeError, match=r"time-first \(samples, channels\).*\.T"):
            call()
    # time-first, the same calls work
    assert sysid.crest_factor(x.T).shape == (2,)
    assert sysid.detect_period(x.T) is None
    assert repair_nan(None, gap.T)[0][1].shape == (500, 2)
