"""A transfer function's dt is checked when it is written, as a state-space model's."""

import numpy as np
import pytest

import sysid


def test_a_transfer_functions_dt_is_checked_on_assignment():
    # g.dt = nan made the model continuous-time silently (its responses then those of s,
    # not z); a negative dt gave negative times. Refused as the constructor refuses them.
    g = sysid.TransferFunction([[[0.5]]], [[[1.0, -0.5]]], dt=0.1)
    for bad in (np.nan, -0.1, np.inf, "fast"):
        with pytest.raises(sysid.DataError, match="dt"):
            g.dt = bad
    assert g.dt == 0.1
    g.dt = 0.2
    assert g.dt == 0.2
    c = sysid.TransferFunction([[[1.0]]], [[[1.0, 1.0]]])
    assert c.dt == 0.0
    c.dt = None
    assert c.dt == 0.0
