"""sysid.identify on records of several experiments of uneven length (issue 26): the horizon,
the orders and the held-out blocks follow the data available, not the shortest experiment."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.identify.core import _horizon
from sysid.subspace.estimator import default_horizon
from sysid.validation.crossval import MIN_BLOCK, fold_count, folds, record_folds


def _plant() -> sysid.StateSpaceModel:
    """Two lightly damped resonances: a 4th-order plant."""
    def pair(r: float, th: float) -> np.ndarray:
        return r * np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]])
    A = np.zeros((4, 4))
    A[:2, :2], A[2:, 2:] = pair(0.95, 0.3), pair(0.8, 1.2)
    return sysid.StateSpaceModel(A, [[1.0], [0.0], [1.0], [0.0]], [[1.0, 0.5, 0.8, 0.0]])


def _record(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = _plant().simulate(u)[:, 0]
    return u, y + 0.1 * y.std() * rng.standard_normal(n)


def _identify(data: sysid.IOData, val: sysid.IOData) -> sysid.IdentifyResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sysid.identify(data, val, refine=False)


def test_a_short_second_experiment_does_not_cap_the_order():
    (u1, y1), (u2, y2), (uv, yv) = _record(500, 1), _record(30, 2), _record(1000, 3)
    val = sysid.IOData(u=uv, y=yv)
    alone = _identify(sysid.IOData(u=u1, y=y1), val)
    both = _identify(sysid.IOData(u=[u1, u2], y=[y1, y2]), val)
    orders = {r["order"] for r in both.leaderboard}
    assert max(orders) >= 8  # was order 1 only (the 30 samples set the horizon)
    assert both.model.nstates >= 4
    # the extra experiment adds data: the model validates as well as from the long one alone
    assert both.validation_fit > alone.validation_fit - 3.0
    assert both.validation_fit > 80.0


def test_an_experiment_shorter_than_the_window_is_left_out_of_the_subspace_fits_and_said():
    (u1, y1), (u2, y2), (uv, yv) = _record(600, 4), _record(15, 5), _record(800, 6)
    res = _identify(sysid.IOData(u=[u1, u2], y=[y1, y2]), sysid.IOData(u=uv, y=yv))
    assert "experiment(s) 1 (15 samples)" in res.checks["experiments"]
    assert max(r["order"] for r in res.leaderboard) >= 8
    assert res.validation_fit > 80.0


def test_record_folds_hold_out_every_experiment_in_blocks_of_the_whole_record():
    d = sysid.IOData(u=[np.zeros(500), np.zeros(30), np.zeros(5)],
                     y=[np.ones(500), np.ones(30), np.ones(5)])
    parts = record_folds(d)
    assert len(parts) == 5
    held = [n for _, h in parts for n in h.lengths]
    assert sum(held) == 530  # every holdable sample held out once; the 5 samples never
    assert min(held) >= MIN_BLOCK
    for fit, h in parts:
        assert sum(fit.lengths) + sum(h.lengths) >= 530  # nothing else is lost
        assert min(fit.lengths) >= 5
    # several experiments of one length: as many blocks as one record of that length
    even = sysid.IOData(u=[np.zeros(200)] * 5, y=[np.ones(200)] * 5)
    assert [h.lengths for _, h in record_folds(even)] == [[200]] * 5


def test_one_experiment_keeps_its_folds_and_horizon():
    for n in (60, 200, 333, 1000, 5000):
        d = sysid.IOData(u=np.arange(float(n)), y=np.ones(n))
        a, b = record_folds(d), folds(d, fold_count(d))
        assert [(f.lengths, h.lengths) for f, h in a] == [(f.lengths, h.lengths) for f, h in b]
        for m, l in ((1, 1), (2, 3)):
            dd = sysid.IOData(u=np.zeros((n, m)), y=np.ones((n, l)))
            # the default, but on a short record up to 4 while the data matrix keeps
            # three columns a row (identify's short-record horizon)
            h = default_horizon(n, m, l)
            assert _horizon(dd) == (h if h >= 4 else max(h, min(4, (n + 1) // (6 * (m + l) + 2))))


def test_order_auto_of_the_subspace_estimators_with_a_short_second_experiment():
    (u1, y1), (u2, y2), (uv, yv) = _record(500, 1), _record(30, 2), _record(1000, 3)
    both = sysid.IOData(u=[u1, u2], y=[y1, y2])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.n4sid(both)  # was order 1 (horizon 2 from the 30 samples), 17 %
        fit = sysid.compare(m, sysid.IOData(u=uv, y=yv)).mean_fit
    assert m.nstates >= 4 and fit > 80.0


def test_bic_counts_an_initial_state_per_experiment():
    """identify's BIC fits each experiment's initial state but counted one: on the dryer
    with its gaps cut out (five experiments, 100-300 samples), a model of order 10 was
    chosen where the blocks could not tell it from order 3 (50 fitted initial values
    counted as 10); it simulated the clean record at 86.2 % against order 3's 88.7 %."""
    from sysid.identify.board import bic
    from sysid.models.statespace import ss_parameter_count
    from sysid.validation.crossval import simulation_errors

    u, y = _record(600, 3)
    m = _plant()
    for cut in ([600], [150, 300, 450, 600]):
        edges = [0] + cut
        d = sysid.IOData([u[a:b] for a, b in zip(edges, edges[1:])],
                         [y[a:b] for a, b in zip(edges, edges[1:])], 1.0)
        E = np.vstack([e for _, e in simulation_errors(m, d, prior=False)])
        fit_part = 600 * np.linalg.slogdet(E.T @ E / 600)[1]
        p = ss_parameter_count(4, 1, 1, feedthrough=False, noise_model=False, x0=True,
                               n_experiments=len(cut))
        assert p == 4 * 2 + 4 * len(cut)
        assert bic(m, d) - fit_part == pytest.approx(p * np.log(600), rel=1e-9)


def test_a_record_cut_at_its_gaps_keeps_a_low_order():
    path = sysid.datasets.path("dryer")
    a = np.loadtxt(path)
    y = a[:, 1].copy()
    y[[100, 101, 700]] = np.nan
    y[300:340] = np.nan
    u = a[:, 0].copy()
    u[550] = np.nan
    d = sysid.IOData.from_raw(u, y, 0.08, nan="split")
    assert d.n_experiments == 5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = sysid.identify(d, progress=False)
    assert r.model.nstates <= 5, r.summary()[:300]
    clean = sysid.IOData(a[:, :1], a[:, 1:], 0.08)
    assert sysid.compare(clean, r.model).fit[0, 0] > 88.0
