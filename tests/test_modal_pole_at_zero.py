"""A pole at ``z = 0`` (a delay realised as a state: infinitely fast) in
:func:`sysid.modal_analysis` has an infinite natural frequency and damping 1, as
:func:`sysid.damp` (and MATLAB's ``damp``, python-control's ``damp``) report it.

Before: the modulus was clamped to the smallest double, so the mode read 7083.96 rad/s
(``ln(2.2e-308) / dt`` at dt = 0.1, above the Nyquist frequency 31.4 rad/s) and ``s`` a
finite ``-7083.96``.
"""

import numpy as np
import pytest

import sysid


@pytest.fixture
def delayed():
    # a unit delay (z = 0) in series with a first-order lag (z = 0.5), dt = 0.1
    return sysid.StateSpaceModel([[0.0, 0.0], [1.0, 0.5]], [[1.0], [0.0]], [[0.0, 1.0]],
                                 dt=0.1)


def test_delay_mode_is_infinitely_fast_with_damping_one(delayed):
    modes = sysid.modal_analysis(delayed)
    assert len(modes) == 2
    k = int(np.argmin(np.abs(modes.eigenvalues)))
    assert modes.eigenvalues[k] == 0
    assert np.isinf(modes.omega[k]) and np.isinf(modes.frequencies_hz[k])
    assert modes.damping[k] == 1.0
    assert modes.s[k] == -np.inf
    # the other mode is untouched: 6.93 rad/s, damping 1
    assert modes.omega[1 - k] == pytest.approx(np.log(2) / 0.1)
    assert modes.damping[1 - k] == pytest.approx(1.0)


def test_consistent_with_damp(delayed):
    modes = sysid.modal_analysis(delayed)
    table = sysid.damp(delayed)
    np.testing.assert_allclose(np.sort(modes.omega), np.sort(table.wn), rtol=1e-12)
    np.testing.assert_allclose(np.sort(modes.damping), np.sort(table.zeta), rtol=1e-12)
    np.testing.assert_allclose(np.sort_complex(modes.s), np.sort_complex(table.s), rtol=1e-12)


def test_tables_show_it(delayed):
    modes = sysid.modal_analysis(delayed)
    assert "inf" in modes.table() and "7083" not in modes.table()
    df = modes.to_pandas()
    assert np.isinf(df["omega"]).sum() == 1
    assert len(modes.select(np.isfinite(modes.frequencies_hz))) == 1


def test_integrator_has_damping_minus_one_as_damp():
    # z = 1 (s = 0): MATLAB's damp reports wn = 0 and zeta = -1; modal_analysis said 1
    m = sysid.StateSpaceModel([[1.0, 0.0], [0.0, 0.5]], [[1.0], [1.0]], [[1.0, 1.0]], dt=0.1)
    modes = sysid.modal_analysis(m)
    k = int(np.argmin(np.abs(modes.eigenvalues - 1.0)))
    assert modes.omega[k] == 0.0 and modes.damping[k] == -1.0
    table = sysid.damp(m)
    np.testing.assert_allclose(np.sort(modes.damping), np.sort(table.zeta), rtol=1e-12)
    assert "-1.0000" in modes.table() and modes.to_pandas()["damping"].min() == -1.0
