"""``model.predict(data, horizon=k)``: every model family takes a record in place of its
measured signals (MATLAB's ``predict(sys, data, K)``), with the result of
``model.predict(data.u, data.y, k)``; the ways it can be misused get errors that name the fix.
"""

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import DataError


@pytest.fixture(scope="module")
def records():
    d = sysid.datasets.load_dryer()
    return d[:300], d[300:420]


def _families(est):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        trend = sysid.detrend(est, "linear", return_trend=True)[1]
        return {
            "statespace": sysid.n4sid(est, 3),
            "polynomial": sysid.armax(est, [2, 2, 2, 1]),
            "transfer function": sysid.tfest(est, 2, 1),
            "process": sysid.procest(est, "P1D"),
            "continuous": sysid.d2c(sysid.n4sid(est, 2)),
            "trended": trend.attach(sysid.n4sid(est, 2)),
            "narx": sysid.nlarx(est, [2, 2, 1]),
            "hammerstein-wiener": sysid.nlhw(est, [2, 2, 1], max_iter=3),
            "identified": sysid.identify(est, max_order=3, progress=False).model,
        }


def test_every_family_predicts_a_record_as_its_signals(records):
    est, val = records
    for name, model in _families(est).items():
        for k in (1, 3):
            a = model.predict(val, horizon=k)
            kw = {"dt": val.dt} if getattr(model, "dt", 1) == 0 else {}  # continuous time
            b = model.predict(val.u, val.y, k, **kw)
            assert a.shape == (val.n_samples, 1), name
            np.testing.assert_array_equal(a, b, err_msg=name)
            assert np.isfinite(a).all(), name


def test_a_continuous_model_takes_the_record_s_sample_time(records):
    est, val = records
    with warnings.catch_warnings():  # the raw dryer's levels, said (from rest): not the point
        warnings.simplefilter("ignore", sysid.OffsetWarning)
        model = sysid.tfest(est, 2, 1)
    with pytest.raises(DataError, match="sample time"):  # arrays carry no sample time
        model.predict(val.u, val.y, 1)
    np.testing.assert_array_equal(model.predict(val), model.predict(val.u, val.y, 1,
                                                                     dt=val.dt))


def test_misuse_names_the_fix(records):
    est, val = records
    model = sysid.n4sid(est, 3)
    with pytest.raises(DataError, match=r"measured outputs y.*predict\(data, horizon=k\)"):
        model.predict(val.u)
    with pytest.raises(DataError, match=r"record and y: pass the record alone"):
        model.predict(val, val.y)
    two = val.merge(est)
    with pytest.raises(DataError, match=r"2 experiments.*data\.experiment\(i\).*compare"):
        model.predict(two, horizon=2)
