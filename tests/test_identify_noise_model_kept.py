"""``sysid.identify`` returns a subspace candidate with its noise model (``K``,
``noise_cov``): attaching the simulation-error criterion's uncertainty replaced the model
by one without ``K``, so that its one-step predictions were its simulation (coloured noise
on a 2-state plant: ``cva``, order 3, compare(horizon=1) 32.0 %, where the same candidate
with its ``K`` predicts at 83.3 %) and the command line said "no noise model". The
simulation is unchanged (``K`` plays no part in it), and the BIC of the returned model is
the leaderboard's: a subspace fit's ``K`` is not charged (no simulation error depends on
it)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import lfilter

import sysid
from sysid.identify.board import bic

PLANT = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 0.5]])


@pytest.fixture(scope="module")
def coloured():
    """The auditor's record: AR(1) noise with a pole at 0.97 on the plant's output."""
    rng = np.random.default_rng(4)
    n = 2000
    u = rng.standard_normal(n)
    e = lfilter([1.0], [1.0, -0.97], 0.3 * rng.standard_normal(n))
    y = PLANT.simulate(u) + e[:, None]
    est = sysid.IOData(u=u[:1000], y=y[:1000])
    val = sysid.IOData(u=u[1000:], y=y[1000:])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(est, validation=val, progress=False)
    return est, val, res


def _fit(model, data, **kw) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return float(sysid.compare(model, data, **kw).mean_fit)


def test_the_chosen_subspace_model_keeps_its_kalman_gain(coloured):
    est, val, res = coloured
    info = res.model.info["identify"]
    assert info["family"] in ("moesp", "n4sid", "cva")  # a subspace candidate is chosen
    ss = res.model.statespace
    assert ss.K is not None and ss.noise_cov is not None
    assert "no noise model" not in repr(ss)
    # the same candidate re-fitted on the record identify fitted it to: the same K
    centred = res.model.remove_offsets(est)
    refit = sysid.SubspaceEstimator(centred).fit(
        ss.nstates, method=info["family"], feedthrough=info["feedthrough"])
    np.testing.assert_allclose(ss.K, refit.K, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(ss.noise_cov, refit.noise_cov, rtol=1e-10)
    # one-step prediction uses it: far above the simulation on coloured noise
    sim, pred = _fit(res.model, val), _fit(res.model, val, horizon=1)
    assert pred > sim + 30.0
    assert not np.allclose(res.model.predict(val.u, val.y), res.model.simulate(val.u))
    # the simulation and the reported fits are the candidate's (K does not enter them)
    np.testing.assert_allclose(res.model.statespace.simulate(centred.u), refit.simulate(
        centred.u), rtol=1e-9, atol=1e-12)
    assert res.validation_fit == pytest.approx(sim, abs=1e-9)
    # its uncertainty is kept, and its draws carry the noise model too
    unc = ss.uncertainty
    assert unc is not None and unc.build(unc.theta).K is not None


def test_the_returned_models_bic_is_the_leaderboards(coloured):
    est, _, res = coloured
    chosen = next(r for r in res.leaderboard if r["chosen"])
    centred = res.model.remove_offsets(est)
    assert bic(res.model.statespace, centred) == pytest.approx(chosen["bic"], rel=1e-12)


def test_only_a_kalman_gain_fitted_with_the_dynamics_is_charged():
    from sysid.identify.board import noise_fitted

    rng = np.random.default_rng(0)
    u = rng.standard_normal(400)
    d = sysid.IOData(u=u, y=PLANT.simulate(u) + 0.1 * rng.standard_normal((400, 1)))
    sub = sysid.SubspaceEstimator(d).fit(2)
    assert sub.K is not None and not noise_fitted(sub)
    bare = sysid.StateSpaceModel(sub.A, sub.B, sub.C, sub.D)
    assert bic(sub, d) == pytest.approx(bic(bare, d), rel=1e-12)  # K changes no sim. error
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pred = sysid.pem(d, sub, focus="prediction", progress=False)
    assert noise_fitted(pred)  # its K shaped A, B, C: counted, n l more parameters
    bare = sysid.StateSpaceModel(pred.A, pred.B, pred.C, pred.D)
    assert bic(pred, d) - bic(bare, d) == pytest.approx(2 * np.log(400), rel=1e-9)
