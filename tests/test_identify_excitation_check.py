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
    assert excitation_check(sysid.IOData(u, np.zeros((400, 1)), 1.0))[0] == (
        "input persistently exciting of order 2")


def test_a_chosen_order_the_input_does_not_determine_is_said_and_warned():
    """Three tones measured with sensor noise (spectral count 6) into a lightly damped plant
    of order 4: identify's held-out blocks repeat the same tones and chose an order above 3
    without a word, where every estimator warns of its own fit. Now checks["order_excitation"]
    and an ExcitationWarning at the user's line say so; an order the input determines gets
    neither."""
    import warnings

    from sysid.errors import ExcitationWarning
    from sysid.identify.notes import excitation_check, order_excitation_check

    rng = np.random.default_rng(0)
    t = np.arange(3000)
    u = sum(np.sin(w * t + p) for w, p in ((0.25, 0.1), (0.6, 1.0), (1.1, 2.0)))
    u = u + 1e-3 * rng.standard_normal(t.size)
    data = sysid.IOData(u, np.zeros((t.size, 1)), 1.0)
    checks: dict = {}
    counted = excitation_check(data)[1]
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        order_excitation_check(3, data, checks, counted)
        assert not checks and not said
        order_excitation_check(4, data, checks, counted)
    assert "chosen order 4 needs an input persistently exciting of order 8" in checks[
        "order_excitation"] and "of order 6" in checks["order_excitation"]
    assert [w.category for w in said] == [ExcitationWarning]
    assert said[0].filename == __file__


def test_identify_says_so_of_its_own_choice():
    import warnings

    from scipy import signal

    from sysid.errors import ExcitationWarning

    rng = np.random.default_rng(0)
    t = np.arange(3000)
    u = sum(np.sin(w * t + p) for w, p in ((0.25, 0.1), (0.6, 1.0), (1.1, 2.0)))
    u = u + 1e-2 * rng.standard_normal(t.size)
    b, a = signal.cheby1(4, 1, 0.3)
    y = signal.lfilter(b, a, u) + signal.lfilter([1], [1, -0.95], 0.05 * rng.standard_normal(
        t.size))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        res = sysid.identify(sysid.IOData(u, y, 1.0), progress=False)
    order = res.model.statespace.A.shape[0]
    assert order > 3   # the held-out blocks (the same tones) prefer it
    assert f"chosen order {order} needs" in res.checks["order_excitation"]
    assert [w.filename for w in said if w.category is ExcitationWarning] == [__file__]
