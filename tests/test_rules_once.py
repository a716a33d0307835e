"""Issue 31 item 2: each rule once, in the core.

Option strings are parsed by the core (one list of names, one error), stabilisation by
pole reflection is the core's, and lagged covariances come from the core's lagged sums; the
Python layer asks the core and presents its answer.
"""

from __future__ import annotations

import numpy as np
import pytest

import sysid
from sysid import _sysid
from sysid.errors import DataError

OPTIONS = {
    "method": ("moesp", "po-moesp", "N4SID"),
    "closed_loop_method": ("pbsid", "pbsid-opt", "ssarx"),
    "compressor": ("auto", "qr", "correlation"),
    "regularization": ("none", "ridge", "tc"),
    "fir_regularization": ("none", "tc"),
    "factor_source": ("qr", "qr-fallback"),
    "realization": ("ho_kalman", "kung", "era"),
    "integrator": ("rk4", "adaptive"),
    "jacobian": ("fd", "sensitivity"),
    "terms": ("full", "states", "inputs"),
    "recursive_method": ("forgetting", "kalman", "normalized_gradient", "gradient"),
    "nonlinearity": ("identity", "saturation", "deadzone", "polynomial", "pwl", "sigmoid"),
}


@pytest.mark.parametrize("option", sorted(OPTIONS))
def test_every_option_is_parsed_by_the_core(option: str) -> None:
    for name in OPTIONS[option]:
        canon = _sysid.option_name(option, name)
        assert _sysid.option_name(option, canon) == canon
    with pytest.raises(DataError, match=r'unknown \w+ "nope"; \w+ must be "'):
        _sysid.option_name(option, "nope")


def test_aliases_and_case_map_to_one_name() -> None:
    assert _sysid.option_name("method", "PO-MOESP") == "moesp"
    assert _sysid.option_name("closed_loop_method", "pbsid-opt") == "pbsid"
    with pytest.raises(DataError, match="unknown option"):
        _sysid.option_name("colour", "red")


def test_python_presents_the_core_error() -> None:
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal((200, 1)), rng.standard_normal((200, 1))
    core = str(pytest.raises(DataError, _sysid.option_name, "compressor", "fast").value)
    with pytest.raises(DataError) as e:
        sysid.compress_stream((u, y), 3, compressor="fast")
    assert str(e.value) == core
    with pytest.raises(DataError, match='"forgetting", "kalman"'):
        sysid.RecursiveARX(1, 1, method="rls")
    with pytest.raises(DataError, match='integrator must be "rk4" or "adaptive"'):
        sysid.NonlinearGreyBox(lambda t, x, u, p: -x, lambda t, x, u, p: x, {"a": 1.0}, nx=1,
                               integrator="euler")
    with pytest.raises(DataError, match="integrator must be a string"):
        sysid.NonlinearGreyBox(lambda t, x, u, p: -x, lambda t, x, u, p: x, {"a": 1.0}, nx=1,
                               integrator=4)
