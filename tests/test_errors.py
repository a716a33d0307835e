"""Bad input raises a clear exception, case by case; nothing panics, nothing returns NaN."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid import _sysid

from conftest import random_system, simulate


@pytest.fixture
def record():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((200, 1))
    y = simulate(*random_system(2, 1, 1, rng), u)
    return u, y


def test_nan_in_output_names_sample_and_fix(record):
    u, y = record
    y = y.copy()
    y[17, 0] = np.nan
    with pytest.raises(
        sysid.NonFiniteError, match=r"y has a non-finite value .* sample 17.*interpolate"
    ):
        sysid.IOData(u=u, y=y)


def test_inf_in_input(record):
    u, y = record
    u = u.copy()
    u[3, 0] = np.inf
    with pytest.raises(sysid.NonFiniteError, match="u has a non-finite"):
        sysid.IOData(u=u, y=y)


def test_nan_reaching_the_core_directly_is_an_error_not_a_panic(record):
    u, y = record
    y = y.copy()
    y[50, 0] = np.nan
    with pytest.raises(sysid.NonFiniteError, match="sample 50"):
        _sysid.compress([(u, y)], 3, 3)


def test_too_few_samples_for_the_horizon(record):
    u, y = record
    with pytest.raises(sysid.InsufficientDataError, match="needs at least .* smaller horizon"):
        sysid.SubspaceEstimator(sysid.IOData(u=u[:30], y=y[:30]), horizon=10)


def test_too_few_samples_at_the_smallest_horizon_asks_only_for_more_data():
    """25 samples of 5 inputs and 2 outputs: n4sid's default horizon is already 2, the
    smallest, and the error told the user to use a smaller one (also pbsid's VARX)."""
    rng = np.random.default_rng(0)
    d = sysid.IOData(u=rng.standard_normal((25, 5)), y=rng.standard_normal((25, 2)))
    for fit in (sysid.n4sid, sysid.pbsid):
        with pytest.raises(sysid.InsufficientDataError) as e:
            fit(d)
        assert "needs at least" in str(e.value)
        assert "horizons are already at their smallest" in str(e.value)
        assert "smaller horizon" not in str(e.value)
    # shorter than the smallest window itself (3 samples, window 4): "allows horizon <= 1"
    # was offered, a horizon no subspace fit takes
    tiny = sysid.IOData(u=rng.standard_normal(3), y=rng.standard_normal(3))
    with pytest.raises(sysid.InsufficientDataError, match=r"smallest subspace window .* "
                       r"needs at least 4 but got 3; give a longer record$"):
        sysid.n4sid(tiny)


def test_experiment_shorter_than_the_window(record):
    u, y = record
    data = sysid.IOData(u=[u, u[:5]], y=[y, y[:5]])
    with pytest.raises(sysid.InsufficientDataError, match="experiment 2"):
        sysid.SubspaceEstimator(data, horizon=4)


def test_constant_input_is_not_persistently_exciting(record):
    _, y = record
    with pytest.raises(sysid.ExcitationError, match="input u0 is 1 in every sample"):
        sysid.SubspaceEstimator(sysid.IOData(u=np.ones((200, 1)), y=y), horizon=4).fit(2)


def test_rank_deficient_inputs(record):
    u, y = record
    u2 = np.hstack([u, 2 * u])
    with pytest.raises(sysid.ExcitationError, match="rank"):
        _ = sysid.SubspaceEstimator(sysid.IOData(u=u2, y=y), horizon=4).singular_values


def test_order_above_the_horizon_limit(record):
    u, y = record
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=4)
    with pytest.raises(sysid.OrderError, match="order 9 is too large.*at most"):
        est.fit(9)


@pytest.mark.parametrize("order", [0, -1, 2.5, "four", True])
def test_invalid_order_values(record, order):
    u, y = record
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=4)
    with pytest.raises(sysid.DataError):
        est.fit(order)


def test_mismatched_lengths(record):
    u, y = record
    with pytest.raises(sysid.ShapeError, match="u has 200 samples but y has 199"):
        sysid.IOData(u=u, y=y[:199])


def test_three_dimensional_arrays(record):
    u, y = record
    with pytest.raises(sysid.ShapeError, match="3-D"):
        sysid.IOData(u=u[:, :, None], y=y)


def test_strings(record):
    _, y = record
    with pytest.raises(sysid.DataError, match="string"):
        sysid.IOData(u="u.csv", y=y)
    with pytest.raises(sysid.DataError, match="dtype"):
        sysid.IOData(u=np.array(["a"] * 200), y=y)


