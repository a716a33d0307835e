"""spa's default lag window is chosen from the data, so that its confidence band is honest.

A 20 000-sample record of a 4th-order system with 2 inputs and 2 outputs (a slowly decaying
resonant pair, poles at radius 0.9): at MATLAB's fixed default (30 lags) the lag window's bias
puts the true response outside the 99 % band at many frequencies; the default chosen from the
data keeps it inside at >= 95 % of the (frequency, output, input) points.
"""

from __future__ import annotations

import numpy as np

import sysid


def _record(seed: int = 0, n: int = 20_000) -> tuple[sysid.IOData, sysid.StateSpaceModel]:
    rng = np.random.default_rng(seed)
    c, s = 0.9 * np.cos(0.3), 0.9 * np.sin(0.3)
    a = np.array([[c, s, 0, 0], [-s, c, 0, 0], [0, 0, 0.7, 0], [0, 0, 0, -0.5]])
    g = sysid.StateSpaceModel(a, rng.standard_normal((4, 2)), rng.standard_normal((2, 4)))
    u = rng.standard_normal((n, 2))
    y = g.simulate(u) + 0.5 * rng.standard_normal((n, 2))
    return sysid.IOData(u=u, y=y), g


def test_default_window_gives_an_honest_99_percent_band() -> None:
    data, g = _record()
    frd = sysid.spa(data)
    inside = frd.within_band(g).mean()
    assert inside >= 0.95, (inside, frd.info)
    assert frd.info["lags_rule"].startswith("data")
    # 6 x the last significant lag, doubled until the bias check passes (here once: the
    # estimates with 78 and 156 lags disagree beyond the band at the resonance)
    doubled = frd.info["lags"] / (6 * frd.info["significant_lag"])
    assert doubled in (1, 2, 4, 8) and frd.info["bias_check"] == "passed", frd.info
    # MATLAB's fixed default is the thing beaten here
    fixed = sysid.spa(data, lags=30).within_band(g).mean()
    assert fixed < 0.9 < inside
    assert sysid.spa(data, lags=30).info["lags_rule"] == "given"


def test_window_follows_the_decay_of_the_response() -> None:
    rng = np.random.default_rng(1)
    u = rng.standard_normal((20_000, 1))
    lags = {}
    for pole in (0.3, 0.8, 0.95):
        g = sysid.StateSpaceModel([[pole]], [[1.0]], [[1.0]])
        y = g.simulate(u) + 0.1 * rng.standard_normal((20_000, 1))
        lags[pole] = sysid.default_lags(sysid.IOData(u=u, y=y))[0]
    assert lags[0.3] < lags[0.8] < lags[0.95] <= 2000


def test_short_records_keep_a_valid_window() -> None:
    data, _ = _record(n=150)
    frd = sysid.spa(data)
    assert 1 <= frd.info["lags"] < 150
