"""Bad input gets a clear error, never a silent NaN/inf or an ignored argument (round 2)."""

import numpy as np
import pytest

import sysid
from sysid.errors import DataError, InsufficientDataError, NonFiniteError


@pytest.fixture(scope="module")
def rec():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 1))
    m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)
    y = m.simulate(u) + 0.05 * rng.standard_normal((400, 1))
    return u, m, sysid.IOData(u=u, y=y, dt=0.1)


@pytest.fixture(scope="module")
def const():
    return sysid.IOData(u=np.ones((400, 1)), y=np.ones((400, 1)), dt=0.1)


def _motor(p, dt=None):
    return [[-1 / p.tau]], [[p.K / p.tau]], [[1.0]], [[0.0]]


@pytest.fixture(scope="module")
def gb():
    return sysid.GreyBox(_motor, params={"K": 2.0, "tau": sysid.param(0.5, bounds=(0.01, 10))})


# -- 1. silent NaN / inf ------------------------------------------------------------------
@pytest.mark.parametrize("tol", [float("nan"), -1.0])
@pytest.mark.parametrize("call", ["persistent_excitation_order", "zeros"])
def test_a_bad_tol_is_refused(rec, tol, call):
    # tol=nan made persistent_excitation_order return 0 for white noise
    arg = rec[0] if call == "persistent_excitation_order" else rec[1]
    with pytest.raises(DataError, match="tol must be a finite number >= 0"):
        getattr(sysid, call)(arg, tol=tol)


def test_criteria_resolution_nan(rec):
    with pytest.raises(DataError, match="resolution must be a finite number"):
        sysid.criteria(rec[1], rec[2], resolution=float("nan"))


def test_criteria_too_many_params(rec):
    with pytest.raises(InsufficientDataError, match="only 400 samples"):
        sysid.criteria(rec[1], rec[2], n_params=400)
    with pytest.raises(DataError, match="n_params must be an integer >= 0"):
        sysid.criteria(rec[1], rec[2], n_params=-3)
    assert np.isfinite(sysid.criteria(rec[1], rec[2]).aicc)


def test_fit_metrics_constant_output():
    with pytest.raises(DataError, match="output y0 is constant"):
        sysid.fit_metrics(np.ones((400, 1)), np.ones((400, 1)))


def test_arxstruc_constant_record(const):
    with pytest.raises(DataError, match="input u0 is 1 in every sample"):
        sysid.arxstruc(const, [1, 2], [1, 2], [1])


def test_procest_constant_record(const):
    with pytest.raises(DataError, match="procest cannot estimate"):
        sysid.procest(const, "P1")


def test_greyest_constant_record(const, gb):
    with pytest.raises(DataError, match="greyest cannot estimate"):
        sysid.greyest(const, gb)


def test_mac_nonfinite():
    with pytest.raises(NonFiniteError, match="phi1 has non-finite"):
        sysid.mac(np.full((3, 1), np.nan), np.ones((3, 1)))


# -- 2. raw internal exceptions -----------------------------------------------------------
@pytest.mark.parametrize("na", [[-1, 2], [np.nan], [1.5]])
def test_arxstruc_bad_orders(rec, na):
    with pytest.raises(DataError, match="every entry of na must be an integer >= 0"):
        sysid.arxstruc(rec[2], na, [1], [1])


def test_frd_subspace_bad_arguments(rec):
    frd = sysid.FRD.from_model(rec[1], np.linspace(0.1, 30, 100))
    with pytest.raises(DataError, match="order must be a positive integer"):
        sysid.frd_subspace(frd, float("nan"))
    with pytest.raises(DataError, match="method must be 'spa' or 'dft'"):
        sysid.frd_subspace(frd, 1, method="foo")
    with pytest.raises(DataError, match="T .* has no use here"):
        sysid.frd_subspace(frd, 1, T=5.0)


def test_n_parameters_checked():
    with pytest.raises(DataError, match="n must be an integer >= 0"):
        sysid.n_parameters(np.nan, 1, 1)
    with pytest.raises(DataError, match="n must be an integer >= 0"):
        sysid.n_parameters(-2, 1, 1)
    with pytest.raises(DataError, match="n_experiments must be a positive integer"):
        sysid.n_parameters(2, 1, 1, n_experiments=0)
    assert sysid.n_parameters(4, 1, 1) == 13


