"""Conversions between :class:`~sysid.TransferFunction` and python-control / SciPy.

python-control is optional at run time: it is imported when a conversion needs it, with an
error naming ``pip install control`` when it is missing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["to_control", "from_control", "to_scipy", "from_scipy", "require_control"]


def require_control() -> Any:
    """The ``control`` module, or a :class:`~sysid.DataError` saying how to install it."""
    try:
        import control
    except ImportError:
        raise DataError("this needs python-control, which is not installed: "
                        "pip install control") from None
    return control


def to_control(tf: Any) -> Any:
    """``control.TransferFunction`` of a delay-free model (``dt = 0`` or the sample time)."""
    if np.any(tf.iodelay > 0):
        raise DataError("python-control transfer functions carry no delay: convert the "
                        "sampled model (tf.to_statespace(dt)) or approximate the delay "
                        "(control.pade) and multiply")
    ct = require_control()
    num = [[list(c) for c in row] for row in tf.num]
    den = [[list(c) for c in row] for row in tf.den]
    if tf.ninputs == tf.noutputs == 1:
        return ct.tf(num[0][0], den[0][0], tf.dt)
    return ct.tf(num, den, tf.dt)


def from_control(cls: Any, sys: Any) -> Any:
    """A :class:`~sysid.TransferFunction` from any python-control LTI system."""
    ct = require_control()
    try:
        g = ct.tf(sys)
    except Exception as e:  # python-control raises several types
        raise DataError(f"cannot convert {type(sys).__name__} to a transfer function: {e}"
                        ) from None
    dt = 0.0 if g.dt in (None, 0) else float(g.dt) if g.dt is not True else 1.0
    num = [[np.asarray(g.num[i][j], float) for j in range(g.ninputs)]
           for i in range(g.noutputs)]
    den = [[np.asarray(g.den[i][j], float) for j in range(g.ninputs)]
           for i in range(g.noutputs)]
    return cls(num, den, dt=dt)


def to_scipy(tf: Any) -> Any:
    """``scipy.signal.TransferFunction`` (single-input single-output, no delay)."""
    import scipy.signal

    if tf.ninputs != 1 or tf.noutputs != 1:
        raise DataError("scipy.signal transfer functions are single-input single-output: "
                        "convert one pair, or use tf.to_statespace()")
    if np.any(tf.iodelay > 0):
        raise DataError("scipy.signal transfer functions carry no delay: use "
                        "tf.to_statespace(dt) for the exact sampled model")
    if tf.dt > 0:
        return scipy.signal.TransferFunction(tf.num[0][0], tf.den[0][0], dt=tf.dt)
    return scipy.signal.TransferFunction(tf.num[0][0], tf.den[0][0])


def from_scipy(cls: Any, sys: Any) -> Any:
    """From ``scipy.signal.lti`` / ``dlti`` (any representation)."""
    if not hasattr(sys, "to_tf"):
        raise DataError(f"expected a scipy.signal lti or dlti object, got {type(sys).__name__}")
    g = sys.to_tf()
    num = np.atleast_2d(g.num)
    if num.shape[0] != 1:
        raise DataError("only single-output scipy systems convert; split the outputs first")
    dt = float(getattr(sys, "dt", None) or 0.0)
    return cls(num[0], g.den, dt=dt)
