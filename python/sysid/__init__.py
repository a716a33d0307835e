r"""sysid: identification of linear state-space models from input/output data.

.. math::

    x(t+1) = A x(t) + B u(t) + K e(t), \qquad y(t) = C x(t) + D u(t) + e(t)

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

from __future__ import annotations

import importlib
from typing import Any

from . import datasets
from ._sysid import __version__
from .criteria import criteria  # a function named like its module: bind it eagerly
from .data import (
    DataSummary,
    IOData,
    SplitData,
    Trend,
    check_unit,
    sample_time,
)
from .errors import (
    DataError,
    ExcitationError,
    ExcitationWarning,
    InsufficientDataError,
    NonFiniteError,
    NumericalError,
    OrderError,
    RiccatiError,
    ShapeError,
    SysidError,
)
from .model import StateSpaceModel
from .subspace import (
    SubspaceEstimator,
    cva,
    default_horizon,
    moesp,
    n4sid,
)

# Everything else loads on first use (PEP 562), so that `import sysid` pulls in neither
# SciPy's signal and statistics modules nor plotting: name -> submodule.
_LAZY = {
    # polynomial models (issue 13)
    "PolynomialModel": "models.polynomial",
    "arx": "estimate.polynomial",
    "armax": "estimate.polynomial",
    "oe": "estimate.polynomial",
    "bj": "estimate.polynomial",
    "arxstruc": "estimate.polynomial",
    "selstruc": "estimate.polynomial",
    "ar": "estimate.polynomial",
    "arma": "estimate.polynomial",
    "delayest": "estimate.polynomial",
    "iv4": "estimate.polynomial",
    "Coherence": "nonparametric",
    "ContinuousStateSpace": "analysis",
    "Correlation": "nonparametric",
    "EraResult": "realization",
    "FRD": "nonparametric",
    "FRDComparison": "nonparametric",
    "Gramians": "reduction",
    "MarkovEstimate": "realization",
    "ModalAnalysis": "modal",
    "Spectra": "nonparametric",
    "StabilizationDiagram": "realization",
    "balanced_realization": "reduction",
    "balanced_truncation": "reduction",
    "bandpass": "preprocessing",
    "butter_sos": "preprocessing",
    "c2d": "analysis",
    "check_excitation": "input_design",
    "chirp": "input_design",
    "coherence": "nonparametric",
    "compare": "validation",
    "compress_dask": "streaming",
    "compress_stream": "streaming",
    "correlation": "nonparametric",
    "crest_factor": "input_design",
    "ctrb": "analysis",
    "d2c": "analysis",
    "damp": "analysis",
    "decimate": "preprocessing",
    "despike": "preprocessing",
    "detrend": "preprocessing",
    "drop_quiet": "preprocessing",
    "era": "realization",
    "era_stabilization": "realization",
    "error_spectrum": "validation",
    "estimate_x0": "validation",
    "etfe": "nonparametric",
    "filtfilt": "preprocessing",
    "find_spikes": "preprocessing",
    "fit_metrics": "validation",
    "from_control": "analysis",
    "from_scipy": "analysis",
    "gramians": "reduction",
    "hankel_singular_values": "reduction",
    "highpass": "preprocessing",
    "ho_kalman": "realization",
    "impulse": "analysis",
    "impulse_from_frf": "realization",
    "impulse_response": "realization",
    "is_controllable": "analysis",
    "is_observable": "analysis",
    "kung": "realization",
    "load_model": "io",
    "lowpass": "preprocessing",
    "modal_analysis": "modal",
    "multisine": "input_design",
    "n_parameters": "criteria",
    "obsv": "analysis",
    "okid": "realization",
    "periodogram": "nonparametric",
    "persistent_excitation_order": "input_design",
    "prbs": "input_design",
    "random_binary": "input_design",
    "random_gaussian": "input_design",
    "repair_nan": "preprocessing",
    "resample": "preprocessing",
    "residuals": "validation",
    "save_model": "io",
    "scale": "preprocessing",
    "select_mask": "preprocessing",
    "select_mode": "preprocessing",
    "select_order": "criteria",
    "spa": "nonparametric",
    "spectra": "nonparametric",
    "step": "analysis",
    "to_control": "analysis",
    "to_scipy": "analysis",
    "welch_frf": "nonparametric",
    "zeros": "analysis",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'sysid' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "PolynomialModel",
    "arx",
    "armax",
    "oe",
    "bj",
    "arxstruc",
    "selstruc",
    "ar",
    "arma",
    "delayest",
    "iv4",
    "__version__",
    "datasets",
    "IOData",
    "StateSpaceModel",
    "SubspaceEstimator",
    "default_horizon",
    "moesp",
    "n4sid",
    "cva",
    "compress_stream",
    "compress_dask",
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
    "ExcitationWarning",
    "Trend",
    "SplitData",
    "DataSummary",
    "sample_time",
    "check_unit",
    "repair_nan",
    "find_spikes",
    "despike",
    "detrend",
    "scale",
    "butter_sos",
    "filtfilt",
    "lowpass",
    "highpass",
    "bandpass",
    "resample",
    "decimate",
    "select_mode",
    "select_mask",
    "drop_quiet",
    "prbs",
    "random_binary",
    "random_gaussian",
    "multisine",
    "chirp",
    "crest_factor",
    "persistent_excitation_order",
    "check_excitation",
    "FRD",
    "FRDComparison",
    "Spectra",
    "Coherence",
    "Correlation",
    "etfe",
    "spa",
    "welch_frf",
    "spectra",
    "periodogram",
    "coherence",
    "correlation",
    "ho_kalman",
    "kung",
    "era",
    "EraResult",
    "impulse_response",
    "okid",
    "MarkovEstimate",
    "impulse_from_frf",
    "era_stabilization",
    "StabilizationDiagram",
    "modal_analysis",
    "ModalAnalysis",
    "gramians",
    "Gramians",
    "hankel_singular_values",
    "balanced_realization",
    "balanced_truncation",
]
