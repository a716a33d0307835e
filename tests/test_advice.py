"""MATLAB's advice(data): each check finds what it should, and stays quiet otherwise."""

import warnings

import numpy as np
import pytest

import sysid

G = sysid.StateSpaceModel([[0.8, 0.2], [-0.2, 0.7]], [[1.0], [0.5]], [[1.0, 0.0]])


def _open_loop(seed=0, n=2000, delay=0):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 1))
    x = G.simulate(u)
    y = np.r_[np.zeros((delay, 1)), x[:n - delay]] if delay else x
    return u, y + 0.1 * rng.standard_normal((n, 1))


def test_a_clean_open_loop_record_needs_nothing():
    u, y = _open_loop()
    a = sysid.advice(sysid.IOData(u, y, 1.0))
    assert a.to_act_on == [] and [f.verdict for f in a.findings] == ["ok"] * 8, a.summary()
    assert [f.topic for f in a.findings] == ["offsets", "trends", "excitation", "feedback",
                                             "periodic", "outliers", "delays", "nonlinearity"]
    df = a.to_pandas()
    assert list(df.columns) == ["topic", "verdict", "finding", "action"] and len(df) == 8
    assert "to act on: none" in repr(a)



@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_input_that_does_not_act_has_no_delay_in_the_advice(seed):
    # G acts through u0 (no dead time beyond its one sample); u1 does not act at all, so
    # the ARX loss over its delays is flat and its least falls anywhere in 0..20: the
    # finding reported that number as u1's dead time (a note to give it to nk), where
    # delayest itself warns that the delay there is not determined
    u, y = _open_loop(seed)
    u = np.c_[u, np.random.default_rng(seed + 10).standard_normal(len(u))]
    a = sysid.advice(sysid.IOData(u, y, 1.0))
    assert "u1 -> y0: not determined" in a["delays"].finding, a["delays"]
    assert "u0 -> y0: 1" in a["delays"].finding and a["delays"].verdict == "ok"

def test_offsets_drift_spikes_and_delay_are_found():
    u, y = _open_loop(1, delay=4)
    t = np.arange(len(y))[:, None]
    a = sysid.advice(sysid.IOData(u + 3.0, y + 500.0, 1.0))
    assert a["offsets"].verdict == "act" and "detrend" in a["offsets"].action
    assert a["delays"].verdict == "note" and ": 5" in a["delays"].finding  # 4 + G's one
    assert a["nonlinearity"].verdict == "ok"  # the offsets are not mistaken for curvature
    b = sysid.advice(sysid.IOData(u, y + 0.05 * t, 1.0))
    assert b["trends"].verdict == "note" and "linear" in b["trends"].action
    spiky = y.copy()
    spiky[[300, 1200]] += 40.0
    assert sysid.advice(sysid.IOData(u, spiky, 1.0))["outliers"].verdict == "act"


def test_feedback_and_poor_excitation_are_to_act_on():
    rng = np.random.default_rng(2)
    n = 3000
    r, e = rng.standard_normal(n), 0.3 * rng.standard_normal(n)
    u, y = np.zeros(n), np.zeros(n)
    x = np.zeros(2)
    for t in range(n):
        y[t] = G.C[0] @ x + e[t]
        u[t] = r[t] - 0.6 * (y[t - 1] if t else 0.0)  # a sampled P controller closes the loop
        x = G.A @ x + G.B[:, 0] * u[t]
    a = sysid.advice(sysid.IOData(u, y, 1.0))
    assert "feedback" in a.to_act_on and "pbsid" in a["feedback"].action
    # the calls it names exist as written (it once named n4sid(..., method='pbsid'))
    d = sysid.IOData(u, y, 1.0)
    assert "sysid.pbsid(data, order)" in a["feedback"].action
    assert "n4sid" not in a["feedback"].action
    assert sysid.pbsid(d, 2).poles(std=True)[1].shape == (2,)
    # the test sees past outputs in the input; it cannot tell a loop from a nonlinear plant
    # (the Bouc-Wen benchmark, open loop, read "the record was taken in closed loop")
    assert "unless the plant is nonlinear" in a["feedback"].finding
    one_sine = np.sin(0.3 * np.arange(1000))[:, None]
    b = sysid.advice(sysid.IOData(one_sine, G.simulate(one_sine), 1.0))
    assert b["excitation"].verdict == "act" and "order 2" in b["excitation"].finding
    c = sysid.advice(sysid.IOData(np.c_[one_sine, np.ones(1000)], G.simulate(one_sine), 1.0))
    assert "never change" in c["excitation"].finding


def test_nonlinearity_and_periodic_excitation_are_noted():
    u, _ = _open_loop(3)
    x = G.simulate(u)
    y = x + 0.4 * x ** 2 + 0.05 * np.random.default_rng(4).standard_normal(x.shape)  # Wiener
    a = sysid.advice(sysid.IOData(u, y, 1.0))
    assert a["nonlinearity"].verdict == "note" and "nlarx" in a["nonlinearity"].action
    um = sysid.multisine(256, band=(0, 0.5), periods=4)
    b = sysid.advice(sysid.IOData(um, G.simulate(um), 1.0))
    assert b["periodic"].verdict == "note" and "256" in b["periodic"].finding
    with pytest.raises(KeyError, match="topics: offsets"):
        b["noise"]


