"""The validation input's coverage by the estimation input's bands (issue 26): a chirp split in
time validates a model where it was never fitted, and identify(validation=) says so."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.validation.coverage import coverage_note, input_coverage

PLANT = sysid.StateSpaceModel([[1.6, -0.8], [1.0, 0.0]], [[1.0], [0.0]], [[0.1, 0.05]], dt=0.01)


def _record(u: np.ndarray, seed: int = 0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    y = PLANT.simulate(u)
    return sysid.IOData(u=u, y=y + 0.01 * np.std(y) * rng.standard_normal(y.shape), dt=0.01)


@pytest.mark.parametrize("method", ["linear", "logarithmic"])
def test_a_chirp_split_in_time_is_flagged_both_ways(method: str) -> None:
    u = sysid.chirp(6000, 0.01, 0.2, 20.0, method=method)
    first, last = u[:4000], u[4000:]
    fwd = input_coverage(_record(first), _record(last))
    back = input_coverage(_record(last), _record(first))
    assert fwd.extrapolates and back.extrapolates
    assert fwd.outside[0] > 0.5 and back.outside[0] > 0.5
    # the bands named lie beyond the estimation part's sweep (it ended below the validation's)
    f_end = 0.2 + (20.0 - 0.2) * 4000 / 6000 if method == "linear" else 0.2 * 100 ** (2 / 3)
    assert fwd.bands[0] and min(lo for lo, _ in fwd.bands[0]) > 0.8 * f_end
    assert "extrapolation" in repr(fwd) and "%" in fwd.summary()


@pytest.mark.parametrize("kind", ["prbs", "white", "multisine", "schroeder_periods"])
def test_ordinary_excitations_are_not_flagged(kind: str) -> None:
    n = 6000
    if kind == "prbs":
        u = np.asarray(sysid.idinput(n, "prbs", band=(0.0, 0.5), seed=3), float).reshape(n, -1)
    elif kind == "white":
        u = np.random.default_rng(3).standard_normal((n, 1))
    elif kind == "multisine":  # random phases
        u = np.asarray(sysid.multisine(n, band=(0.01, 0.4), phases="random", seed=3),
                       float).reshape(n, -1)
    else:  # Schroeder's phases sweep through the band within a period: whole periods here
        u = np.asarray(sysid.multisine(n // 3, band=(0.01, 0.4), periods=3), float).reshape(n, -1)
    cov = input_coverage(_record(u[:4000]), _record(u[4000:]))
    assert not cov.extrapolates, cov.summary()
    assert cov.outside[0] < 0.05


def test_a_schroeder_multisine_cut_inside_its_period_is_a_sweep() -> None:
    # Schroeder's phases make one period a sweep of the band: a cut inside it extrapolates
    u = np.asarray(sysid.multisine(6000, band=(0.01, 0.4)), float).reshape(6000, -1)
    assert input_coverage(_record(u[:4000]), _record(u[4000:])).extrapolates


def test_identify_records_the_extrapolation_among_its_checks() -> None:
    rng = np.random.default_rng(2)
    u = sysid.chirp(3000, 0.01, 0.2, 20.0, method="linear") + 0.01 * rng.standard_normal((3000, 1))
    est, val = _record(u[:2000]), _record(u[2000:])
    res = sysid.identify(est, validation=val, progress=False, max_order=4)
    assert "validation" in res.checks
    assert "did not excite" in res.checks["validation"]
    assert "validation" in res.summary()
    w = np.random.default_rng(1).standard_normal((3000, 1))
    plain = sysid.identify(_record(w[:2000]), validation=_record(w[2000:], 1), progress=False,
                           max_order=4)
    assert "validation" not in plain.checks
    assert coverage_note(_record(w[:2000]), _record(w[2000:], 1)) is None


def test_bad_records_are_refused_clearly() -> None:
    u = np.random.default_rng(0).standard_normal((500, 1))
    with pytest.raises(sysid.DataError, match="inputs"):
        input_coverage((u, u), (np.hstack([u, u]), u))
    with pytest.raises(sysid.DataError, match="sample times"):
        input_coverage(sysid.IOData(u, u, dt=0.1), sysid.IOData(u, u, dt=0.2))
    with pytest.raises(sysid.DataError, match="segment"):
        input_coverage((u, u), (u, u), segment=4)
    with pytest.raises(sysid.DataError, match="floor"):
        input_coverage((u, u), (u, u), floor=2.0)


def test_a_validation_input_that_stands_still_is_no_extrapolation():
    # a heater held at one level through the validation part (a PID log): its rounding
    # noise sat in a bin the estimation input's spectrum leaves empty, read as 67 % outside
    rng = np.random.default_rng(3)
    u = np.r_[rng.standard_normal(3000), np.full(1500, 21.116)]
    y = np.zeros_like(u)
    cov = input_coverage((u[:3000], y[:3000]), (u[3000:], y[3000:]))
    assert not cov.extrapolates and cov.outside[0] == 0.0
