"""identify on a record sampled far faster than its input changes
(:mod:`sysid.identify.oversampled`)."""

import warnings

import numpy as np
import pytest

import sysid
from sysid.data.oversampling import decimation_factor, input_band

DT = 0.001  # 1 kHz, as a bench logger samples a valve swept by a slow chirp


def _plant():
    # a lightly damped 1.5 Hz mode and a 20 Hz pole (an electrical lag), sampled at 1 kHz
    wn, z = 2 * np.pi * 1.5, 0.3
    ct = sysid.ContinuousStateSpace([[0.0, 1.0, 0.0], [-wn ** 2, -2 * z * wn, wn ** 2],
                                     [0.0, 0.0, -2 * np.pi * 20]],
                                    [[0.0], [0.0], [2 * np.pi * 20]], [[1.0, 0.0, 0.0]])
    return sysid.c2d(ct, DT)


def _chirp_record(seed, n=40000):
    # a chirp from 0.2 to 3 Hz around a level, the output with a little sensor noise
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    f = 0.2 + (3.0 - 0.2) * t / t[-1] / 2
    u = 5.0 + 2.0 * np.sin(2 * np.pi * f * t)
    y = _plant().simulate(u - 5.0) + 1.0 + 1e-3 * rng.standard_normal((n, 1))
    return sysid.IOData(u=u, y=y, dt=DT)


def test_every_subspace_window_refuses_the_record_as_sampled():
    # the premise: 20 samples of a slow chirp are a smooth curve (numerical rank 6 of 20);
    # the refusal names the decimation that helps (before: "use a richer input")
    d = _chirp_record(0)
    centred = sysid.IOData(u=d.u - d.u.mean(0), y=d.y - d.y.mean(0), dt=DT)
    q = decimation_factor(d)
    with pytest.raises(sysid.ExcitationError, match="not persistently exciting") as err:
        sysid.n4sid(centred, 3)
    assert f"sysid.decimate(data, {q})" in str(err.value) and "sysid.identify" in str(err.value)
    assert err.value.remedy.startswith("the inputs change slowly against the sample time")


def test_identify_decimates_an_oversampled_record_and_returns_the_model_at_its_rate():
    # before, identify raised the subspace estimators' ExcitationError: no model at all
    est, val = _chirp_record(0), _chirp_record(1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(est, validation=val, progress=False)
    m = res.model.statespace
    assert m.dt == DT and res.model.dt == DT
    q = m.info["decimated"]["q"]
    assert q == decimation_factor(est) and 10 <= q <= 40  # the chirp's band at 0.2 of Nyquist
    assert m.info["decimated"]["dt"] == pytest.approx(q * DT)
    assert "decimated by" in res.checks["sampling"] and "d2d" in res.checks["sampling"]
    # the feedback test is the record's as sampled (p = 1): the anti-alias filter's smoothing
    # makes past outputs predict the smooth input a little beyond its own past, and the
    # decimated copy's own test "detects" feedback (p = 1e-125), which set the open-loop
    # subspace fits aside
    assert res.checks["feedback"].startswith("not detected")
    assert not any(r["family"] in ("pbsid", "ssarx") for r in res.leaderboard)
    # it simulates fresh data at the record's rate as the true plant does: 99.0 %, converted
    # with a first-order hold (Tustin's map 97.1 %, a zero-order hold 85.8 %: it takes the
    # smooth input as held over each decimated sample, half a sample late)
    assert res.validation_fit > 98.0
    assert "first-order hold" in res.checks["sampling"]
    assert res.validation_fit == pytest.approx(res.model.compare(val).mean_fit)
    assert res.model.is_stable()
    # its static gain and mode are the plant's (1 and 1.5 Hz)
    assert np.allclose(m.dcgain(), 1.0, atol=0.03)
    ct = sysid.d2c(m)
    freqs = np.abs(np.linalg.eigvals(ct.A)) / (2 * np.pi)
    assert np.min(np.abs(freqs - 1.5)) < 0.05


def _pendulum_record(seed, amp):
    # a short record: a lightly damped 0.45 Hz pendulum logged at 20 Hz for 60 s while a
    # chirp sweeps it from 0.09 to 0.7 Hz (a student rig's identification run)
    dt = 0.05
    wn, z = 2 * np.pi * 0.45, 0.05
    ct = sysid.ContinuousStateSpace([[0.0, 1.0], [-wn ** 2, -2 * z * wn]], [[0.0], [wn ** 2]],
                                    [[1.0, 0.0]])
    t = np.arange(1200) * dt
    u = amp * np.sin(2 * np.pi * (0.09 + 0.61 * t / t[-1] / 2) * t)
    y = sysid.c2d(ct, dt).simulate(u) + 0.01 * np.random.default_rng(seed).standard_normal(
        (1200, 1))
    return sysid.IOData(u=u, y=y, dt=dt)


def test_a_short_record_twice_oversampled_is_decimated_too():
    # 1 200 samples whose input needs half the rate: every subspace window refuses them
    # (rank 11 of 20). Decimated by 2 they keep 600 samples; with at least 1 000 required
    # after decimation identify refused the record outright
    est, val = _pendulum_record(0, 1.0), _pendulum_record(1, 0.7)
    assert decimation_factor(est) == 2
    centred = sysid.IOData(u=est.u - est.u.mean(0), y=est.y - est.y.mean(0), dt=est.dt)
    with pytest.raises(sysid.ExcitationError, match="sysid.decimate"):
        sysid.n4sid(centred, 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(est, validation=val, progress=False)
    assert res.model.statespace.info["decimated"]["q"] == 2 and res.model.dt == est.dt
    assert res.validation_fit > 95.0 and res.model.is_stable()


def test_a_record_refused_for_another_reason_still_raises():
    # two tones high in the band (persistently exciting of order 4 only): refused, and no
    # decimation helps (its band is most of the Nyquist band), so identify raises the
    # subspace estimators' error as before
    rng = np.random.default_rng(0)
    t = np.arange(6000)
    u = np.sin(0.3 * np.pi * t) + np.sin(0.7 * np.pi * t)
    d = sysid.IOData(u=u, y=_plant().simulate(u) + 0.01 * rng.standard_normal((6000, 1)),
                     dt=DT)
    assert input_band(d) > 0.5 and decimation_factor(d) is None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(sysid.ExcitationError, match="not persistently exciting"):
            sysid.identify(d, progress=False)


def test_a_coarse_pole_on_the_negative_real_axis_is_converted_by_tustins_map():
    # no first-order-hold equivalent exists for it: Tustin's map keeps the order, and the
    # check says which conversion was made
    from sysid.identify.oversampled import _at_record_rate
    from sysid.identify.result import IdentifiedModel, IdentifyResult

    coarse = sysid.StateSpaceModel([[0.9, 0.0], [0.0, -0.5]], [[1.0], [1.0]], [[1.0, 0.2]],
                                   dt=10 * DT)
    res = IdentifyResult(IdentifiedModel(coarse, [0.0], [0.0]), [], "a choice", {}, None, 0.0)
    rec = sysid.IOData(u=np.zeros(400), y=np.zeros(400), dt=DT)
    out = _at_record_rate(res, rec, None, 10, 0.02, 1.0)
    fine = out.model.statespace
    assert fine.dt == DT and fine.nstates == 2 and "Tustin" in out.checks["sampling"]
    np.testing.assert_allclose(fine.dcgain(), coarse.dcgain(), rtol=1e-10)
    # the slow pole lands near where an exact map puts it (Tustin moves it a little)
    assert np.min(np.abs(fine.poles() - 0.9 ** 0.1)) < 1e-3