def test_shipped_records():
    # the dryer's dead time (MATLAB's examples fit it with nk = 3; its response at lag 2 is
    # small but significant: sysid.delayest), and the pH process's nonlinearity (a
    # titration curve)
    d = sysid.advice(sysid.datasets.load_dryer())
    assert d["delays"].verdict == "note" and d["delays"].finding.endswith((": 2", ": 3"))
    assert d["nonlinearity"].verdict == "ok" and d.to_act_on == []
    ph = sysid.advice(sysid.datasets.load_ph())
    assert ph["nonlinearity"].verdict == "note"
    # its feedback test fires (p = 0.003) on an open-loop record: with the nonlinearity found
    # too, it is a note that names both causes, not a finding to act on
    assert ph["feedback"].verdict == "note" and "nonlinearity" in ph["feedback"].finding


def test_a_constant_input_is_named_as_such_not_as_zero():
    # the model-based checks see the centred record, where a constant input of 1 read as
    # "input u0 is 0 in every sample" (delays, nonlinearity)
    rng = np.random.default_rng(0)
    y = rng.standard_normal((300, 1))
    a = sysid.advice(sysid.IOData(np.ones((300, 1)), y, 1.0))
    assert a["excitation"].verdict == "act" and "never change" in a["excitation"].finding
    for topic in ("delays", "nonlinearity"):
        assert a[topic].verdict == "note"
        assert "never change" in a[topic].finding and "is 0 in every" not in a[topic].finding


def test_a_record_too_short_for_the_feedback_test_is_still_advised_on():
    """12 samples of 5 inputs and 2 outputs: advice raised check_feedback's "lags = 2 leaves
    no degrees of freedom" (a lag the user never chose) instead of advising; the feedback
    finding now says it was not tested and why, as the delays' finding does."""
    rng = np.random.default_rng(0)
    d = sysid.IOData(u=rng.standard_normal((12, 5)), y=rng.standard_normal((12, 2)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = sysid.advice(d)
    assert a["feedback"].verdict == "note"
    assert a["feedback"].finding.startswith("not tested (lags = 2 leaves no degrees")


def test_poor_excitation_of_several_inputs_names_the_poor_one():
    """A catchment's daily rainfall (a rich input) beside its climatological potential
    evaporation (the same annual curve every year: a few spectral lines) was advised 'the
    input is persistently exciting of order 3 only', as if the rainfall were poor; the
    finding now names the input that limits the order and the order of each."""
    rng = np.random.default_rng(4)
    n = 3000
    rain = rng.exponential(1.0, n) * (rng.random(n) < 0.3)
    evap = 3.0 + 2.0 * np.sin(2 * np.pi * np.arange(n) / 365.0)
    u = np.c_[rain, evap]
    y = sysid.StateSpaceModel([[0.9]], [[0.1, -0.02]], [[1.0]]).simulate(u)
    a = sysid.advice(sysid.IOData(u, y, 86400.0, input_names=["P", "Ep"]))
    f = a["excitation"].finding
    assert a["excitation"].verdict == "act" and "the inputs together" in f
    assert "limited by Ep (alone: order 3" in f and "P alone: order >= 40" in f


def test_a_step_test_is_not_called_richly_exciting():
    # an irrigation canal's gate stepped at sample 1: the input's spectrum in the record is
    # the step's edge, and the spectral count read "persistently exciting of order >= 40
    # (models up to order 20 determined)" while the subspace methods refuse the record
    n = 600
    u = np.r_[0.0, np.full(n - 1, 25.0)][:, None]
    y = G.simulate(u) + 0.01 * np.random.default_rng(0).standard_normal((n, 1))
    f = sysid.advice(sysid.IOData(u, y, 1.0))["excitation"]
    assert f.verdict == "note" and "step test" in f.finding and "sample(s) 1 " in f.finding
    assert "order >= " not in f.finding and "procest" in f.action
    with pytest.raises(sysid.errors.ExcitationError):  # what the finding says of them
        sysid.n4sid(sysid.IOData(u - u.mean(), y - y.mean(), 1.0), 2)


def test_a_pulse_in_mid_record_is_a_step_test_the_subspace_fits_may_still_take():
    # a helicopter's yaw motor pulsed (on at sample 2, off at 951): the finding said "the
    # subspace methods refuse it", but the pulse's second edge lies inside their data matrix
    # and n4sid returned a model; the finding now says when they refuse one
    n = 1500
    u = np.zeros((n, 1))
    u[2:951] = 6.0
    y = G.simulate(u) + 0.01 * np.random.default_rng(1).standard_normal((n, 1))
    f = sysid.advice(sysid.IOData(u, y, 1.0))["excitation"]
    assert f.verdict == "note" and "sample(s) 2, 951 " in f.finding
    assert "refuse it when they all come before" in f.finding
    assert "methods refuse it" not in f.finding
    m = sysid.n4sid(sysid.IOData(u - u.mean(), y - y.mean(), 1.0), 2)  # no refusal
    assert np.asarray(m.A).shape == (2, 2)


def test_one_pulsed_input_beside_a_rich_one_is_named():
    # a helicopter's pitch motor ramped while its yaw motor was pulsed once: the joint
    # spectral count read "input persistently exciting of order >= 40" for both; the pulsed
    # input is now named, with the samples where it changes, and the others' count given
    from conftest import pulsed_record

    f = sysid.advice(pulsed_record(1200, 400, 700, 6.0, 0.01, seed=2))["excitation"]
    assert f.verdict == "note" and "u1 at sample(s) 400, 700" in f.finding
    assert "other input(s) persistently exciting of order >= 40" in f.finding
    assert "u0 at" not in f.finding
