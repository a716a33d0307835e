"""The feedback test on a periodic input runs on what changes from period to period.

A piezo steering mirror's open-loop multisine (the thirteenth sweep, two periods of 8192
samples, the measured voltages repeating to 0.02 %) was declared fed back at p < 1e-300:
the nonlinear distortions of its outputs, periodic and functions of the input's past, stayed
in a linear ARX model's innovations and "predicted" the deterministic input. On the
period-to-period changes they cancel; a loop's fed-back output noise does not.
"""

from __future__ import annotations

import numpy as np

import sysid

PERIOD, PERIODS = 1024, 4


def _plant(u: np.ndarray, e: np.ndarray) -> np.ndarray:
    """A second-order resonance followed by a cubic (a Wiener system), noise ``e``."""
    x = np.zeros(2)
    y = np.empty(len(u))
    for t in range(len(u)):
        v = x[0]
        y[t] = v + 0.05 * v ** 3 + e[t]
        x = np.array([1.6 * x[0] - 0.8 * x[1] + 0.3 * u[t], x[0]])
    return y


def _open_loop(seed: int) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    r = sysid.multisine(PERIOD, band=(0.0, 0.4), periods=PERIODS, seed=seed).ravel()
    u = r + 0.01 * rng.standard_normal(len(r))  # a measured input: its own small noise
    return sysid.IOData(u=u, y=_plant(u, 0.05 * rng.standard_normal(len(r))))


def _closed_loop(seed: int) -> sysid.IOData:
    rng = np.random.default_rng(seed)
    r = sysid.multisine(PERIOD, band=(0.0, 0.4), periods=PERIODS, seed=seed).ravel()
    e = 0.05 * rng.standard_normal(len(r))
    u, y, x = np.empty(len(r)), np.empty(len(r)), np.zeros(2)
    for t in range(len(r)):  # u(t) = r(t) - 0.1 y(t - 1): the output's noise fed back
        y[t] = x[0] + 0.05 * x[0] ** 3 + e[t]
        u[t] = r[t] - 0.1 * (y[t - 1] if t else 0.0)
        x = np.array([1.6 * x[0] - 0.8 * x[1] + 0.3 * u[t], x[0]])
    return sysid.IOData(u=u, y=y)


def test_an_open_loop_nonlinear_plant_under_a_periodic_input_is_not_called_fed_back():
    """At the 0.01 level over 40 records: at most 3 false detections (binomial, 40 draws at
    p = 0.01: P(4 or more) = 0.0075). Before the change every record was detected."""
    tests = [sysid.check_feedback(_open_loop(s)) for s in range(40)]
    assert all(t.periodic == (PERIOD, PERIODS) for t in tests)
    assert sum(t.detected for t in tests) <= 3
    assert "periodic input (1024 samples, 4 periods)" in tests[0].summary()


def test_a_loop_around_a_periodic_reference_is_still_detected():
    """The loop feeds the output's noise into the input's period-to-period changes: every one
    of 10 records is detected, with the share of the whole input's variance it explains."""
    tests = [sysid.check_feedback(_closed_loop(s)) for s in range(10)]
    assert all(t.periodic == (PERIOD, PERIODS) and t.detected for t in tests)
    assert all(0 < t.explained_share < 0.05 for t in tests)


def test_a_random_input_is_tested_on_the_whole_record():
    rng = np.random.default_rng(1)
    u = rng.standard_normal(PERIOD * PERIODS)
    t = sysid.check_feedback(sysid.IOData(u=u, y=_plant(u, 0.05 * rng.standard_normal(len(u)))))
    assert t.periodic is None and "periodic input" not in t.summary()
