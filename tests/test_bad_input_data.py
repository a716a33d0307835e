"""Bad input to the data, FRD, serialisation, report, grey-box and recursive entry points:
a sysid error naming the problem and the fix, never a raw AttributeError, KeyError or
third-party error, a silently ignored argument or a misleading message."""

from __future__ import annotations

import numpy as np
import pytest

import sysid

from conftest import first_order_record


@pytest.fixture(scope="module")
def record():
    m, u, y, d = first_order_record()
    return m, u, y, d


# ---- 1. raw AttributeError --------------------------------------------------------------

@pytest.mark.parametrize("call", [
    lambda u: sysid.despike(u),
    lambda u: sysid.drop_quiet(u),
    lambda u: sysid.select_mask(u, np.ones(len(u), bool)),
    lambda u: sysid.select_mode(u, np.ones(len(u)), keep=1),
    lambda u: sysid.check_offsets(u),
])
def test_preprocessing_refuses_an_array_for_a_record(record, call):
    _, u, _, _ = record
    with pytest.raises(sysid.DataError, match="takes an IOData record"):
        call(u)


def test_merge_of_a_list_says_how_to_call_it(record):
    d = record[3]
    with pytest.raises(sysid.DataError, match=r"records\[0\]\.merge"):
        sysid.IOData.merge([d, d])


def test_frd_refuses_a_model_without_freqresp(record):
    m = record[0]
    with pytest.raises(sysid.DataError, match="freqresp"):
        sysid.FRD.from_model("x", [1.0])
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    frd = sysid.FRD.from_model(m, np.linspace(0.1, 30, 50))
    with pytest.raises(sysid.DataError, match="models must be a model with freqresp"):
        frd.plot(models="x")


def test_register_model_refuses_a_non_class():
    with pytest.raises(sysid.DataError, match="takes a model class"):
        sysid.register_model(5)


def test_report_refuses_a_selection_that_is_not_an_order_sweep(record, tmp_path):
    m, _, _, d = record
    with pytest.raises(sysid.DataError, match=r"result\.model"):
        sysid.report(m, d, tmp_path / "r", selection=sysid.identify(d))
    with pytest.raises(sysid.DataError, match="selection must be an order sweep"):
        sysid.report(m, d, tmp_path / "r", selection="aic")
    with pytest.raises(sysid.DataError, match="which must be"):
        sysid.report(m, d, tmp_path / "r", which="foo")
    assert not (tmp_path / "r").exists()
