"""identify's excitation check names an input switched a few times beside richly excited
ones, and states the order it counts (at least 40, or exactly a lower one)."""

import numpy as np

import sysid

from conftest import pulsed_record


def test_a_pulsed_input_beside_a_rich_one_is_named_in_identifys_checks():
    # a helicopter's pitch motor ramped while its yaw motor was pulsed once: the check read
    # "input persistently exciting of order >= 40" for both inputs
    data = pulsed_record(900, 300, 500, 2.0, 0.05, seed=5)
    res = sysid.identify(data, refine=False, progress=False)
    c = res.checks["excitation"]
    assert "u1 at sample(s) 300, 500" in c and "steps or pulses" in c
    assert "other input(s) persistently exciting of order >= 40" in c


def test_the_count_is_exact_below_forty():
    from sysid.identify.notes import excitation_check

    t = np.arange(400.0)
    u = np.c_[np.sin(0.3 * t)]
    assert excitation_check(sysid.IOData(u, np.zeros((400, 1)), 1.0)) == (
        "input persistently exciting of order 2")
