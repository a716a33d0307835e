r"""Autoregressive models ``A(q) y(t) = e(t)`` of time series, four ways.

With ``A(q) = 1 + a_1 q^-1 + ... + a_n q^-n``:

* ``"yw"`` (Yule-Walker): solve the Toeplitz system ``R a = -r`` of the biased sample
  autocovariances ``r_k = 1/N sum_t y(t) y(t+k)`` (the signal windowed by zeros);
* ``"burg"``: reflection coefficients ``k_m = -2 sum f b / sum (f^2 + b^2)`` of the forward
  and backward prediction errors, order by order (Levinson recursion), so the model is always
  stable;
* ``"ls"``: least squares of the forward prediction errors over the samples where all lags
  are measured (no windowing);
* ``"fb"`` (MATLAB's default): least squares of the forward and backward prediction errors
  together.

Several experiments are used together (their sums pooled). The mean is not removed (as in
MATLAB's ``ar``): detrend first. The reported covariance of ``a`` is the asymptotic one,
``lambda (Phi^T Phi)^-1`` with ``Phi`` the forward regressors and ``lambda`` the innovation
variance, the same for every method (they share their asymptotic distribution).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int, experiment_arrays, require_inputs_vary
from ..errors import DataError, InsufficientDataError

_METHODS = ("burg", "yw", "ls", "fb")


def _series(data: Any, na: int, name: str) -> tuple[list[np.ndarray], float]:
    """One 1-D float array per experiment, and the sample time."""
    from ..data.iodata import IOData

    if not isinstance(data, IOData):
        arr = np.asarray(data)
        if arr.dtype.kind not in "biuf" or arr.ndim not in (1, 2) or (
                arr.ndim == 2 and arr.shape[1] != 1):
            raise DataError(f"{name}: y must be an IOData record without inputs or a 1-D "
                            f"array (one channel), got {arr.dtype} array of shape {arr.shape}")
        data = IOData(None, arr.reshape(-1, 1).astype(float), 1.0)
    exps = experiment_arrays(data)
    if exps[0][0].shape[1] != 0:
        raise DataError(f"{name} models time series: pass data without inputs "
                        "(IOData(None, y)); for input/output data use arx/armax")
    if exps[0][1].shape[1] != 1:
        raise DataError(f"{name} models one channel; the data have {exps[0][1].shape[1]} "
                        "outputs: fit one per channel, or sysid.n4sid(data, order) for a "
                        "multichannel state-space time-series model")
    require_inputs_vary(exps, name, getattr(data, "output_names", None), side=1)
    ys = [y[:, 0] for _, y in exps]
    if min(y.size for y in ys) <= 2 * na:
        raise InsufficientDataError(
            f"{name} of order {na} needs more than {2 * na} samples in every experiment, got "
            f"{min(y.size for y in ys)}; use a lower order or a longer record")
    return ys, float(data.dt)


def _forward(ys: list[np.ndarray], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Stacked forward regressors ``[-y(t-1) .. -y(t-n)]`` and targets ``y(t)``, t >= n."""
    Phi = np.vstack([-np.column_stack([y[n - k:y.size - k] for k in range(1, n + 1)])
                     for y in ys])
    return Phi, np.concatenate([y[n:] for y in ys])


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """``a . b`` of two long vectors in one thread (``einsum``: a multi-threaded BLAS ``ddot``
    on a loaded machine was measured 1000 times slower, 17 ms for 10^5 samples)."""
    return float(np.einsum("i,i->", a, b))


def _gram(ys: list[np.ndarray], n: int) -> np.ndarray:
    """``Phi^T Phi`` of the forward regressors of :func:`_forward` from lagged sums:
    ``G[i, j] = sum_t y(t-1-i) y(t-1-j)`` over ``t = n..N-1``."""
    G = np.empty((n, n))
    for i in range(n):
        for j in range(i, n):
            G[i, j] = G[j, i] = sum(_dot(y[n - 1 - i:y.size - 1 - i], y[n - 1 - j:y.size - 1 - j])
                                    for y in ys)
    return G


