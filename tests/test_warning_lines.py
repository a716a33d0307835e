"""Every warning points at the user's line, however deep inside sysid it is raised and
whichever wrappers (the BLAS-thread limit of every estimator) stand between: a warning that
names ``_threads.py`` or another sysid file tells the user nothing about which call of theirs
it concerns (``procest``'s identifiability and iteration-cap warnings did, with fixed
``stacklevel`` counts that the wrapper's frame put one short)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sysid


def _integrating() -> sysid.IOData:
    rng = np.random.default_rng(0)
    u = rng.standard_normal((300, 1))
    y = np.cumsum(u, 0) * 0.1 + rng.standard_normal((300, 1))
    return sysid.IOData(u, y, 0.1)


def _with_d() -> tuple[sysid.IOData, sysid.StateSpaceModel]:
    rng = np.random.default_rng(1)
    u = rng.standard_normal((400, 1))
    m = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], [[0.5]], dt=1.0)
    y = m.simulate(u) + 0.01 * rng.standard_normal((400, 1))
    return sysid.IOData(u, y, 1.0), m


CALLS = {
    # identifiability (a pole pair against the integrator), the iteration cap, a bound
    "procest": lambda: sysid.procest(_integrating(), "P2DU"),
    "ssest at its cap": lambda: sysid.ssest(_with_d()[0], 2, max_iter=1),
    "n4sid on an offset": lambda: sysid.n4sid(
        sysid.IOData(_integrating().u, _integrating().y + 100.0, 0.1), 2),
    "check_excitation": lambda: sysid.check_excitation(np.sin(0.3 * np.arange(200.0)), 4),
    "pem dropping D": lambda: sysid.pem(_with_d()[0], _with_d()[1], feedthrough=False),
}


@pytest.mark.parametrize("name", list(CALLS))
def test_every_warning_names_the_callers_line(name: str) -> None:
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        CALLS[name]()
    assert said, f"{name} gave no warning: the case no longer checks anything"
    where = {(w.category.__name__, w.filename) for w in said if w.filename != __file__}
    assert not where, f"{name}: warnings pointing inside sysid: {sorted(where)}"
