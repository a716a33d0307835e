"""compare on a validation record whose output barely moves (issue 26): the settled end of a
step test gave NRMSE fits of -258 to -938 % with no word about why (the fit divides the error
by the output's variation about its mean, which there is little more than noise)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid
from sysid.errors import SysidWarning


def _step_test(n=900, seed=0):
    """A motor's speed after a torque step at sample 50 (gain 4, time constant 20 samples),
    settled from about sample 200; the last third is the settled end."""
    rng = np.random.default_rng(seed)
    u = np.r_[np.zeros(50), np.full(n - 50, 1.0)]
    true = sysid.StateSpaceModel([[0.95]], [[0.2]], [[1.0]], dt=1.0)
    y = true.simulate(u) + 0.02 * rng.standard_normal((n, 1))
    return sysid.IOData(u=u, y=y, dt=1.0)


def test_a_flat_validation_output_says_the_fit_is_not_meaningful():
    data = _step_test()
    settled = data[600:]
    model = sysid.StateSpaceModel([[0.95]], [[0.196]], [[1.0]], dt=1.0)  # gain 2 % low
    with pytest.warns(SysidWarning, match="not a meaningful measure") as said:
        r = sysid.compare(model, settled)
    assert r.fit[0, 0] < -100  # the number that misled
    msg = str(said[0].message)
    assert "variation" in msg and "level" in msg and "RMSE" in msg and "changes" in msg
    assert r.flat == [(0, 0)] and len(r.notes) == 1
    assert "note: output y0" in r.summary() and "flat output" in r.summary()
    assert "fit not meaningful on flat output y0" in repr(r)
    assert r.rmse[0, 0] < 0.1  # the level is 2 % off: the RMSE says it is close
    # the same model on a segment holding the step: a meaningful fit, no note, no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        moving = sysid.compare(model, data[:300])
    assert moving.fit[0, 0] > 90 and not moving.flat and not moving.notes
    assert "note" not in moving.summary() and "flat" not in repr(moving)


def test_a_flat_output_with_inputs_standing_still_is_judged_by_its_noise():
    """An output about zero (no level to measure against) that shows only noise while the
    inputs stand still is flat too; a lively output about zero is not."""
    rng = np.random.default_rng(1)
    model = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=1.0)
    quiet = sysid.IOData(u=np.zeros(300), y=0.01 * rng.standard_normal(300), dt=1.0)
    with pytest.warns(SysidWarning, match="inputs stand still"):
        r = sysid.compare(model, quiet, x0="zero")
    assert r.flat == [(0, 0)] and "noise" in r.notes[0]
    u = rng.standard_normal(300)
    lively = sysid.IOData(u=u, y=model.simulate(u) + 0.01 * rng.standard_normal((300, 1)),
                          dt=1.0)
    assert not sysid.compare(model, lively).flat


def test_a_comparison_of_several_models_notes_the_flat_output_too():
    data = _step_test()
    m1 = sysid.StateSpaceModel([[0.95]], [[0.196]], [[1.0]], dt=1.0)
    m2 = sysid.StateSpaceModel([[0.95]], [[0.204]], [[1.0]], dt=1.0)
    with pytest.warns(SysidWarning, match="not a meaningful measure"):
        cs = sysid.compare(data[600:], m1, m2)
    assert "note: output y0 barely moves" in cs.summary()
    assert all(r.flat == [(0, 0)] for r in cs.results)
