"""A direct term chosen on closed-loop data is named as possibly the controller's (found by
the sixth sweep of fresh records: a heated air duct with a 0.12-0.2 s dead time under PI
control, where identify chose D = -0.23 and -0.59 on two parts of the record)."""

from __future__ import annotations

import warnings

import numpy as np

import sysid


def _loop(seed: int, gain: float = 1.5, n: int = 3000):
    """A plant with a three-sample dead time (no direct term) under a proportional controller
    that acts within the sample: ``u(t) = r(t) - gain * y(t)``; a coloured disturbance."""
    rng = np.random.default_rng(seed)
    r = np.repeat(rng.standard_normal(n // 50), 50)
    e = 0.3 * rng.standard_normal(n)
    v, y, u = np.zeros(n), np.zeros(n), np.zeros(n)
    for t in range(n):
        v[t] = (0.8 * v[t - 1] if t else 0.0) + e[t]
        y[t] = (0.9 * y[t - 1] + 0.3 * u[t - 3] if t >= 3 else 0.0) + v[t]
        u[t] = r[t] - gain * y[t]
    return sysid.IOData(u=u, y=y, dt=1.0)


def test_a_direct_term_on_closed_loop_data_is_named_as_possibly_the_controllers():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(_loop(0))
    d = np.asarray(res.model.statespace.D)
    assert res.checks["feedback"].startswith("detected")
    # the trap the note is for: the plant has no direct term, the chosen model's is the
    # controller's inverse gain (-1 / 1.5)
    assert res.model.statespace.info["identify"]["feedthrough"] and abs(d[0, 0] + 1 / 1.5) < 0.2
    note = res.checks["loop_feedthrough"]
    assert "may be the controller's" in note and "feedthrough=False" in note
    # refit as the note says: no direct term, and the plant's dead time comes back (its
    # impulse response near zero until the third sample, 0.3 there)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = sysid.ssest(_loop(0), 5, feedthrough=False)
    h = np.asarray(sysid.impulse(m, 8).y).ravel()
    assert np.all(np.abs(h[:3]) < 0.1) and 0.15 < h[3] < 0.45, h


def test_open_loop_data_with_a_direct_term_get_no_such_note():
    rng = np.random.default_rng(1)
    u = rng.standard_normal(2000)
    true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[0.5]], [[0.7]], dt=1.0)
    y = true.simulate(u)[:, 0] + 0.05 * rng.standard_normal(2000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(sysid.IOData(u=u, y=y, dt=1.0))
    assert res.model.statespace.info["identify"]["feedthrough"]
    assert "loop_feedthrough" not in res.checks


def test_a_model_without_noise_model_chosen_under_feedback_is_named_as_biased_too():
    """identify's feedback line calls the open-loop subspace fits biased and sets them
    aside; a chosen refinement with simulation focus (no noise model) is biased by the loop
    the same way, and the note says so (with the consistent fits to compare): on the
    shipped winding record (feedback detected) identify chooses such a model. A
    prediction-focus choice, or an open-loop record, gets no such note."""
    from sysid.identify.notes import loop_bias_check

    d = sysid.datasets.load_winding()
    n = d.experiments[0][1].shape[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sysid.identify(d[: 2 * n // 3])
    chosen = res.model.statespace.info["identify"]
    assert res.checks["feedback"].startswith("detected") and chosen["focus"] == "simulation"
    note = res.checks["loop_bias"]
    assert "no noise model" in note and "sysid.pbsid" in note and note in res.summary()
    for focus, family, fb in (("prediction", "pem", True), ("simulation", "pem", False),
                              (None, "pbsid", True)):
        checks: dict = {}
        loop_bias_check(focus, family, fb, checks)
        assert "loop_bias" not in checks
