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

import importlib as _importlib

from ._sysid import __version__
from .analysis.criteria import criteria  # a function named like its module: bind it eagerly
from .data import datasets
from .data.iodata import DataSummary, IOData
from .data.segments import SplitData
from .data.trend import Trend
from .data.units import check_unit, sample_time
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
from .estimate.subspace import (
    SubspaceEstimator,
    cva,
    default_horizon,
    moesp,
    n4sid,
)
from .models.statespace import StateSpaceModel

# Everything else loads on first use (PEP 562), so that `import sysid` pulls in neither
# SciPy's signal and statistics modules nor plotting: name -> submodule.
_LAZY = {
    "Coherence": "analysis.spectra",
    "ContinuousStateSpace": "analysis.lti",
    "Correlation": "analysis.correlation",
    "EraResult": "estimate.realization",
    "FRD": "models.frd",
    "FRDComparison": "models.frd",
    "Gramians": "analysis.reduction",
    "MarkovEstimate": "estimate.realization",
    "ModalAnalysis": "analysis.modal",
    "PolynomialModel": "models.polynomial",
    "Spectra": "analysis.spectra",
    "StabilizationDiagram": "estimate.realization",
    "ar": "estimate.polynomial",
    "arma": "estimate.polynomial",
    "armax": "estimate.polynomial",
    "arx": "estimate.polynomial",
    "arxstruc": "estimate.polynomial",
    "balanced_realization": "analysis.reduction",
    "balanced_truncation": "analysis.reduction",
    "bandpass": "data.filtering",
    "bj": "estimate.polynomial",
    "butter_sos": "data.filtering",
    "c2d": "analysis.lti",
    "check_excitation": "data.input_design",
    "chirp": "data.input_design",
    "coherence": "analysis.spectra",
    "compare": "analysis.validation",
    "compress_dask": "estimate.streaming",
    "compress_stream": "estimate.streaming",
    "correlation": "analysis.correlation",
    "crest_factor": "data.input_design",
    "ctrb": "analysis.lti",
    "d2c": "analysis.lti",
    "damp": "analysis.lti",
    "decimate": "data.filtering",
    "delayest": "estimate.polynomial",
    "despike": "data.preprocessing",
    "detrend": "data.preprocessing",
    "drop_quiet": "data.preprocessing",
    "era": "estimate.realization",
    "era_stabilization": "estimate.realization",
    "error_spectrum": "analysis.validation",
    "estimate_x0": "analysis.validation",
    "etfe": "analysis.frf",
    "filtfilt": "data.filtering",
    "find_spikes": "data.preprocessing",
    "fit_metrics": "analysis.validation",
    "from_control": "analysis.lti",
    "from_scipy": "analysis.lti",
    "gramians": "analysis.reduction",
    "hankel_singular_values": "analysis.reduction",
    "highpass": "data.filtering",
    "ho_kalman": "estimate.realization",
    "impulse": "analysis.lti",
    "impulse_from_frf": "estimate.markov",
    "impulse_response": "estimate.markov",
    "is_controllable": "analysis.lti",
    "is_observable": "analysis.lti",
    "iv4": "estimate.polynomial",
    "kung": "estimate.realization",
    "load_model": "models.io",
    "lowpass": "data.filtering",
    "modal_analysis": "analysis.modal",
    "multisine": "data.input_design",
    "n_parameters": "analysis.criteria",
    "obsv": "analysis.lti",
    "oe": "estimate.polynomial",
    "okid": "estimate.markov",
    "pem": "estimate.pem",
    "periodogram": "analysis.spectra",
    "persistent_excitation_order": "data.input_design",
    "prbs": "data.input_design",
    "random_binary": "data.input_design",
    "random_gaussian": "data.input_design",
    "repair_nan": "data.raw",
    "resample": "data.filtering",
    "residuals": "analysis.validation",
    "save_model": "models.io",
    "scale": "data.preprocessing",
    "select_mask": "data.preprocessing",
    "select_mode": "data.preprocessing",
    "select_order": "analysis.criteria",
    "selstruc": "estimate.polynomial",
    "spa": "analysis.frf",
    "spectra": "analysis.spectra",
    "ssest": "estimate.pem",
    "step": "analysis.lti",
    "to_control": "analysis.lti",
    "to_scipy": "analysis.lti",
    "welch_frf": "analysis.frf",
    "zeros": "analysis.lti",
}


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'sysid' has no attribute {name!r}")
    value = getattr(_importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(__all__) | {"datasets", "__version__"})


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
    "pem",
    "ssest",
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
