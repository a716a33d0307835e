"""Known input delays of state-space estimators (MATLAB's ``InputDelay``): a delayed system
recovered to machine precision from noise-free data by the subspace methods and ``ssest``,
``"auto"`` finding the delays, the absorbed model's impulse response zero for the delay,
its uncertainty that of the delay-free fit (the unit delays exact, no Monte Carlo warning),
a save/load round trip, and clear errors."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.errors import DataError
from sysid.models.input_delay import absorb_delay, shift_inputs

TRUE = sysid.StateSpaceModel([[0.8, 0.1], [0.0, 0.6]], [[1.0, 0.0], [0.3, 1.0]],
                             [[1.0, 0.0], [0.0, 1.0]], [[0.0, 0.5], [0.0, 0.0]])
DELAYS = [3, 1]
W = np.array([0.05, 0.7, 2.0])


def _record(noise: float = 0.0, n: int = 1200, seed: int = 0) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 2))
    y = absorb_delay(TRUE, DELAYS).simulate(u)
    return sysid.IOData(u=u, y=y + noise * rng.standard_normal(y.shape))


def test_absorbed_model_is_the_delayed_system():
    d = absorb_delay(TRUE, DELAYS)
    assert d.nstates == 2 + 4
    h = d.impulse(8).y  # (samples, outputs, inputs)
    h0 = TRUE.impulse(8).y
    assert np.allclose(h[3:, :, 0], h0[:5, :, 0]) and np.all(h[:3, :, 0] == 0)
    assert np.allclose(h[1:, :, 1], h0[:7, :, 1]) and np.all(h[:1, :, 1] == 0)
    z = np.exp(1j * W)
    assert np.allclose(d.freqresp(W), TRUE.freqresp(W) * z[:, None, None] ** -np.array(DELAYS))


@pytest.mark.parametrize("fit", [sysid.n4sid, sysid.moesp, sysid.cva])
def test_subspace_recovers_a_delayed_system_exactly(fit):
    m = fit(_record(), 2, feedthrough=True, input_delay=DELAYS)
    assert m.info["input_delay"] == DELAYS and m.info["delay_free"].nstates == 2
    assert np.allclose(m.freqresp(W), absorb_delay(TRUE, DELAYS).freqresp(W), atol=1e-10)


def test_ssest_with_auto_delay_on_noisy_data():
    data = _record(noise=0.05, seed=1)
    m = sysid.ssest(data, 2, feedthrough=True, focus="simulation", input_delay="auto")
    # delayest's 4 and 1 (samples to the first response): with D estimated, the first input's
    # delay is 4 and its D the true model's C B (the same system); the second's direct term 1
    assert m.info["input_delay"] == [4, 1]
    p, sd = m.poles(std=True)  # the unit delays: exact (std 0), no Monte Carlo warning
    inner_p, inner_sd = m.info["delay_free"].poles(std=True)
    slow = np.abs(p) > 0.1
    assert np.allclose(np.sort(p[slow].real), np.sort(inner_p.real))
    assert np.allclose(np.sort(np.abs(sd[slow])), np.sort(np.abs(inner_sd)), rtol=1e-6)
    assert np.all(sd[~slow] == 0)
    assert np.allclose(np.sort(inner_p.real), [0.6, 0.8], atol=0.01)
    # without the delay the same order cannot fit the record
    plain = sysid.ssest(data, 2, feedthrough=True, focus="simulation")
    assert sysid.compare(data, m).mean_fit > sysid.compare(data, plain).mean_fit + 10


def test_shift_and_round_trip(tmp_path):
    data = _record(n=300)
    s = shift_inputs(data, np.array(DELAYS))
    assert s.n_samples == 297
    assert np.array_equal(s.u[:, 0], data.u[0:297, 0]) and np.array_equal(s.y, data.y[3:])
    assert np.array_equal(s.u[:, 1], data.u[2:299, 1])
    m = sysid.n4sid(data, 2, input_delay=DELAYS, feedthrough=True)
    m.save(tmp_path / "m.json")
    back = sysid.load_model(tmp_path / "m.json")
    assert np.allclose(back.simulate(data.u), m.simulate(data.u))
    assert back.info["input_delay"] == DELAYS


def test_bad_delays_are_refused():
    data = _record(n=200)
    with pytest.raises(DataError, match="one per input"):
        sysid.n4sid(data, 2, input_delay=[1, 2, 3])
    with pytest.raises(DataError, match="input_delay"):
        sysid.n4sid(data, 2, input_delay=-1)
    with pytest.raises(DataError, match="samples, not seconds"):
        sysid.ssest(data, 2, input_delay=150)
    with pytest.raises(DataError, match="'auto'"):
        sysid.ssest(data, 2, input_delay="guess")
    with pytest.raises(DataError, match="start model"):
        sysid.ssest(data, TRUE, input_delay=1)


def test_nkshift_delays_and_advances():
    u = np.column_stack([np.arange(6.0), 10 + np.arange(6.0)])
    d = sysid.nkshift(sysid.IOData(u=u, y=np.arange(6.0)), [1, -1])
    assert d.y.ravel().tolist() == [1.0, 2.0, 3.0, 4.0]
    assert d.u.tolist() == [[0.0, 12.0], [1.0, 13.0], [2.0, 14.0], [3.0, 15.0]]
    two = sysid.nkshift(sysid.IOData(u=[u, u], y=[np.arange(6.0), np.arange(6.0)]), 2)
    assert two.lengths == [4, 4]
    with pytest.raises(DataError, match="whole samples"):
        sysid.nkshift(sysid.IOData(u=u, y=np.arange(6.0)), 1.5)
    with pytest.raises(DataError, match="too little"):
        sysid.nkshift(sysid.IOData(u=u, y=np.arange(6.0)), [5, -1])


def test_auto_delay_leaves_out_outputs_the_input_does_not_act_on():
    # input_delay="auto" took each input's smallest delayest delay over all outputs, an
    # output the input does not reach included: its delay is anywhere in the range (here 4
    # for pure noise, against 6 on the output the input drives), and the fit got 3
    # samples of delay states instead of 5
    from sysid.models.input_delay import input_delays

    rng = np.random.default_rng(5)
    u = rng.standard_normal((2000, 1))
    y0 = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(
        np.vstack([np.zeros((5, 1)), u[:-5]]))
    r = np.random.default_rng(2)
    d = sysid.IOData(u, np.hstack([y0 + 0.05 * r.standard_normal((2000, 1)),
                                   r.standard_normal((2000, 1))]))
    with pytest.warns(sysid.DelayWarning, match="u0 -> y1"):
        assert sysid.delayest(d).ravel().tolist() == [6, 4]
    assert input_delays(d, "auto").tolist() == [5]
    # an input that reaches no output gets no delay, and says so
    blind = sysid.IOData(u, r.standard_normal((2000, 2)))
    with pytest.warns(sysid.DelayWarning, match="no delay is given to it"):
        assert input_delays(blind, "auto").tolist() == [0]


def test_a_known_delay_adds_no_parameters(tmp_path):
    # the delay line's states were counted as parameters (n4sid(d, 1, input_delay=5): 18
    # instead of 3) and criteria charged their initial values too (24); MATLAB counts neither
    d = absorb_delay(TRUE, DELAYS)  # the delayed input's feed-through moved into C
    assert TRUE.n_parameters == 12 and d.n_parameters == 12
    sysid.save_model(d, tmp_path / "d.json")
    assert sysid.load_model(tmp_path / "d.json").n_parameters == 12
    rng = np.random.default_rng(1)
    u = rng.standard_normal((300, 1))
    m0 = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], K=[[0.3]])
    y = absorb_delay(m0, [5]).simulate(u) + 0.1 * rng.standard_normal((300, 1))
    rec = sysid.IOData(u=u, y=y)
    est = sysid.n4sid(rec, 1, input_delay=5)
    assert est.nstates == 6 and est.n_parameters == 3
    assert sysid.criteria(est, rec).n_params == 3 + 1  # one fitted initial state, not six
    assert sysid.criteria(est, rec, x0="zero").n_params == 3
    # a polynomial model's nk beyond one sample: no initial states for its delay line
    p6 = sysid.PolynomialModel([[[-0.8]]], [[[1.0]]], [[6]], 1.0)
    p1 = sysid.PolynomialModel([[[-0.8]]], [[[1.0]]], [[1]], 1.0)
    assert sysid.criteria(p6, rec).n_params == sysid.criteria(p1, rec).n_params == 2 + 1


@pytest.mark.parametrize("dt", [1.0, None])
def test_a_transfer_functions_iodelay_adds_no_parameters(dt):
    # criteria, aic(model, data) and fpe(model, data) counted the iodelay's delay line as
    # fitted initial states (tfest with iodelay=3: 9 instead of 6 discrete, 10 instead of 7
    # continuous); a known delay is no parameter, MATLAB counts neither it nor its states
    rng = np.random.default_rng(0)
    u = rng.standard_normal(600)
    g = sysid.TransferFunction([0.5, 0.2], [1.0, -1.2, 0.5], dt=1.0)
    kw = {} if dt is None else {"dt": dt}
    counts = []
    for delay in (0, 3):
        y = g.simulate(np.r_[np.zeros(delay), u][:600]) + 0.05 * rng.standard_normal((600, 1))
        rec = sysid.IOData(u, y, 1.0)
        m = sysid.tfest(rec, 2, 1, iodelay=delay, **kw)
        c = sysid.criteria(m, rec)
        assert sysid.aic(m, rec) == pytest.approx(c.log_loss + 2 * c.n_params / 600)
        counts.append((m.n_parameters, c.n_params, sysid.criteria(m, rec, x0="zero").n_params))
    assert counts[0] == counts[1]
    assert counts[0][0] == counts[0][2] == 4


def test_a_process_models_delay_line_is_no_initial_state():
    # Td is estimated (a parameter) but the states of its delay line start from the
    # unrecorded past input: the count is that of the same model without its delay
    rng = np.random.default_rng(0)
    u = np.repeat(rng.standard_normal(100), 6)
    rec = sysid.IOData(u, rng.standard_normal((600, 1)), 1.0)
    counts = [sysid.criteria(sysid.ProcessModel("P1D", Kp=2.0, Tp1=4.0, Td=td), rec).n_params
              for td in (0.0, 2.5, 3.0)]
    assert counts[0] == counts[1] == counts[2]


def test_identify_bic_does_not_charge_a_known_delay():
    from sysid.identify.board import bic

    rng = np.random.default_rng(2)
    u = rng.standard_normal((400, 1))
    m = absorb_delay(sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]), [4])
    rec = sysid.IOData(u=u, y=m.simulate(u) + 0.1 * rng.standard_normal((400, 1)))
    bare = sysid.StateSpaceModel(m.A, m.B, m.C, m.D)  # the same matrices, no delay recorded
    # four states of (1 + 1) entries and a fitted start each, charged only without the record
    assert bic(bare, rec) - bic(m, rec) == pytest.approx(4 * 3 * np.log(400))
