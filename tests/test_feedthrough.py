"""One feedthrough default for every state-space estimator (no D, MATLAB's) and one
``feedthrough="auto"`` rule (issue 26 item 2)."""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid.subspace.feedthrough import choose_feedthrough

from conftest import feedthrough_record, quiet

# -- the default: D = 0 everywhere ---------------------------------------------------------
DEFAULTS = {
    "n4sid": lambda d: sysid.n4sid(d, 2),
    "moesp": lambda d: sysid.moesp(d, 2),
    "cva": lambda d: sysid.cva(d, 2),
    "SubspaceEstimator.fit": lambda d: sysid.SubspaceEstimator(d).fit(2, method="n4sid"),
    "pbsid": lambda d: sysid.pbsid(d, 2),
    "ssarx": lambda d: sysid.ssarx(d, 2),
    "frd_subspace (IOData)": lambda d: sysid.frd_subspace(d, 2),
    "frd_subspace (dft)": lambda d: sysid.frd_subspace(d, 2, method="dft"),
    "orthogonal_decomposition": lambda d: sysid.orthogonal_decomposition(d, 2, 1).deterministic,
    "okid + era": lambda d: sysid.okid(d, 10, 40).era(2).model,
    "ssest": lambda d: sysid.ssest(d, 2),
    "pem": lambda d: sysid.pem(d, sysid.n4sid(d, 2)),
    "select_order": lambda d: sysid.select_order(d, [2]).model(2),
}


@pytest.mark.parametrize("name", sorted(DEFAULTS))
def test_every_state_space_estimator_defaults_to_no_feedthrough(name):
    m = quiet(DEFAULTS[name], feedthrough_record(0.8))
    assert np.all(np.asarray(m.D) == 0.0), (name, m.D)


def test_recursive_subspace_and_impulse_response_default_to_no_feedthrough():
    data = feedthrough_record(0.8)
    rs = sysid.RecursiveSubspace(order=2, horizon=5)
    u, y = data.experiments[0]
    m = quiet(rs.update, u, y)
    assert np.all(m.D == 0)
    h = quiet(sysid.impulse_response, data, 20)
    assert np.all(h.markov[0] == 0)


def test_the_cli_subspace_path_defaults_to_no_feedthrough():
    from sysid.cli import identify

    data = feedthrough_record(0.8)
    u, y = data.experiments[0]
    est, val = (sysid.IOData(u=u[:500], y=y[:500]), sysid.IOData(u=u[500:], y=y[500:]))
    out = quiet(identify, est, val, order=2)
    assert np.all(out["model"].D == 0)
    out = quiet(identify, est, val, order=2, feedthrough=True)
    assert abs(out["model"].D[0, 0] - 0.8) < 0.05


@pytest.mark.parametrize("name", ["n4sid", "moesp", "cva", "ssest", "okid + era",
                                  "frd_subspace (dft)"])
def test_feedthrough_true_estimates_d(name):
    calls = {
        "n4sid": lambda d: sysid.n4sid(d, 2, feedthrough=True),
        "moesp": lambda d: sysid.moesp(d, 2, feedthrough=True),
        "cva": lambda d: sysid.cva(d, 2, feedthrough=True),
        "ssest": lambda d: sysid.ssest(d, 2, feedthrough=True),
        "okid + era": lambda d: sysid.okid(d, 10, 40, feedthrough=True).era(2).model,
        "frd_subspace (dft)": lambda d: sysid.frd_subspace(d, 2, method="dft",
                                                          feedthrough=True),
    }
    m = quiet(calls[name], feedthrough_record(0.8))
    assert abs(m.D[0, 0] - 0.8) < 0.05, (name, m.D)


def test_pem_says_when_it_drops_the_start_d():
    data = feedthrough_record(0.8)
    start = quiet(sysid.n4sid, data, 2, feedthrough=True)
    with pytest.warns(UserWarning, match="non-zero D but feedthrough=False"):
        m = sysid.pem(data, start, feedthrough=False)
    assert np.all(m.D == 0) and m.info["pem"]["start_d_dropped"]
    kept = quiet(sysid.pem, data, start, feedthrough=True)
    assert abs(kept.D[0, 0] - 0.8) < 0.05 and not kept.info["pem"]["start_d_dropped"]
    # by default pem refines the structure it is given: the start's D (it dropped it, with a
    # warning that called D = 0 "the default of every sysid estimator"; on a heat exchanger
    # record the validation fit fell from 57.5 to 16.0 %)
    same = quiet(sysid.pem, data, start)
    assert abs(same.D[0, 0] - 0.8) < 0.05 and not same.info["pem"]["start_d_dropped"]
    assert sysid.pem_loss(data, start) < sysid.pem_loss(data, start, feedthrough=False)


