"""The parameter uncertainty of polynomial, transfer-function and process models carried
through ``to_statespace()``, ``to_tf()``, ``d2c``, ``d2d`` and ``c2d`` (it was dropped:
every ``std=True`` after them raised "no parameter uncertainty"). What a conversion leaves
unchanged has the same standard deviation after it; what it changes (continuous poles)
has the spread of the converted draws."""

import warnings

import numpy as np
import pytest

import sysid

DT = 0.1
W = [0.5, 3.0]  # rad/s, below the Nyquist frequency pi / DT


@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 1))
    plant = sysid.TransferFunction([0.0, 0.5, 0.3], [1.0, -1.2, 0.6], dt=DT)
    return sysid.IOData(u, plant.simulate(u) + 0.3 * rng.standard_normal((400, 1)), DT)


def _stds(m):
    """Pole (sorted), frequency response at W and DC gain standard deviations."""
    p, sp = m.poles(std=True)
    _, sH = m.freqresp(W, std=True)
    _, sg = m.dcgain(std=True)
    sp = sp[np.lexsort((p.imag, p.real))]
    return np.r_[sp.real, sp.imag, sH.ravel().real, sH.ravel().imag, np.ravel(sg)]


@pytest.mark.parametrize("fit", [
    lambda d: sysid.oe(d, 2, 2, 1),
    lambda d: sysid.armax(d, 2, 2, 1, 1),
    lambda d: sysid.tfest(d, 2, 1, dt=DT),
    lambda d: sysid.tfest(d, 2, 1),
], ids=["oe", "armax", "tf-discrete", "tf-continuous"])
def test_to_statespace_keeps_every_std(record, fit):
    m = fit(record)
    ss = m.to_statespace()
    np.testing.assert_allclose(_stds(ss), _stds(m), rtol=1e-6)
    assert ss.uncertainty.n_parameters == m.uncertainty.n_parameters


def test_process_model_to_tf_and_to_statespace_keep_every_std(record):
    m = sysid.procest(record, "P2U")
    np.testing.assert_allclose(_stds(m.to_tf()), _stds(m), rtol=1e-6)
    np.testing.assert_allclose(_stds(m.to_statespace()), _stds(m), rtol=1e-6)


def test_d2c_of_a_polynomial_model_is_that_of_its_realisation(record):
    m = sysid.armax(record, 2, 2, 1, 1)
    np.testing.assert_allclose(_stds(sysid.d2c(m)), _stds(sysid.d2c(m.to_statespace())),
                               rtol=1e-6)
    # the continuous poles change: their std is the spread of the converted draws
    p, sp = sysid.d2c(m).poles(std=True)
    k = int(np.argmax(p.imag))
    # (the zoh equivalent's poles are log(z) / dt: the draws' poles mapped, without a
    # matrix logarithm per draw)
    draws = [np.log(d.poles()) / DT for d in m.uncertainty.sample(2000, rng=1)]
    top = np.array([q[np.argmax(q.imag)] for q in draws])
    q = sysid.d2c(m.uncertainty.sample(1, rng=1)[0]).poles()
    np.testing.assert_allclose(q[np.argmax(q.imag)], top[0], rtol=1e-8)
    # sample std of 2000 Gaussian draws: ~1.6 % relative error; first order on a mildly
    # nonlinear map (the logarithm; ~1 % here with 4000 draws)
    assert abs(sp[k].real / top.real.std() - 1) < 0.06
    assert abs(sp[k].imag / top.imag.std() - 1) < 0.06


def test_resampling_keeps_the_dc_gain_std(record):
    tf = sysid.tfest(record, 2, 1, dt=DT)
    g, sg = tf.dcgain(std=True)
    for out in (sysid.d2d(tf, 2 * DT), sysid.d2d(tf, 0.15), sysid.d2c(tf)):
        np.testing.assert_allclose(out.dcgain(std=True)[1], sg, rtol=1e-6)
    tc = sysid.tfest(record, 2, 1)
    dz = sysid.c2d(tc, DT)  # zoh keeps the DC gain
    np.testing.assert_allclose(dz.dcgain(std=True)[1], tc.dcgain(std=True)[1], rtol=1e-6)
    p, sp = dz.poles(std=True)  # z = exp(s dt): the spread of the sampled draws
    z = np.array([sysid.c2d(d, DT).poles() for d in tc.uncertainty.sample(800, rng=2)])
    np.testing.assert_allclose(np.sort(np.abs(sp.real)), np.sort(z.real.std(0)), rtol=0.1)


def test_a_model_without_uncertainty_converts_without_one():
    m = sysid.PolynomialModel([[[-0.5]]], [[[1.0]]], [[1]], 1.0)
    assert m.to_statespace().uncertainty is None and sysid.d2c(m).uncertainty is None


@pytest.mark.parametrize("convert", [
    lambda m: sysid.canon(m, "modal"),
    lambda m: sysid.canon(m, "companion"),
    sysid.balanced_realization,
], ids=["modal", "companion", "balanced"])
def test_a_change_of_state_basis_keeps_every_std(record, convert):
    # each draw taken to the estimate's new basis (a fixed similarity): poles, responses
    # and the DC gain have the standard deviations they had
    for m in (sysid.n4sid(record, 2), sysid.oe(record, 2, 2, 1)):
        np.testing.assert_allclose(_stds(convert(m)), _stds(m), rtol=1e-6)


def test_pole_std_of_a_dead_time_realised_as_a_delay_line():
    # Before: poles(std=True) raised "the number of poles changed between samples" on a
    # process model with a dead time realised as states (identify's model of a heated air
    # duct's step test, 20 delay-line poles): the delay line's poles at z = 0 coincide, so
    # they go to Monte Carlo, and a draw whose dead time crosses a sample boundary has one
    # pole more or fewer there
    dt = 0.1
    true = sysid.ProcessModel("P1D", Kp=2.0, Tp1=1.5, Td=1.995)  # 19.95 samples
    rng = np.random.default_rng(1)
    u = np.repeat(rng.choice([-1.0, 1.0], 60), 10)
    y = true.to_statespace(dt=dt).simulate(u).ravel() + 0.05 * rng.standard_normal(u.size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pm = sysid.procest(sysid.IOData(u=u, y=y, dt=dt), "P1D")
    sd_td = float(np.sqrt(pm.uncertainty.covariance[2, 2]))
    td, tp1 = pm.uncertainty.theta[2], pm.uncertainty.theta[1]  # Kp, Tp1, Td
    assert abs(td / dt - 20.0) < 3 * sd_td / dt  # draws fall on both sides of 20 samples
    ss = pm.to_statespace(dt=dt)
    p, sd = ss.poles(std=True)
    slow = np.abs(p) > 0
    assert slow.sum() == 1 and np.all(sd[~slow] == 0)  # the delay line's poles: exact
    # the process pole exp(-dt / Tp1): first order through Tp1
    z = float(p[slow][0].real)
    expected = z * dt / tp1**2 * float(np.sqrt(pm.uncertainty.covariance[1, 1]))
    assert np.isclose(float(sd[slow][0].real), expected, rtol=0.05)
