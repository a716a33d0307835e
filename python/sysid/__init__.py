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
from .criteria import criteria, n_parameters, select_order
from .data import DataSummary, IOData, SplitData, Trend, check_unit, sample_time
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
from .input_design import (
    check_excitation,
    chirp,
    crest_factor,
    multisine,
    persistent_excitation_order,
    prbs,
    random_binary,
    random_gaussian,
)
from .io import load_model, save_model
from .modal import ModalAnalysis, modal_analysis
from .model import StateSpaceModel
from .nonparametric import (
    FRD,
    Coherence,
    Correlation,
    FRDComparison,
    Spectra,
    coherence,
    correlation,
    etfe,
    periodogram,
    spa,
    spectra,
    welch_frf,
)
from .preprocessing import (
    bandpass,
    butter_sos,
    decimate,
    despike,
    detrend,
    drop_quiet,
    filtfilt,
    find_spikes,
    highpass,
    lowpass,
    repair_nan,
    resample,
    scale,
    select_mask,
    select_mode,
)
from .realization import (
    EraResult,
    MarkovEstimate,
    StabilizationDiagram,
    era,
    era_stabilization,
    ho_kalman,
    impulse_from_frf,
    impulse_response,
    kung,
    okid,
)
from .reduction import (
    Gramians,
    balanced_realization,
    balanced_truncation,
    gramians,
    hankel_singular_values,
)
from .streaming import compress_dask, compress_stream
from .subspace import SubspaceEstimator, cva, default_horizon, moesp, n4sid
from .validation import compare, error_spectrum, estimate_x0, fit_metrics, residuals

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
    # data handling, pre-processing, input design, non-parametric analysis
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
    # realisation, Markov parameters, reduction, modal analysis
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