def _yule_walker(ys: list[np.ndarray], n: int) -> np.ndarray:
    from scipy.linalg import solve_toeplitz

    N = sum(y.size for y in ys)
    r = np.array([sum(_dot(y[: y.size - k], y[k:]) for y in ys) for k in range(n + 1)]) / N
    if r[0] <= 0:
        raise DataError("the signal is identically zero; nothing to model")
    return np.asarray(solve_toeplitz(r[:n], -r[1:]))


def _burg(ys: list[np.ndarray], n: int) -> np.ndarray:
    f = [y.copy() for y in ys]
    b = [y.copy() for y in ys]
    a = np.ones(1)
    for m in range(1, n + 1):
        num = sum(_dot(fi[m:], bi[m - 1:-1]) for fi, bi in zip(f, b))
        den = sum(_dot(fi[m:], fi[m:]) + _dot(bi[m - 1:-1], bi[m - 1:-1]) for fi, bi in zip(f, b))
        if den <= 0:
            if m == 1:
                raise DataError("the signal is identically zero; nothing to model")
            raise DataError(f"the signal is predicted exactly by an AR model of order {m - 1} "
                            "(a deterministic sequence: its prediction errors vanish), so "
                            f"higher orders are not determined; use order {m - 1}")
        k = -2.0 * num / den
        a = np.r_[a, 0.0] + k * np.r_[a, 0.0][::-1]
        for fi, bi in zip(f, b):
            fn, bn = fi[m:] + k * bi[m - 1:-1], bi[m - 1:-1] + k * fi[m:]
            fi[m:], bi[m:] = fn, bn
    return a[1:]


def _least_squares(ys: list[np.ndarray], n: int, backward: bool) -> np.ndarray:
    Phi, t = _forward(ys, n)
    if backward:  # y(t) = -sum a_k y(t+k) + e: the time-reversed signal, same coefficients
        Pb, tb = _forward([y[::-1] for y in ys], n)
        Phi, t = np.vstack([Phi, Pb]), np.r_[t, tb]
    sol, _, rank, _ = np.linalg.lstsq(Phi, t, rcond=None)
    if rank < n:
        raise DataError(f"the lagged signal has rank {rank} < {n}: the series is too regular "
                        "for this order (a constant or a pure sinusoid); use a lower order")
    return np.asarray(sol)


def ar(data: Any, na: int, method: str = "fb", *, dt: float | None = None) -> Any:
    """Autoregressive model ``A(q) y(t) = e(t)`` of a time series (MATLAB's ``ar``).

    Parameters
    ----------
    data : IOData without inputs, or array_like (n_samples,)
        The series (several experiments are pooled). Not detrended here.
    na : int
        Order of ``A``.
    method : {"fb", "burg", "yw", "ls"}
        Forward-backward least squares (default, as MATLAB), Burg, Yule-Walker, or forward
        least squares; see :mod:`sysid.timeseries.ar`.
    dt : float, optional
        Sample time when ``data`` is an array (default 1). With a record it may only repeat
        the record's own ``dt``; another value is a :class:`~sysid.DataError`.

    Returns
    -------
    PolynomialModel
        ``a`` with ``noise_variance`` (the one-step prediction errors over the samples with
        all lags measured, their sum of squares divided by their number less the ``na``
        parameters: unbiased), ``covariance`` and ``uncertainty`` (``model.std``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> y = signal.lfilter([1], [1, -1.5, 0.7], np.random.default_rng(0).standard_normal(5000))
    >>> m = sysid.ar(y, 2, "burg")
    >>> np.round(m.a[0][0], 2)
    array([-1.5,  0.7])
    >>> bool(np.all(np.abs(m.a[0][0] - [-1.5, 0.7]) < 3 * m.std["a"][0][0]))
    True
    """
    from ..polynomial.model import PolynomialModel
    from ..polynomial.uncertainty import attach_uncertainty as _attach_uncertainty

    if method not in _METHODS:
        raise DataError(f"method must be one of {', '.join(map(repr, _METHODS))}, got "
                        f"{method!r}")
    if isinstance(na, str):  # "auto": MATLAB's ar has no automatic order either
        raise DataError(f"ar takes its order as a whole number, got {na!r}: compare orders "
                        "with sysid.selstruc(sysid.arxstruc(est, val, sysid.struc(range(1, "
                        "21)))) on an estimation and a validation part of the series")
    na = as_int(na, "na", 1)
    ys, dt0 = _series(data, na, "ar")
    from ..data.iodata import IOData
    from ..data.offsets import check_offsets

    # the one offset check every estimator runs (an AR model has no constant term either)
    check_offsets(IOData(None, [y[:, None] for y in ys] if len(ys) > 1 else ys[0][:, None],
                         dt0, output_names=getattr(data, "output_names", None)))
    if dt is not None:
        from .._checks import as_dt

        given = as_dt(dt)
        if isinstance(data, IOData) and abs(given - dt0) > 1e-12 * max(given, dt0):
            # the record's own sample time was silently replaced: every frequency of the
            # model (its spectrum, its poles in rad/s) moved by the ratio
            raise DataError(f"ar: dt = {given:g} s disagrees with the record's dt = {dt0:g} s; "
                            "an IOData record carries its own sample time: leave dt out (it "
                            "is for arrays), or rebuild the record with the right dt")
        dt0 = given
    if method == "yw":
        a = _yule_walker(ys, na)
    elif method == "burg":
        a = _burg(ys, na)
    else:
        a = _least_squares(ys, na, method == "fb")
    from scipy.signal import lfilter

    # residuals A(q) y and the Gram matrix of the forward regressors, without forming them
    res = np.concatenate([lfilter(np.r_[1.0, a], [1.0], y)[na:] for y in ys])
    lam = _dot(res, res) / max(res.size - na, 1)
    cov = lam * np.linalg.pinv(_gram(ys, na))
    m = PolynomialModel([[a]], [[]], np.zeros((1, 0), int), dt0, noise_variance=[lam])
    m.output_names = getattr(data, "output_names", None)  # the data's channel name
    m.info = {"method": f"ar ({method})", "loss": [lam]}
    m.covariance = [cov]  # type: ignore[attr-defined]
    m.parameters = [a]  # type: ignore[attr-defined]
    _attach_uncertainty(m, [cov], "arx", "asymptotic")
    return m


