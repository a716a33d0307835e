"""Prediction-error refinement of periodic data in the frequency domain (issue 28).

With ``P`` whole periods of a periodic input in steady state, the DFT of each period gives,
on the lines the input excites, ``Y_k = G(e^{j w_k}) U_k + V_k`` with no transient and no
initial state. :func:`sysid.bla` averages the periods (the response ``G_k`` and the variance
``s2_k`` of each entry from the spread over the periods); the model is then fitted on those
lines only,

.. code-block:: text

    minimise  sum_k sum_ij |G_ij(e^{j w_k}) - G_k,ij|^2 / s2_k,ij

(for one input the same sum as ``|Y_k - G U_k|^2 / var(Y_k)``: the maximum-likelihood
criterion of frequency-domain tools, with the variances from the periods), over ``A, B, C``
(and ``D``), by the shared optimiser with the analytic Jacobian of the Rust core
(``sysid_core::pem::pem_frequency``: ``A`` held in its real modal form). One pass over the
record (the DFT of each period) replaces the passes over every sample of each iteration.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int, user_stacklevel
from .._progress import iteration_callback, iteration_printer
from ..data.iodata import IOData
from ..data.periodicity import whole_periods
from ..errors import DataError
from ..models.frd import FRD
from ..models.statespace import StateSpaceModel
from ..nonparametric.bla import bla

__all__ = ["periodic_lines", "lines_cost", "resolve_periods", "sample_variance_factor"]

CRITERION = "weighted sum of squares on the excited lines"


def periodic_lines(data: IOData, periods: Any, transient: Any = 0) -> FRD:
    """The averaged frequency response on the excited lines of periodic data, with the noise
    variance of each entry from the spread over the periods (:func:`sysid.bla`).

    Parameters
    ----------
    data : IOData
        Every experiment holds ``periods`` whole periods; with ``m`` inputs, ``m``
        experiments with different phases per realisation.
    periods : int
        Periods in each experiment.
    transient : int
        Leading periods dropped (they carry the transient); at least 2 periods must remain
        (the noise variance comes from their spread).

    Returns
    -------
    FRD
        As :func:`sysid.bla`.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = sysid.multisine(128, band=(0, 0.5), periods=3, seed=0)
    >>> g = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> y = g.simulate(np.vstack([u[-128:], u]))[128:]     # steady state from the start
    >>> from sysid.pem.periodic import periodic_lines
    >>> f = periodic_lines(sysid.IOData(u=u, y=y), periods=3)
    >>> bool(np.allclose(f.response, g.freqresp(f.omega), atol=1e-9))
    True
    """
    if not isinstance(data, IOData):
        raise DataError(f"periods= needs a sysid.IOData, got {type(data).__name__}")
    P = as_int(periods, "periods", 1)
    T = as_int(transient, "transient", 0)
    if P - T < 2:
        raise DataError(f"periods={P}, transient={T}: the noise variance on the lines comes "
                        "from the spread over the steady-state periods, so at least 2 are "
                        "needed; measure more periods, drop fewer, or leave periods out "
                        "(time-domain refinement)")
    lengths = [u.shape[0] for u, _ in data.experiments]
    bad = [n for n in lengths if n % P]
    if bad:
        raise DataError(f"periods={P} does not divide the record length {bad[0]} (samples "
                        f"per experiment {lengths}): give the number of whole periods in "
                        "each experiment, cut the record to whole periods, or pass "
                        "periods='auto'")
    return bla(data, P, transient=T)


def resolve_periods(data: IOData, periods: Any,
                    transient: Any) -> tuple[FRD | None, dict[str, Any]]:
    """The lines of ``sysid.pem``/``ssest``'s ``periods=``, ``transient=``: declared (an int;
    ``transient`` default 0, the periods are in steady state) or detected (``"auto"``,
    :func:`sysid.detect_period` on the input; ``transient`` default 1, the first period
    carries the transient; a trailing partial period is dropped). Returns the lines, or
    ``None`` when ``"auto"`` finds no period or fewer than 2 periods after the transient (the
    caller then refines in the time domain), and what ``info["pem"]["periodicity"]`` says."""
    if periods is None:
        raise DataError("transient= drops leading periods of periodic data: give periods= "
                        "(an int or 'auto') as well, or leave transient out")
    if not isinstance(data, IOData):
        raise DataError(f"periods= needs a sysid.IOData, got {type(data).__name__}")
    if not (isinstance(periods, str) and periods == "auto"):
        if isinstance(periods, str):
            raise DataError(f"periods must be an int or 'auto', got {periods!r}")
        T = 0 if transient is None else transient
        frd = periodic_lines(data, periods, T)
        return frd, {"periods": "declared", "period": frd.info["n_per"],
                     "whole_periods": frd.info["periods"], "transient": frd.info["transient"]}
    from ..data.periodicity import detect

    T = as_int(1 if transient is None else transient, "transient", 0)
    found, why = detect(data)
    info: dict[str, Any] = {"periods": "auto", "detected": found is not None, "reason": why}
    if found is None:
        info["reason"] = f"time domain: {why}"
        return None, info
    info.update(period=found.period, whole_periods=found.periods, transient=T,
                unused_samples=list(found.unused), mismatch=found.mismatch)
    if found.periods - T < 2:
        info["reason"] = (f"time domain: {why}, {found.periods - T} after the {T} transient "
                          "one(s); the noise variance needs 2 or more")
        return None, info
    if any(found.unused):
        info["reason"] = (f"{why} (the samples after them dropped: {list(found.unused)}; a "
                          "partial period)")
    return periodic_lines(whole_periods(data, found), found.periods, T), info


def line_weights(frd: FRD) -> np.ndarray:
    """Weights of the real and imaginary parts of each entry: ``2 / s2`` with ``s2`` the
    variance of the complex entry (``std**2``: for a BLA the noise variance from the periods,
    with several realisations noise plus nonlinear distortions; else ``noise_std**2``; each
    part carries half of it), the variances floored at 1e-12 of their median so that
    noise-free lines do not divide by zero. ``1/2 sum w |e|^2`` is then the negative
    log-likelihood.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.periodic import line_weights
    >>> f = sysid.FRD([1.0, 2.0], np.ones(2), std=np.array([0.5, 1.0])[:, None, None])
    >>> line_weights(f).ravel().tolist()
    [8.0, 2.0]
    """
    std = frd.std if frd.std is not None else frd.info.get("noise_std")
    if std is None or not np.all(np.isfinite(std)):
        raise DataError("the frequency-domain refinement weights each line by its noise "
                        "variance: give periodic data with periods >= 2, or an FRD with std")
    s2 = np.asarray(std, dtype=float) ** 2
    floor = 1e-12 * float(np.median(s2)) if np.any(s2 > 0) else 1.0
    return 2.0 / np.maximum(s2, max(floor, 1e-300))


def frequency_weights(frd: FRD) -> np.ndarray:
    """One weight per frequency for :func:`sysid.frd_subspace`: :func:`line_weights`
    averaged over the output/input pairs, scaled to mean 1.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.periodic import frequency_weights
    >>> f = sysid.FRD([1.0, 2.0], np.ones(2), std=np.array([0.5, 1.0])[:, None, None])
    >>> frequency_weights(f).tolist()
    [1.6, 0.4]
    """
    w = np.mean(line_weights(frd), axis=(1, 2))
    return w / w.mean()


def with_line_weights(frd: FRD) -> tuple[FRD, str]:
    """``frd`` and ``"noise"`` when it carries its lines' noise level (``std`` or
    ``info["noise_std"]``); otherwise a copy with the same unit standard deviation on every
    line and ``"uniform"``, MATLAB's default for frequency-response data (no weighting
    filter): the refinement then fits the complex response by least squares, and its
    covariance is scaled by the residual variance (one noise level for every line).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.periodic import with_line_weights
    >>> f, how = with_line_weights(sysid.FRD([1.0, 2.0], np.ones(2), dt=1.0))
    >>> how, f.std.ravel().tolist()
    ('uniform', [1.0, 1.0])
    """
    std = frd.std if frd.std is not None else frd.info.get("noise_std")
    if std is not None and np.all(np.isfinite(std)):
        return frd, "noise"
    out = FRD(frd.omega, frd.response, std=np.ones(frd.response.shape), dt=frd.dt,
              input_names=frd.input_names, output_names=frd.output_names,
              method=frd.method, info=dict(frd.info or {}))
    return out, "uniform"


def sample_variance_factor(frd: FRD, who: str) -> float:
    """Factor on the covariance ``s (J^T W J)^-1`` of a fit weighted by the variances of a
    :func:`sysid.bla` (``1/std**2``, estimated from the spread over the periods or the
    realisations, ``frd.dof`` real degrees of freedom ``nu``): ``(nu - 2) / (nu - 4)``.

    The weights and the noise on the averaged response are independent, but ``1/std**2``
    fits the lines whose noise happened to look small too closely: the estimate is noisier
    than with the true variances by ``(nu - 2) / (nu - 4)`` in variance, asymptotically in
    the number of lines (the sample maximum-likelihood estimator: Schoukens, Pintelon,
    Vandersteen and Guillaume, "Frequency-domain system identification using non-parametric
    noise models estimated from a small number of data sets", Automatica, 1997), i.e.
    ``(M - 2) / (M - 3)`` with ``M`` steady-state periods: 2 at 4 periods, 1.2 at 8, 1.08 at
    16. The residual scale ``s`` cannot see this (it is the variance of the weighted
    residuals, about ``nu / (nu - 2)`` whatever the spread of the estimate). With
    ``nu <= 4`` (3 periods or fewer, or 3 realisations or fewer) the variance has no finite
    bound: :class:`~sysid.models.uncertainty.UncertaintyWarning` says so, naming ``who``,
    and the factor is 1 (the std is then that of exactly known variances, a lower bound, too
    small by a factor that grows with the number of lines: about 1.5 with 3 periods, 2 to 3
    with 2). Other FRDs (a user's std, spectral estimates) are taken as exact: 1.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.periodic import sample_variance_factor
    >>> u = sysid.multisine(64, band=(0, 0.5), periods=4, seed=0)
    >>> y = u + 0.01 * np.random.default_rng(0).standard_normal(u.shape)
    >>> sample_variance_factor(sysid.bla(sysid.IOData(u, y, 1.0), 4), "tfest")
    2.0
    """
    if frd.method != "bla" or frd.dof is None or frd.std is None:
        return 1.0
    nu = float(frd.dof)
    if nu > 4.0:
        return (nu - 2.0) / (nu - 4.0)
    import warnings

    from ..models.uncertainty import UncertaintyWarning

    info = frd.info or {}
    r, p = int(info.get("realizations", 1)), info.get("periods", "?")
    t = int(info.get("transient", 0))
    src = (f"the spread over {r} realisations: use 4 or more (8 or more for a std within "
           "10 %)" if r > 1 else
           f"the spread over {int(nu / 2) + 1} steady-state periods (periods={p}, "
           f"transient={t}): measure 4 or more (8 or more for a std within 10 %)"
           + (" or drop fewer transient periods" if t else ""))
    warnings.warn(f"{who}: the noise variances that weight the lines come from {src}. With "
                  "3 or fewer the estimate's variance has no finite bound (sample maximum "
                  "likelihood), so the std reported is the one for exactly known variances "
                  "and too small (by about 1.5 with 3 periods, 2 to 3 with 2, more with "
                  "more lines)", UncertaintyWarning, stacklevel=user_stacklevel())
    return 1.0


def lines_cost(frd: FRD, model: Any) -> float:
    """``sum |G_model - G_k|^2 / s2`` on the lines of ``frd``: the criterion that
    ``sysid.pem(..., periods=)`` minimises, for scoring candidate models.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.periodic import lines_cost
    >>> g = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> w = np.linspace(0.1, 3.0, 8)
    >>> f = sysid.FRD(w, g.freqresp(w), std=np.full((8, 1, 1), 0.1), dt=1.0)
    >>> lines_cost(f, g) < 1e-20 < lines_cost(f, sysid.StateSpaceModel([[0.4]], [[1.0]], [[1.0]]))
    True
    """
    e = model.freqresp(frd.omega) - frd.response
    return float(0.5 * np.sum(line_weights(frd) * np.abs(e) ** 2))


def pem_lines(frd: FRD, model: StateSpaceModel, *, feedthrough: bool, max_iter: int,
              tol: float, progress: bool | None | Callable[..., Any],
              stabilize: Callable[[np.ndarray], np.ndarray]) -> tuple[dict[str, Any], Any]:
    """Runs the core's frequency-domain refinement of ``model`` on the lines of ``frd``;
    returns the core's dict and what :func:`sysid.pem` reports beside it (internal: called by
    :func:`sysid.pem` with ``periods=`` or an FRD)."""
    if frd.dt is None:
        raise DataError("the lines need the sample time (frd.dt) to place e^{j w dt}")
    if frd.n_inputs != model.ninputs or frd.n_outputs != model.noutputs:
        raise DataError(f"the model has {model.ninputs} input(s) and {model.noutputs} "
                        f"output(s) but the data have {frd.n_inputs} and {frd.n_outputs}")
    nk = frd.omega.size
    g = frd.response.reshape(nk, -1)
    A = model.A.copy()
    stabilized = None
    if model.nstates and np.max(np.abs(np.linalg.eigvals(A))) >= 1.0:
        A = stabilize(A)
        stabilized = "unstable poles of A reflected into the unit circle"
    D = model.D.copy() if feedthrough else np.zeros_like(model.D)
    cb, close_bar = iteration_callback(progress, "pem", max_iter,
                                       iteration_printer("pem", CRITERION))
    try:
        res = _sysid.pem_frequency_refine(
            np.ascontiguousarray(A), np.ascontiguousarray(model.B),
            np.ascontiguousarray(model.C), np.ascontiguousarray(D),
            np.ascontiguousarray(frd.omega * float(frd.dt)), np.ascontiguousarray(g.real),
            np.ascontiguousarray(g.imag), np.ascontiguousarray(line_weights(frd).reshape(nk, -1)),
            estimate_d=bool(feedthrough), max_iter=max_iter, tol_cost=tol, progress=cb)
    finally:
        close_bar()
    factor = sample_variance_factor(frd, "pem")
    res["covariance"] = np.asarray(res["covariance"]) * factor
    extra = {"domain": "frequency", "lines": int(nk), "periods": frd.info.get("periods"),
             "n_residuals": int(res["n_residuals"]),
             "residual_scale": float(res["residual_scale"]), "sample_variance_factor": factor,
             "modal": bool(res["modal"]),
             "stabilized": stabilized}
    return res, extra
