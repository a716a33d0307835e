"""sysid: identification of linear state-space models from input/output data.

.. math::

    x(t+1) = A x(t) + B u(t) + K e(t), \\qquad y(t) = C x(t) + D u(t) + e(t)

A streaming Rust core (on faer) compresses the record once; every estimate, order choice
and validation step works on small matrices afterwards.

Examples
--------
>>> import numpy as np, sysid
>>> d = np.loadtxt(sysid.datasets.path("dryer"))
>>> data = sysid.IOData(u=d[:, :1], y=d[:, 1:], dt=0.08)
>>> est = sysid.SubspaceEstimator(data, horizon=15)
>>> est.auto_order
4
"""

from . import datasets
from ._sysid import __version__
from .data import IOData
from .errors import (
    DataError,
    ExcitationError,
    InsufficientDataError,
    NonFiniteError,
    NumericalError,
    OrderError,
    RiccatiError,
    ShapeError,
    SysidError,
)
from .model import StateSpaceModel
from .subspace import SubspaceEstimator, cva, default_horizon, moesp, n4sid
from .validation import compare, error_spectrum, estimate_x0, fit_metrics, residuals
from .criteria import criteria, n_parameters, select_order
from .analysis import (
    ContinuousStateSpace,
    c2d,
    ctrb,
    d2c,
    damp,
    from_control,
    from_scipy,
    impulse,
    is_controllable,
    is_observable,
    obsv,
    step,
    to_control,
    to_scipy,
    zeros,
)
from .io import load_model, save_model

__all__ = [
    "__version__",
    "datasets",
    "IOData",
    "StateSpaceModel",
    "SubspaceEstimator",
    "default_horizon",
    "moesp",
    "n4sid",
    "cva",
    "SysidError",
    "DataError",
    "NonFiniteError",
    "ShapeError",
    "InsufficientDataError",
    "ExcitationError",
    "OrderError",
    "NumericalError",
    "RiccatiError",
    "compare",
    "residuals",
    "error_spectrum",
    "estimate_x0",
    "fit_metrics",
    "criteria",
    "n_parameters",
    "select_order",
    "ContinuousStateSpace",
    "zeros",
    "damp",
    "ctrb",
    "obsv",
    "is_controllable",
    "is_observable",
    "step",
    "impulse",
    "c2d",
    "d2c",
    "to_control",
    "from_control",
    "to_scipy",
    "from_scipy",
    "save_model",
    "load_model",
]
