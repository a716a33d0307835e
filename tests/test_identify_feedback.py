"""Under feedback, identify refines from the open-loop subspace fits but does not return one
(issue 26): their estimates are biased there (the future inputs the data matrix projects on
are correlated with the past noise). On a buck converter in closed loop (not shipped) the
choice was ``n4sid`` order 3, validated at 46.6 %; now a refinement, 59.8 %."""

from __future__ import annotations

import types
import warnings

import numpy as np
import pytest

import sysid
from sysid.identify.board import Board

OPEN_LOOP = ("n4sid", "moesp", "cva")


def _closed_loop(n, seed, gain=0.5):
    # a resonant plant under proportional feedback, a coloured output disturbance
    rng = np.random.default_rng(seed)
    r, e = rng.standard_normal(n), 0.3 * rng.standard_normal(n)
    A = np.array([[1.5, -0.7], [1.0, 0.0]])
    B, C = np.array([1.0, 0.0]), np.array([0.5, 0.3])
    u, y, x, v = np.zeros(n), np.zeros(n), np.zeros(2), 0.0
    for t in range(n):
        v = 0.9 * v + e[t]
        y[t] = C @ x + v
        u[t] = r[t] - gain * y[t]
        x = A @ x + B * u[t]
    return sysid.IOData(u=u, y=y)


def test_under_feedback_an_open_loop_subspace_fit_is_a_start_not_the_choice():
    # this record's choice was moesp order 3 before (its BIC the smallest among the
    # candidates the held-out blocks cannot tell apart)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(_closed_loop(600, 7), progress=False)
    assert res.checks["feedback"].startswith("detected")
    assert "are refined from but not chosen" in res.checks["feedback"]
    chosen = next(r for r in res.leaderboard if r["chosen"])
    assert chosen["family"] not in OPEN_LOOP
    plain = [r for r in res.leaderboard
             if r["family"] in OPEN_LOOP and r["criterion"] == "subspace"]
    assert plain and all(r["start_only"] for r in plain)
    assert any("a start, not chosen" in r["note"] for r in plain)  # unless noted otherwise
    # they still start refinements
    assert any(r["criterion"] == f"prediction error from {f}" for r in res.leaderboard
               for f in OPEN_LOOP)


def test_starts_only_keeps_the_families_when_the_rest_is_clearly_worse_or_absent():
    b = Board.__new__(Board)

    def row(family, fit):
        return {"family": family, "criterion": "subspace", "held_out_fit": fit,
                "stable": True, "note": ""}
    b.rows = [row("n4sid", 80.0), row("moesp", 70.0)]
    assert b.starts_only(OPEN_LOOP, "biased") == 0  # no other candidate: left as they were
    assert not any(r.get("start_only") for r in b.rows) and b.best()["family"] == "n4sid"
    b.rows.append(row("ssarx", 60.0))  # the blocks prefer the biased fit by 20 points
    assert b.starts_only(OPEN_LOOP, "biased") == 0 and b.best()["family"] == "n4sid"
    b.rows.append(row("pbsid", 79.8))  # within the blocks' resolution of it
    assert b.starts_only(OPEN_LOOP, "biased") == 2
    assert b.best()["family"] == "pbsid" and b.rows[0]["note"] == "biased"


def _identify_keeping_biased_fits(monkeypatch, kept_biased):
    """identify on a closed-loop record whose board keeps the open-loop fits as candidates,
    with ``kept_biased`` the best held-out fits with and without them."""
    def kept(self, families, note):
        self.kept_biased = kept_biased
        return 0
    monkeypatch.setattr(Board, "starts_only", kept)
    monkeypatch.setattr(sysid, "check_feedback",
                        lambda data, **kw: types.SimpleNamespace(detected=True, p_value=1e-9))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sysid.identify(_closed_loop(600, 7), progress=False)


def test_open_loop_fits_kept_under_feedback_say_why(monkeypatch):
    """Under detected feedback the open-loop subspace fits stay candidates when every other
    candidate scores clearly below them; the summary then said "feedback: detected" above an
    n4sid choice (an aircraft's flight test), with n4sid's own FeedbackWarning advising
    against it, and nothing to say why. The check now gives the best held-out fit with and
    without them."""
    b = Board.__new__(Board)
    b.rows = [{"family": f, "criterion": "subspace", "held_out_fit": fit, "stable": True,
               "note": ""} for f, fit in (("n4sid", 80.0), ("moesp", 70.0))]
    assert b.starts_only(OPEN_LOOP, "biased") == 0 and b.kept_biased == (80.0, None)
    b.rows.append({"family": "ssarx", "criterion": "subspace", "held_out_fit": 60.0,
                   "stable": True, "note": ""})
    assert b.starts_only(OPEN_LOOP, "biased") == 0 and b.kept_biased == (80.0, 60.0)
    # the blocks prefer the biased fits clearly
    res = _identify_keeping_biased_fits(monkeypatch, (72.3, 64.7))
    assert ("stay candidates: without them the best held-out fit falls from 72.3 % to "
            "64.7 %") in res.checks["feedback"]


def test_open_loop_fits_kept_when_the_others_are_unstable_do_not_say_none_scored(monkeypatch):
    """On a car's acceleration log under feedback every closed-loop fit (pbsid, ssarx) scored,
    some above the kept n4sid fit, but each was unstable on a held-out block; the summary said
    "stay candidates: no other candidate scored", which was false. It now says that without
    them no stable candidate is left."""
    b = Board.__new__(Board)
    b.rows = [{"family": f, "criterion": "subspace", "held_out_fit": fit, "stable": st,
               "note": ""} for f, fit, st in (("n4sid", 53.7, True), ("pbsid", 57.4, False))]
    assert b.starts_only(OPEN_LOOP, "biased") == 0 and b.kept_biased == (53.7, None)
    res = _identify_keeping_biased_fits(monkeypatch, (53.7, None))
    check = res.checks["feedback"]
    assert "no other candidate scored" not in check
    assert "stay candidates: without them no stable candidate is left" in check


def test_a_p_value_that_underflowed_is_not_printed_as_zero():
    # a battery tester's record: "feedback: detected (p = 0)" in identify's checks, and the
    # command line's "residual whiteness (Ljung-Box p): Voltage(V): 0"; no test gives p = 0,
    # the tail probability underflowed
    rng = np.random.default_rng(0)
    n = 20000
    y, u, x = np.zeros(n), np.zeros(n), 0.0
    for t in range(n):  # a controller acting on the last output sample, a noisy output
        y[t] = x + rng.standard_normal()
        u[t] = -0.8 * y[t - 1] + 0.1 * rng.standard_normal()
        x = 0.9 * x + 0.5 * u[t]
    data = sysid.IOData(u, y, 1.0)
    fb = sysid.check_feedback(data)
    assert fb.p_value == 0.0  # the premise: an underflow
    assert "p < 1e-300" in repr(fb) and "p = 0 " not in repr(fb)
    with pytest.warns(sysid.FeedbackWarning) as got:
        sysid.n4sid(data, 1)
    assert any("p < 1e-300" in str(w.message) for w in got)
    assert not any("p = 0)" in str(w.message) or "p = 0:" in str(w.message) for w in got)
    assert "p < 1e-300" in sysid.advice(data)["feedback"].finding
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(data, progress=False)
    assert res.checks["feedback"].startswith("detected (p < 1e-300;")