def arma(data: Any, na: int, nc: int, *, max_iter: int = 100,
         initial_condition: str = "auto") -> Any:
    """ARMA model ``A(q) y(t) = C(q) e(t)`` of a time series by prediction-error
    minimisation (the shared Gauss-Newton optimiser; MATLAB's ``armax`` without input).

    Parameters
    ----------
    data : IOData without inputs, or array_like (n_samples,)
        The series (several experiments are used together).
    na, nc : int
        Orders of ``A`` and ``C``.
    max_iter : int
        Iteration limit of the search.
    initial_condition : {"auto", "zero", "estimate"}
        MATLAB's ``InitialCondition``, ``"auto"`` (default), ``"zero"`` or ``"estimate"``
        (:mod:`sysid.polynomial.initial`; the series before the record, one state per
        experiment).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> y = signal.lfilter([1, 0.5], [1, -0.7], np.random.default_rng(1).standard_normal(4000))
    >>> m = sysid.arma(y, 1, 1)
    >>> np.round([m.a[0][0][0], m.c[0][0]], 1)
    array([-0.7,  0.5])

    A noise-free series that starts off rest (the free response of ``A``):

    >>> y = signal.lfilter([1.0], [1, -1.5, 0.7, -0.1], np.r_[1.0, -0.3, 0.4, np.zeros(97)])
    >>> m = sysid.arma(y, 3, 1)
    >>> m.info["initial_condition"], np.round(m.a[0][0], 12), np.round(m.c[0], 12)
    ('estimate', array([-1.5,  0.7, -0.1]), array([0.]))
    """
    from ..data.iodata import IOData
    from ..polynomial.estimators import _pem
    from ..polynomial.initial import check as _check_initial

    na_i, nc_i = as_int(na, "na", 0), as_int(nc, "nc", 0)
    if na_i + nc_i == 0:
        raise DataError("arma needs na + nc >= 1")
    _check_initial(initial_condition)
    if not isinstance(data, IOData):
        ys, _ = _series(data, na_i + nc_i, "arma")
        data = IOData(None, ys[0][:, None], 1.0)
    else:
        _series(data, na_i + nc_i, "arma")
    return _pem(data, na_i, 0, nc_i, 0, 0, 0, "arma", max_iter, None,
                initial_condition=initial_condition)
