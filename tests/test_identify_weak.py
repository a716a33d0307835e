"""``identify`` notes a chosen model that explains less than half of what the outputs do on
its held-out blocks (``checks["weak"]``). Before: on an unshipped soft-robot record (the pose
of a pneumatic arm against its valve command, input and outputs correlated at 0.01) it chose
a model at a held-out fit of 15 % (a validation fit of -121 %) and its summary said nothing
of it: the best of poor models passed as a model."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.identify.notes import WEAK_FIT, weak_check


def quiet_identify(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sysid.identify(data, progress=False)


def _disturbed(ratio: float, n: int = 1500, seed: int = 0) -> sysid.IOData:
    # a second-order plant under a slow disturbance `ratio` times its response's size
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 1))
    plant = sysid.StateSpaceModel([[1.5, -0.7], [1.0, 0.0]], [[1.0], [0.0]], [[0.3, 0.2]])
    y = plant.simulate(u)
    v = np.zeros_like(y)
    e = rng.standard_normal(y.shape)
    for t in range(1, n):
        v[t] = 0.98 * v[t - 1] + e[t]
    return sysid.IOData(u=u, y=y + ratio * np.std(y) / np.std(v) * v)


def test_a_record_mostly_disturbance_is_noted_as_weak():
    res = quiet_identify(_disturbed(2.0))
    fit = res.model.info["identify"]["held_out_fit"]
    assert fit < WEAK_FIT  # the case: the input explains little of the output
    assert "weak" in res.checks, res.checks
    assert f"{fit:.1f} % fit" in res.checks["weak"]
    assert "weak:" in res.summary()


def test_a_record_the_input_explains_gets_no_note():
    res = quiet_identify(_disturbed(0.2))
    assert res.model.info["identify"]["held_out_fit"] > WEAK_FIT
    assert "weak" not in res.checks, res.checks


@pytest.mark.parametrize("fit,noted", [(-50.0, True), (0.0, True), (29.0, True),
                                       (WEAK_FIT, False), (80.0, False),
                                       (float("-inf"), False)])
def test_the_line_is_half_of_the_variation_explained(fit, noted):
    checks: dict = {}
    weak_check(fit, checks)
    assert ("weak" in checks) is noted
    if noted:
        explained = max(0.0, 1 - (1 - fit / 100) ** 2)
        assert f"explains about {100 * explained:.0f} %" in checks["weak"]
