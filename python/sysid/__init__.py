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
from .modal import ModalAnalysis, modal_analysis
from .model import StateSpaceModel
from .realization import EraResult, MarkovEstimate, era, ho_kalman, impulse_response, kung, okid
from .reduction import (
    Gramians,
    balanced_realization,
    balanced_truncation,
    gramians,
    hankel_singular_values,
)
from .subspace import SubspaceEstimator, cva, default_horizon, moesp, n4sid

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
    "ho_kalman",
    "kung",
    "era",
    "EraResult",
    "impulse_response",
    "okid",
    "MarkovEstimate",
    "modal_analysis",
    "ModalAnalysis",
    "gramians",
    "Gramians",
    "hankel_singular_values",
    "balanced_realization",
    "balanced_truncation",
]
