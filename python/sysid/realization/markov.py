"""Markov parameters (impulse responses) estimated from input/output data.

- :func:`impulse_response`: least-squares FIR, optionally regularised with a TC kernel whose
  hyperparameters are tuned by marginal likelihood (as MATLAB's ``impulseest`` does);
- :func:`okid` (Juang, Phan, Horta and Longman 1993): observer Markov parameters from a short
  ARX regression, then the system's, for lightly damped systems and arbitrary inputs;
- :func:`impulse_from_frf`: the inverse FFT of a frequency response on the FFT grid.

Each returns a :class:`~sysid.MarkovEstimate` shaped ``(count, noutputs, ninputs)``, which
:func:`sysid.era` realises (``est.era(order)``). The numerics run in the Rust core.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import check_elements, require_inputs_vary, user_stacklevel
from ..data.iodata import IOData
from ..errors import DataError, ExcitationError, NonFiniteError, ShapeError, SysidWarning
from ..pem.sandwich import _ar_fit
from .realize import MarkovEstimate, _count

__all__ = ["impulse_response", "okid", "impulse_from_frf"]


def _experiments(data: Any, who: str) -> tuple[list[tuple[np.ndarray, np.ndarray]], float]:
    if not isinstance(data, IOData):
        raise DataError(f"data must be a sysid.IOData, got {type(data).__name__}; "
                        "wrap arrays with sysid.IOData(u, y, dt)")
    exps = data.experiments
    if exps[0][0].shape[1] == 0:
        raise DataError("Markov parameters need inputs: this IOData has none")
    # a constant input cannot be told from the FIR's missing constant term: its Markov
    # parameters would be meaningless
    require_inputs_vary(exps, who, data.input_names, error=ExcitationError)
    from ..data.offsets import check_offsets

    # Markov parameters have neither a constant term nor an initial state: an offset costs
    # them what it costs a model simulated from rest (the dryer and heating-system records:
    # ERA of order 2 validated 39 and 34 % raw against 81 and 66 % detrended, while the
    # quick fit from measured samples lost nothing); the means removed inside would not
    # help either: the model still lacks the offset when it meets raw data
    check_offsets(data, from_rest=True,
                  fix="Markov parameters carry neither a constant term nor an initial state")
    return [(np.asarray(u, dtype=float), np.asarray(y, dtype=float)) for u, y in exps], data.dt


def _feedthrough(data: IOData, value: Any) -> bool:
    """``feedthrough`` as a bool: ``"auto"`` decided by the rule every estimator shares."""
    from ..subspace.estimator import SubspaceEstimator
    from ..subspace.feedthrough import check_feedthrough, choose_feedthrough

    if check_feedthrough(value) == "auto":
        return choose_feedthrough(SubspaceEstimator(data))[0]
    return bool(value)


#: the longest default FIR of :func:`impulse_response` (as MATLAB's ``impulseest`` default)
DEFAULT_LENGTH = 70
#: the most coefficients per output the default lengthens to when the response has not
#: decayed at ``DEFAULT_LENGTH`` (the TC tuning's SVDs are of this size, about a second)
LONGEST_DEFAULT = 400


def _tail(out: dict[str, Any], l: int, m: int) -> float | None:
    """The largest share of its pair's peak that the last tenth of the Markov parameters
    holds (root mean square), where it is also 3 standard deviations above zero and above
    5 %; None when every pair has decayed."""
    h = np.asarray(out["markov"]).reshape(-1, l, m)
    sd = np.asarray(out["std"]).reshape(-1, l, m)
    k = max(3, h.shape[0] // 10)
    if h.shape[0] < 2 * k:
        return None
    rms = np.sqrt(np.mean(h[-k:] ** 2, axis=0))
    noise = np.sqrt(np.mean(sd[-k:] ** 2, axis=0))
    peak = np.max(np.abs(h), axis=0)
    share = np.where(peak > 0, rms / np.where(peak > 0, peak, 1.0), 0.0)
    bad = (share > 0.05) & (rms > 3.0 * noise)
    return float(share[bad].max()) if np.any(bad) else None


def default_length(exps: list[tuple[np.ndarray, np.ndarray]]) -> tuple[int, str]:
    """The FIR length :func:`impulse_response` takes when none is given, and why: the
    input's order of persistent excitation (:func:`sysid.persistent_excitation_order`, up to
    ``DEFAULT_LENGTH``), at most a quarter of the samples per input (the regression keeps
    four samples per coefficient), at least 1.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.realization.markov import default_length
    >>> u = np.random.default_rng(0).standard_normal((1000, 1))
    >>> default_length([(u, u)])[0], default_length([(u[:100], u[:100])])[0]
    (70, 25)
    """
    from ..data.input_design import persistent_excitation_order

    m = exps[0][0].shape[1]
    total = sum(u.shape[0] for u, _ in exps)
    pe = persistent_excitation_order([u for u, _ in exps], DEFAULT_LENGTH)
    cap = max(1, total // (4 * m))
    n = max(1, min(pe, cap))
    why = (f"{n} Markov parameters: the input is persistently exciting of order "
           f"{'>= ' if pe >= DEFAULT_LENGTH else ''}{pe}"
           + (f", and {total} samples of {m} input(s) support {cap}" if cap < pe else "")
           + f" (at most {DEFAULT_LENGTH}; pass length= for another)")
    return n, why


def impulse_response(data: IOData, length: int | None = None, *,
                     regularization: str | None = "tc",
                     hyper: tuple[float, float] | None = None,
                     feedthrough: bool | str = False,
                     prewhiten: bool = True) -> MarkovEstimate:
    """Markov parameters by least-squares FIR, optionally TC-regularised.

    Fits ``y(t) = sum_{k<length} h_k u(t-k) + e(t)`` over all experiments of ``data`` (means
    are not removed: detrend first if needed; an ``OffsetWarning`` says when). The record is
    compressed once into a triangular factor; tuning the TC kernel then costs about 30
    eigendecompositions of size ``length * ninputs``, so for very long responses (lightly
    damped systems sampled fast) :func:`okid` is the cheaper route.

    Parameters
    ----------
    data : IOData
        Input/output record(s).
    length : int, optional
        Number of Markov parameters ``h_0 .. h_{length-1}``. Default (MATLAB's
        ``impulseest(data)``): from the input's order of persistent excitation, at most 70
        and a quarter of the samples per input (:func:`default_length`; the reason in
        ``info["length"]``), lengthened (up to 400 coefficients per output) when the
        response runs on past it. A response that has not decayed (its last tenth above 5 %
        of its peak and 3 standard deviations) is said with a warning: its step and DC gain
        would be truncated.
    regularization : {"tc", None}
        ``"tc"``: prior ``E[h_k h_j] = c lambda^max(k, j)`` (per output, inputs scaled to unit
        variance), hyperparameters by marginal likelihood unless ``hyper`` fixes them;
        ``None``: plain least squares.
    hyper : (float, float), optional
        Fixed TC ``(c, lambda)`` for unit-variance inputs.
    feedthrough : bool or "auto"
        Estimate ``h_0 = D``; if False (the default, as every sysid state-space estimator)
        it is zero. ``"auto"``: decided from the data
        (:func:`sysid.subspace.feedthrough.choose_feedthrough`).
    prewhiten : bool
        When the FIR's residuals of an output are coloured (an AR model of order 1 to
        ``PREWHITEN_MAX`` chosen by BIC over order 0), fit that output again with its input
        and output filtered by the AR polynomial ``A(q)``: the residuals are then white, as
        the standard deviations (and the TC prior's likelihood) assume. Without it, coloured
        output noise makes ``info["std"]`` wrong, too large or too small depending on the
        input's spectrum. ``info["prewhitening"]`` lists each output's ``A`` (``[1.0]``:
        white residuals, the fit unchanged). Not done when the response has not decayed
        within ``length`` (the warning below): the residuals then hold the truncated tail,
        which the filter would turn into bias.

    Returns
    -------
    MarkovEstimate

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(400)
    >>> data = sysid.IOData(u, true.simulate(u) + 0.01 * rng.standard_normal((400, 1)))
    >>> est = sysid.impulse_response(data, 30)
    >>> bool(np.allclose(est.markov[:5, 0, 0], true.markov(5)[:, 0, 0], atol=0.01))
    True
    """
    exps, dt = _experiments(data, "impulse_response")
    n = _count(length, "length")
    why = None
    if n is None:
        n, why = default_length(exps)
    if regularization not in ("tc", None):
        raise DataError(f"regularization must be 'tc' or None, got {regularization!r}")
    ft = _feedthrough(data, feedthrough)
    out = _sysid.fir(exps, n, ft, regularization or "none", hyper)
    l, m = exps[0][1].shape[1], exps[0][0].shape[1]
    tail = _tail(out, l, m)
    if why is not None and tail is not None:
        # the response runs on past the default length (a slow or oversampled system):
        # as long as the tuning allows
        total = sum(u.shape[0] for u, _ in exps)
        longer = min(LONGEST_DEFAULT // m, total // (4 * m))
        if longer > n:
            out = _sysid.fir(exps, longer, ft, regularization or "none", hyper)
            why += (f"; lengthened to {longer} (the last tenth of {n} lags still held "
                    f"{100 * tail:.0f} % of the peak)")
            n = longer
            tail = _tail(out, l, m)
    if tail is not None:
        warnings.warn(
            f"impulse_response: the response has not decayed within its {n} Markov "
            f"parameters (their last tenth holds {100 * tail:.0f} % of the peak, well above "
            "their standard deviation): its step, DC gain and any model realised from it are "
            "truncated; pass a longer length=, decimate the record (sysid.decimate), or use "
            "sysid.okid or a parametric model (sysid.n4sid)", SysidWarning,
            stacklevel=user_stacklevel())
    h = np.asarray(out["markov"]).reshape(-1, l, m)
    info = {k: out[k] for k in ("scale", "decay", "noise_variance", "samples")}
    info["std"] = np.asarray(out["std"]).reshape(-1, l, m)
    if prewhiten and tail is None:  # a truncated FIR's residuals hold its missing tail
        h = _prewhitened(exps, h, info, ft, regularization or "none", hyper)
    if why is not None:
        info["length"] = why
    return MarkovEstimate(h, dt, "fir-tc" if regularization else "fir", info,
                          input_names=data.input_names, output_names=data.output_names)


#: the highest order of the AR filter that whitens the FIR's residuals
PREWHITEN_MAX = 10


def _fir_residuals(exps: list[tuple[np.ndarray, np.ndarray]], h: np.ndarray,
                   j: int) -> list[np.ndarray]:
    """Output ``j``'s residuals ``y - sum_k h_k u(t - k)`` of each experiment, over the
    samples the regression used (all ``len(h) - 1`` lags measured)."""
    n = h.shape[0]
    out = []
    for u, y in exps:
        fit = sum(np.convolve(u[:, i], h[:, j, i])[:u.shape[0]] for i in range(u.shape[1]))
        out.append((y[:, j] - fit)[n - 1:])
    return out


def _prewhitened(exps: list[tuple[np.ndarray, np.ndarray]], h: np.ndarray,
                 info: dict[str, Any], ft: bool, reg: str,
                 hyper: tuple[float, float] | None) -> np.ndarray:
    """The FIR refitted, output by output, on data filtered by the AR polynomial that whitens
    that output's residuals (the sandwich covariances' autoregression, its order by BIC);
    updates ``info`` (``std``, ``scale``, ``decay``, ``prewhitening``) and returns the
    Markov parameters. A generalised least squares step: with ``y = H u + v`` and
    ``A(q) v = e`` white, ``A y = H (A u) + e``."""
    n, l, _ = h.shape
    shortest = min(u.shape[0] for u, _ in exps)
    top = min(PREWHITEN_MAX, max(0, (shortest - n) // 20))
    h = h.copy()
    polys = []
    for j in range(l):
        res = [r for r in _fir_residuals(exps, h, j) if r.size > 2 * top + 1]
        ar = _ar_fit(res, top, penalty=np.log(sum(r.size for r in res)))[0] if (
            top and res) else []
        a = np.r_[1.0, -np.asarray(ar, float)]
        polys.append(a)
        if a.size == 1:
            continue
        p = a.size - 1
        filt = [(np.column_stack([np.convolve(u[:, i], a)[p:u.shape[0]]
                                  for i in range(u.shape[1])]),
                 np.convolve(y[:, j], a)[p:y.shape[0]][:, None]) for u, y in exps]
        out = _sysid.fir(filt, n, ft, reg, hyper)
        h[:, j, :] = np.asarray(out["markov"]).reshape(n, 1, -1)[:, 0, :]
        info["std"][:, j, :] = np.asarray(out["std"]).reshape(n, 1, -1)[:, 0, :]
        for key in ("scale", "decay"):
            info[key] = np.array(info[key], dtype=float)
            info[key][j] = np.asarray(out[key])[0]
    info["prewhitening"] = polys
    return h


def okid(data: IOData, observer_order: int, count: int | None = None, *,
         feedthrough: bool | str = False) -> MarkovEstimate:
    """Observer/Kalman filter identification of Markov parameters.

    Regresses ``y(t)`` on ``u(t)`` and ``observer_order`` past inputs and outputs (the
    observer Markov parameters), then recovers the system's Markov parameters, as many as
    wanted, by the OKID recursion. A short observer captures a lightly damped system, with
    any input and noise in innovation form.

    Parameters
    ----------
    data : IOData
        Input/output record(s).
    observer_order : int
        Lags p of the regression; ``p * noutputs`` should exceed the expected order.
    count : int, optional
        Markov parameters returned (default ``4 * observer_order + 1``); a count whose
        arrays would exceed the size limit of one call raises a DataError.
    feedthrough : bool or "auto"
        Estimate ``h_0 = D``; if False (the default, as every sysid state-space estimator)
        it is zero. ``"auto"``: decided from the data
        (:func:`sysid.subspace.feedthrough.choose_feedthrough`).

    Returns
    -------
    MarkovEstimate
        ``info["observer_markov"]`` is ``(p, l, m + l)``; ``info["residual_cov"]`` the
        covariance of the one-step prediction errors.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(1)
    >>> true = sysid.StateSpaceModel([[0.95, 0.25], [-0.25, 0.95]], [[1.0], [0.0]], [[1.0, 0.0]])
    >>> u = rng.standard_normal(2000)
    >>> data = sysid.IOData(u, true.simulate(u) + 0.05 * rng.standard_normal((2000, 1)))
    >>> r = sysid.okid(data, observer_order=10, count=60).era(order=2)
    >>> bool(np.allclose(np.sort(np.abs(r.model.poles())), np.abs(true.poles()), atol=0.01))
    True
    """
    exps, dt = _experiments(data, "okid")
    p = _count(observer_order, "observer_order")
    if p is None:
        raise DataError("observer_order is required: the number of past samples in the observer")
    c = _count(count, "count") or 4 * p + 1
    l, m = exps[0][1].shape[1], exps[0][0].shape[1]
    # the recursion keeps about 3 (l, m + l) and one (l, m) blocks per Markov parameter
    check_elements(c * (3 * l * (m + l) + l * m), f"count = {c}",
                   "pass a count of the order of the response's length in samples")
    ft = _feedthrough(data, feedthrough)
    # the default: said when the record shows a direct term (the regression with u(t) from
    # the same triangular factor)
    out = _sysid.okid(exps, p, c, ft, check_direct=feedthrough is False)
    if feedthrough is False:
        _warn_direct_term(exps, out, l, m)
    h = np.asarray(out["markov"]).reshape(-1, l, m)
    info = {
        "observer_markov": np.asarray(out["observer_markov"]).reshape(-1, l, m + l),
        "residual_cov": np.asarray(out["residual_cov"]),
        "samples": out["samples"],
        "observer_order": p,
    }
    return MarkovEstimate(h, dt, "okid", info, input_names=data.input_names,
                          output_names=data.output_names)


#: how many standard deviations (and how large a share of the largest Markov parameter) the
#: estimated direct term must reach for :func:`okid` to say it left one out
DIRECT_TERM_SIGMAS, DIRECT_TERM_SHARE = 10.0, 0.05


def _warn_direct_term(exps: list[tuple[np.ndarray, np.ndarray]], out: dict[str, Any],
                      l: int, m: int) -> None:
    """A :class:`~sysid.FeedthroughWarning` when the observer regression with ``u(t)``
    (``out["direct"]``, solved from the same triangular factor) estimates ``D`` far from
    zero: more than ``DIRECT_TERM_SIGMAS`` rough standard deviations (residual std over
    ``sqrt(N var u)``, as if ``u(t)`` were uncorrelated with the past) and
    ``DIRECT_TERM_SHARE`` of the largest Markov parameter of the fit without it
    (``out["markov"]``). Acceleration records have a
    direct term, and ``D = 0`` then bends every Markov parameter (a 3-mass structure's ERA
    model came back unstable at the wrong frequency)."""
    from ..errors import FeedthroughWarning

    d = np.asarray(out["direct"]).reshape(l, m)
    h = np.asarray(out["markov"]).reshape(-1, l, m)
    lam = np.clip(np.diag(np.atleast_2d(out["direct_residual_cov"])), 0.0, None)
    u = np.vstack([x for x, _ in exps])
    su = np.sqrt(u.shape[0] * np.maximum(u.var(axis=0), 1e-300))
    sd = np.sqrt(lam)[:, None] / su[None, :]
    big = (np.abs(d) > DIRECT_TERM_SIGMAS * sd) & (np.abs(d) > DIRECT_TERM_SHARE
                                                   * max(float(np.abs(h).max()), 1e-300))
    if np.any(big):
        warnings.warn(FeedthroughWarning(
            f"the record shows a direct term (D estimated at up to "
            f"{float(np.abs(d[big]).max()):.3g}, against Markov parameters up to "
            f"{float(np.abs(h).max()):.3g}): with D = 0 every Markov parameter is biased; pass "
            "feedthrough=True (acceleration sensors have one) or feedthrough='auto'"),
            stacklevel=user_stacklevel())


def impulse_from_frf(frf: Any, n_fft: int | None = None, *, dt: float | None = None,
                     fill_missing: bool = False) -> MarkovEstimate:
    """Markov parameters as the inverse FFT of a frequency response on the FFT grid.

    For a record of ``n_fft`` samples in periodic steady state (a periodic input, the
    transient dropped), the ETFE ``Y/U`` at ``omega_k = 2 pi k / (n_fft dt)`` is exact, and
    its inverse FFT is the impulse response folded over one period,
    ``sum_j h_{k + j n_fft}``, which equals ``h_k`` once the response has decayed within a
    period. ERA then realises it (the approach of seed 001: ETFE, inverse FFT, ERA).

    Parameters
    ----------
    frf : FRD or array_like
        A :class:`sysid.FRD` (e.g. from :func:`sysid.etfe`) or a complex array
        ``(n_fft // 2 + 1, noutputs, ninputs)`` on the full grid from 0 to the Nyquist
        frequency.
    n_fft : int, optional
        Length of the period; taken from the FRD (``info["n_fft"]``) if omitted. A length
        whose arrays would exceed the size limit of one call raises a DataError.
    dt : float, optional
        Sample time; taken from the FRD if omitted, else 1.
    fill_missing : bool
        Set bins absent from the FRD (unexcited lines) to zero instead of raising; the
        impulse response is then band-limited.

    Returns
    -------
    MarkovEstimate
        ``n_fft`` Markov parameters (method ``"ifft"``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> true = sysid.StateSpaceModel([[0.8, 0.3], [-0.3, 0.8]], [[1.0], [0.0]], [[1.0, 1.0]])
    >>> u = np.tile(np.random.default_rng(0).standard_normal(256), 2)
    >>> y = true.simulate(u)
    >>> frd = sysid.etfe(sysid.IOData(u[256:], y[256:]))   # one period in steady state
    >>> est = sysid.impulse_from_frf(frd)
    >>> bool(np.allclose(est.markov[:50], true.markov(50), atol=1e-10))
    True
    """
    omega = None
    if hasattr(frf, "response") and hasattr(frf, "omega"):
        omega = np.asarray(frf.omega, dtype=float)
        if dt is None:
            dt = getattr(frf, "dt", None)
        if n_fft is None:
            n_fft = (getattr(frf, "info", None) or {}).get("n_fft")
        g = np.asarray(frf.response)
    else:
        g = np.asarray(frf)
    if g.ndim == 1:
        g = g[:, None, None]
    if g.ndim != 3:
        raise ShapeError(
            f"the frequency response must be (n_freq, noutputs, ninputs), got {g.shape}")
    if not np.isfinite(g).all():
        raise NonFiniteError("the frequency response has non-finite values (NaN or Inf)")
    dt = float(dt if dt is not None else 1.0)
    if n_fft is None:
        if omega is not None:
            raise DataError("n_fft is required: the FRD does not record its FFT length")
        n_fft = 2 * (g.shape[0] - 1)
    n_fft = _count(n_fft, "n_fft")
    assert n_fft is not None
    # the one-sided response (complex, 2 values a bin) and the n_fft impulse response
    check_elements(2 * n_fft * g.shape[1] * g.shape[2], f"n_fft = {n_fft}",
                   "pass the length of one period of the record (the FRD's n_fft)")
    nf = n_fft // 2 + 1
    full = np.zeros((nf,) + g.shape[1:], dtype=complex)
    if omega is None:
        if g.shape[0] != nf:
            raise ShapeError(f"a frequency response for n_fft = {n_fft} needs {nf} bins, got "
                             f"{g.shape[0]}")
        full[:] = g
    else:
        k = omega * n_fft * dt / (2 * np.pi)
        idx = np.rint(k).astype(int)
        if np.any(np.abs(k - idx) > 1e-6) or np.any(idx < 0) or np.any(idx >= nf):
            raise DataError("the FRD frequencies are not on the FFT grid of n_fft samples; "
                            "use an unsmoothed ETFE of one period (or pass n_fft)")
        full[idx] = g
        missing = np.setdiff1d(np.arange(nf), idx)
        if missing.size and not fill_missing:
            raise DataError(
                f"{missing.size} of the {nf} FFT bins are missing from the FRD (unexcited "
                "lines?); excite the whole band, or pass fill_missing=True for a band-limited "
                "impulse response")
    h = np.fft.irfft(full, n=n_fft, axis=0)
    return MarkovEstimate(h, dt, "ifft", {"samples": n_fft},
                          input_names=getattr(frf, "input_names", None),
                          output_names=getattr(frf, "output_names", None))