def test_complex_data_is_rejected(record):
    u, y = record
    with pytest.raises(sysid.DataError, match="real numeric"):
        sysid.IOData(u=u + 1j, y=y)


def test_unknown_method_and_bad_horizon(record):
    u, y = record
    data = sysid.IOData(u=u, y=y)
    with pytest.raises(sysid.DataError, match="unknown method"):
        sysid.SubspaceEstimator(data, method="magic")
    with pytest.raises(sysid.DataError, match="horizon"):
        sysid.SubspaceEstimator(data, horizon=0)
    with pytest.raises(sysid.DataError, match="future horizon"):
        sysid.SubspaceEstimator(data, past=3, future=1).fit(1)


def test_bad_dt(record):
    u, y = record
    with pytest.raises(sysid.DataError, match="dt"):
        sysid.IOData(u=u, y=y, dt=0.0)


def test_simulate_with_wrong_channel_count(record):
    m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    with pytest.raises(sysid.ShapeError, match="1 column"):
        m.simulate(np.zeros((10, 2)))
    with pytest.raises(sysid.ShapeError):
        m.simulate(np.zeros(10), x0=[1.0, 2.0])


def test_model_matrices_with_inconsistent_shapes():
    with pytest.raises(sysid.ShapeError, match="B"):
        sysid.StateSpaceModel(np.eye(2), np.ones((3, 1)), np.ones((1, 2)))
    with pytest.raises(sysid.NonFiniteError):
        sysid.StateSpaceModel([[np.nan]], [[1.0]], [[1.0]])


def test_unstable_model_simulation_overflow_is_an_error():
    m = sysid.StateSpaceModel([[10.0]], [[1.0]], [[1.0]])
    with pytest.raises(sysid.NumericalError, match="unstable"):
        m.simulate(np.ones((2000, 1)))


def test_riccati_without_stabilising_solution():
    with pytest.raises(sysid.RiccatiError, match="no stabilising solution"):
        _sysid.kalman_gain(
            np.diag([1.5, 0.5]), np.array([[0.0, 1.0]]), np.eye(2), np.eye(1), np.zeros((2, 1))
        )


def test_x0_needs_the_data(record):
    u, y = record
    est = sysid.SubspaceEstimator(sysid.IOData(u=[u, u], y=[y, y]), horizon=3)
    est2 = sysid.SubspaceEstimator.from_factor(est.factor)
    with pytest.raises(sysid.DataError, match="needs the data"):
        est2.fit(2, x0=True)


def test_kalman_gain_with_mismatched_shapes_is_a_shape_error_not_a_panic():
    with pytest.raises(sysid.ShapeError, match="C has shape"):
        _sysid.kalman_gain(np.eye(2), np.zeros((1, 3)), np.eye(2), np.eye(1), np.zeros((2, 1)))


def test_every_sysid_warning_derives_from_one_base_class():
    # sysid's own plain warnings (identify's skipped candidates and time budget, the
    # residuals' untested independence, a horizon note, the file readers' guesses) were
    # bare UserWarnings, and DelayWarning and CompressionFallbackWarning were not exported:
    # a user could not silence or catch sysid's warnings alone
    import warnings

    exported = [getattr(sysid, n) for n in dir(sysid) if n.endswith("Warning")]
    assert {"SysidWarning", "DelayWarning", "CompressionFallbackWarning"} <= {
        w.__name__ for w in exported}
    assert all(issubclass(w, sysid.SysidWarning) for w in exported)
    assert issubclass(sysid.SysidWarning, UserWarning)
    # the residual tests of a record too short for the independence test: a SysidWarning
    rng = np.random.default_rng(0)
    u = rng.standard_normal((60, 5))
    y = u @ rng.standard_normal((5, 1)) + 0.1 * rng.standard_normal((60, 1))
    d = sysid.IOData(u=u, y=y)
    m = sysid.StateSpaceModel(np.zeros((1, 1)), np.zeros((1, 5)), np.zeros((1, 1)),
                              np.linalg.lstsq(u, y, rcond=None)[0].T, dt=1.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sysid.residuals(m, d)
    said = [w for w in caught if "independence not tested" in str(w.message)]
    assert said and all(issubclass(w.category, sysid.SysidWarning) for w in said)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", sysid.SysidWarning)
        sysid.residuals(m, d)  # silenced by the one filter