def test_frd_subspace_continuous_default_has_no_continuous_feedthrough():
    ct = sysid.ContinuousStateSpace([[0.0, 1.0], [-4.0, -0.4]], [[0.0], [1.0]], [[1.0, 0.0]])
    w = np.logspace(-1, 1.5, 60)
    fit = sysid.frd_subspace(sysid.FRD(w, ct.freqresp(w)), 2, continuous=True)
    assert abs(fit.D[0, 0]) < 1e-9
    assert np.allclose(fit.freqresp(w), ct.freqresp(w), atol=1e-8)
    # a continuous plant with a direct term needs feedthrough=True
    ctd = sysid.ContinuousStateSpace(ct.A, ct.B, ct.C, [[0.3]])
    fit = sysid.frd_subspace(sysid.FRD(w, ctd.freqresp(w)), 2, continuous=True,
                             feedthrough=True)
    assert abs(fit.D[0, 0] - 0.3) < 1e-8
    # "auto" decides on held-out lines (it was refused for an FRD): D for the plant with one,
    # none for the one without; the default without D says when the response shows one
    for g, has in ((ct, False), (ctd, True)):
        fit = sysid.frd_subspace(sysid.FRD(w, g.freqresp(w)), 2, continuous=True,
                                 feedthrough="auto")
        assert fit.info["feedthrough_selection"]["feedthrough"] is has
        assert abs(fit.D[0, 0] - (0.3 if has else 0.0)) < 1e-8
    with pytest.warns(sysid.FeedthroughWarning, match="the response shows one"):
        sysid.frd_subspace(sysid.FRD(w, ctd.freqresp(w)), 2, continuous=True)
    with pytest.raises(sysid.DataError, match="the FRD's own time base"):
        sysid.frd_subspace(sysid.FRD(w, ct.freqresp(w), dt=0.01), 2, continuous=True,
                           feedthrough="auto")


# -- feedthrough="auto": one rule ----------------------------------------------------------
AUTO = {
    "n4sid": lambda d: sysid.n4sid(d, 2, feedthrough="auto"),
    "ssest": lambda d: sysid.ssest(d, 2, feedthrough="auto"),
    "pem": lambda d: sysid.pem(d, sysid.n4sid(d, 2), feedthrough="auto"),
    "frd_subspace": lambda d: sysid.frd_subspace(d, 2, method="dft", feedthrough="auto"),
    "orthogonal_decomposition": lambda d: sysid.orthogonal_decomposition(
        d, 2, 1, feedthrough="auto").deterministic,
}


@pytest.mark.parametrize("name", sorted(AUTO))
@pytest.mark.parametrize("d", [0.0, 0.8])
def test_feedthrough_auto_decides_from_the_data_with_one_rule(name, d):
    data = feedthrough_record(d, seed=3)
    m = quiet(AUTO[name], data)
    want, why = choose_feedthrough(sysid.SubspaceEstimator(data), 2)
    assert want is (d != 0), why
    assert abs(m.D[0, 0] - d) < 0.05, (name, m.D)
    sel = m.info.get("feedthrough_selection")
    if name != "orthogonal_decomposition":  # its info is the submodel's
        # the same rule (each estimator's own subspace weighting in the held-out fits)
        assert sel["feedthrough"] is want and sel["criterion"] == why["criterion"], sel


def test_feedthrough_auto_under_feedback_keeps_d_zero_and_says_why():
    m = quiet(sysid.pbsid, feedthrough_record(0.8), 2, feedthrough="auto")
    assert np.all(m.D == 0)
    assert "closed-loop" in m.info["feedthrough_selection"]["reason"]


def test_feedthrough_auto_in_okid_and_select_order():
    data = feedthrough_record(0.8, seed=4)
    h = quiet(sysid.impulse_response, data, 20, feedthrough="auto")
    assert abs(h.markov[0][0, 0] - 0.8) < 0.05
    sel = quiet(sysid.select_order, data, [2], feedthrough="auto")
    assert abs(sel.model(2).D[0, 0] - 0.8) < 0.05


@pytest.mark.parametrize("bad", ["yes", 1, "none"])
def test_feedthrough_rejects_anything_but_true_false_auto(bad):
    data = feedthrough_record(0.0)
    for call in (lambda: sysid.n4sid(data, 2, feedthrough=bad),
                 lambda: sysid.ssest(data, 2, feedthrough=bad),
                 lambda: sysid.pem(data, quiet(sysid.n4sid, data, 2), feedthrough=bad)):
        with pytest.raises(sysid.DataError, match="feedthrough must be"):
            quiet(call)
