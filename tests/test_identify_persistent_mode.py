"""``identify`` notes a chosen pole that does not decay over the record
(``checks["persistent_mode"]``). Before: on the robot arm's first half it returned a model with
a pole at 1 - 7e-10 (its static gain set by where the search's stability bound held that pole)
and no check said so."""

from __future__ import annotations

import warnings

import numpy as np

import sysid
from sysid.identify.notes import PERSISTENT_DECAY, persistent_mode_check


def quiet_identify(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sysid.identify(data, progress=False)


def test_the_robot_arm_integrator_is_noted():
    d = sysid.datasets.load_robot_arm()
    half = d.lengths[0] // 2
    res = quiet_identify(sysid.IOData(u=d.u[:half], y=d.y[:half], dt=d.dt))
    rho = float(np.max(np.abs(res.model.poles())))
    assert rho ** half > PERSISTENT_DECAY  # the case: a mode that keeps > 99 % over the record
    assert "persistent_mode" in res.checks, res.checks
    assert "integrator" in res.checks["persistent_mode"]


def test_a_plant_with_decaying_modes_gets_no_note():
    d = sysid.datasets.load_dryer()
    res = quiet_identify(d)
    assert "persistent_mode" not in res.checks, res.checks


def test_the_rule_follows_the_record_length():
    m = sysid.StateSpaceModel([[0.9999]], [[1.0]], [[1.0]])
    for n, noted in ((50, True), (5000, False)):  # 0.9999**50 = 0.995, **5000 = 0.61
        checks: dict = {}
        persistent_mode_check(m, sysid.IOData(u=np.ones(n), y=np.linspace(0, 1, n)), checks)
        assert ("persistent_mode" in checks) is noted
    checks = {}
    unstable = sysid.StateSpaceModel([[1.01]], [[1.0]], [[1.0]])  # warned where chosen
    persistent_mode_check(unstable, sysid.IOData(u=np.ones(50), y=np.ones(50) * 2), checks)
    assert checks == {}