def test_freqresp_at_pole_is_inf():
    dm = sysid.StateSpaceModel([[1.0]], [[1.0]], [[1.0]], dt=0.1)
    h = dm.freqresp([0.0, 1.0])
    assert np.isinf(h[0, 0, 0]) and np.isfinite(h[1, 0, 0])
    cm = sysid.ContinuousStateSpace([[0.0]], [[1.0]], [[1.0]])
    assert np.isinf(cm.freqresp([0.0])[0, 0, 0])
    with pytest.raises(sysid.NumericalError, match="DC gain is infinite"):
        dm.dcgain()
    with pytest.raises(sysid.NumericalError, match="DC gain is infinite"):
        cm.dcgain()


@pytest.mark.parametrize("call", ["damp", "pem_loss", "minreal"])
def test_model_mutated_to_nan(rec, call):
    mm = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=0.1)
    with pytest.raises(ValueError, match="read-only"):  # the matrices are read-only now
        mm.A[0, 0] = np.nan
    mm.__dict__["_matrix_A"] = np.array([[np.nan]])  # made NaN behind their back
    args = (rec[2], mm) if call == "pem_loss" else (mm,)
    with pytest.raises(NonFiniteError, match="model's A has non-finite entries"):
        getattr(sysid, call)(*args)


# -- 3. wrong arguments accepted ----------------------------------------------------------
@pytest.mark.parametrize("tol", [float("nan"), -1.0])
def test_greyest_tol(rec, gb, tol):
    with pytest.raises(DataError, match="tol must be a positive finite number"):
        sysid.greyest(rec[2], gb, tol=tol)


def test_sampled_dt_checked(rec):
    with pytest.raises(DataError, match="dt must be a positive number"):
        sysid.tfest(rec[2], 1, 0).sampled(float("nan"))
    pm = sysid.ProcessModel("P1D", Kp=2.0, Tp1=1.5, Td=0.37)
    with pytest.raises(DataError, match="dt must be a positive number"):
        pm.sampled(-0.1)
    with pytest.raises(DataError, match="dt must be a positive number"):
        pm.sampled_taps(-0.1)
    with pytest.raises(DataError, match="hold must be 'zoh' or 'foh'"):
        pm.sampled_taps(0.1, hold="xx")


@pytest.mark.parametrize("dt", [float("nan"), -1.0])
def test_recursive_dt(dt):
    with pytest.raises(DataError, match="dt must be a positive number"):
        sysid.RecursiveARX(2, 2, 1, dt=dt)


def test_dt_contradicting_the_model(rec):
    mm = sysid.StateSpaceModel([[0.9, 0.3], [-0.3, 0.9]], [[1.0], [0.0]], [[1.0, 0.0]],
                               dt=0.1)
    with pytest.raises(DataError, match="contradicts the model's sample time"):
        sysid.modal_analysis(mm, dt=1.0)
    slow = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=1.0)
    with pytest.raises(DataError, match="sampled every 0.1 s but the model every 1 s"):
        sysid.pem_loss(rec[2], slow)


def test_selstruc_n_samples(rec):
    table = sysid.arxstruc(rec[2], [1, 2, 3], [1, 2], [1])
    for n in (-5, 0):
        with pytest.raises(DataError, match="n_samples must be a positive integer"):
            sysid.selstruc(table, "aic", n_samples=n)


def test_stepinfo_args(rec):
    with pytest.raises(DataError, match="n_samples must be an integer >= 2"):
        sysid.stepinfo(rec[1], n_samples=-1)
    with pytest.raises(NonFiniteError, match="yfinal must be finite"):
        sysid.stepinfo(rec[1], yfinal=float("nan"))


def test_select_order_scalar_orders(rec):
    with pytest.raises(DataError, match="orders must be a sequence of model orders"):
        sysid.select_order(rec[2], 3)


@pytest.mark.parametrize("ref", ["foo", "model"])
def test_iv4_reference(rec, ref):
    with pytest.raises(DataError, match="reference must be the reference signal"):
        sysid.iv4(rec[2], 2, 2, 1, reference=rec[1] if ref == "model" else ref)
