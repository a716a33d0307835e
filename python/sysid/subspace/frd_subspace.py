"""Subspace identification from frequency-response data, discrete or continuous time.

:func:`frd_subspace` implements the frequency-domain subspace algorithm of McKelvey, Akçay &
Ljung (1996) in the Rust core: the responses ``G_k`` at ``z_k = e^{j ω_k dt}`` are stacked
as ``[G_k; z_k G_k; ...; z_k^{q-1} G_k]``, the known input part ``[I; z_k I; ...]`` is
projected out (LQ factorisation of the real and imaginary parts side by side), the SVD gives
the extended observability matrix, A and C follow by shift invariance and B, D by weighted
linear least squares on ``G_k``. Exact data give the system to round-off; with noisy data
the estimate converges as the number of frequencies grows.

Continuous time (``continuous=True``) goes through the bilinear map: the frequencies are
warped, ``ω_d = 2 atan(ω T / 2)``, a discrete model with sample time ``T`` is identified and
mapped back with Tustin's rule (:func:`sysid.d2c`), which is exact for this map: the result
is a :class:`sysid.ContinuousStateSpace` whose response equals the discrete one at the
warped frequencies.

The SVD and the least squares for B and D weigh every entry of the response in its own units,
so with several channels the model changes with them (an output recorded in units 1000 times
smaller and an input in units 1000 times larger moved the poles of a noisy 2 x 2 fit by
0.017). With ``scale=True`` (the default) an FRD is balanced as Markov parameters are
(:func:`sysid.era`): each output row divided and each input column multiplied by the scales
that give every row and column of the response a unit root mean square over the frequencies
and the other channels (:func:`sysid.subspace.scaling.balanced_scales`); a time record
(``IOData``) has every channel divided by its root mean square, as
:class:`sysid.SubspaceEstimator` does. The model is fitted in those units and returned in the
record's, the scales in ``info["channel_scaling"]``: it is then the same whatever the units.
``scale=False`` fits the response as given.
"""

from __future__ import annotations

from typing import Any, Union

import numpy as np

from .. import _sysid
from .._checks import as_int
from ..errors import DataError, ShapeError
from .feedthrough import check_feedthrough, choose_feedthrough
from .scaling import balanced_scales, check_scale, in_record_units, record_rms

__all__ = ["frd_subspace"]

Order = Union[int, str]


def frd_subspace(
    frd: Any,
    order: Order = "auto",
    *,
    horizon: int | None = None,
    continuous: bool = False,
    T: float | None = None,
    weights: Any = None,
    lags: int | None = None,
    method: str = "spa",
    feedthrough: bool | str | None = None,
    scale: bool | None = None,
    warp: bool | str = "auto",
) -> Any:
    """State-space model from frequency-response data (McKelvey, Akçay & Ljung 1996).

    Parameters
    ----------
    frd : FRD or IOData
        Measured (``etfe``, ``spa``, ``welch_frf``) or computed response. Discrete time needs
        ``frd.dt`` (the frequencies up to ``pi / dt``). A sampled record (``IOData``) is
        turned into its Blackman-Tukey estimate (:func:`sysid.spa`, ``lags`` below) first;
        with ``continuous=True`` its discrete model is then converted with the zero-order
        hold it was sampled with (:func:`sysid.d2c`), which gives a
        :class:`sysid.ContinuousStateSpace` directly from time data.
    order : int or "auto"
        ``"auto"``: the largest gap of the log singular values.
    horizon : int, optional
        Block rows ``q`` (> order); default ``min(20, max(3, n_freq // 4))``.
    continuous : bool
        Return a :class:`sysid.ContinuousStateSpace` (through the bilinear map).
    T : float, optional
        Sample time of the bilinear map (continuous time); default ``2 / sqrt(w_min w_max)``
        over the positive frequencies, which maps their geometric centre to ``pi / 2``.
        Only for an FRD with ``continuous=True`` (elsewhere it raises: it has no use).
    weights : array_like, optional
        Non-negative weight per frequency (for example ``1 / std``).
    lags : int, optional
        Lag window of :func:`sysid.spa` for ``IOData`` input (default: its own).
    method : {"spa", "dft"}
        For ``IOData`` input (an FRD takes only the default): through the smoothed FRD
        (``"spa"``) or directly from the input and output DFTs of the (single-experiment)
        record (``"dft"``, McKelvey, Akçay & Ljung's spectra form, with the transient term
        estimated: exact for noise-free records, periodic or not).
    feedthrough : bool or "auto", optional
        Estimate ``D``. Default: no direct term, as every sysid state-space estimator; with
        an FRD that shows one (the fit with ``D`` errs on its lines at least twice less) a
        :class:`~sysid.FeedthroughWarning` says so (with ``continuous=True`` the
        continuous-time ``D`` is zero: the discrete fit is constrained to ``G(-1) = 0``,
        which Tustin's map sends to infinite frequency).
        ``"auto"``: decided from the data, a record's by held-out simulation fit
        (:func:`sysid.subspace.feedthrough.choose_feedthrough`), an FRD's by the error on
        lines held out of the fit (:func:`sysid.subspace.feedthrough_frd.choose_feedthrough_frd`:
        a force-to-acceleration response needs ``D``); the reason in
        ``info["feedthrough_selection"]``.
    scale : bool, optional
        Fit with the channels scaled and return the model in the record's units: the same
        model whatever the channels' units. An FRD has every output row and input column of
        its response at unit root mean square over the frequencies and the other channels
        (:mod:`sysid.subspace.frd_subspace`), an ``IOData`` every channel at unit root mean
        square. Default True (:data:`sysid.subspace.scaling.SCALE_DEFAULT`); ``False`` fits the
        response as given. Nothing changes with one input and one output.
    warp : bool or "auto"
        Discrete time: fit at warped frequencies (module notes), which spreads lines that
        crowd a small arc of the unit circle over it. ``"auto"`` (default) warps when the
        lines lie below ``0.9 pi`` and warping widens the arc they span at least 1.5 times
        (a 2-15 Hz band sampled at 400 Hz: 0.2 rad -> 1.7 rad); ``info["warped"]`` says
        whether it did. Exact data give the system either way.

    Returns
    -------
    StateSpaceModel or ContinuousStateSpace
        With ``info["singular_values"]`` (of the scaled response) and
        ``info["channel_scaling"]`` (the scales).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.5]])
    >>> w = np.linspace(0.01, np.pi, 50)
    >>> model = sysid.frd_subspace(sysid.FRD(w, true.freqresp(w), dt=1.0), order=2)
    >>> float(model.D[0, 0])
    0.0
    >>> bool(np.allclose(np.sort_complex(model.poles()), np.sort_complex(true.poles())))
    True
    >>> ct = sysid.ContinuousStateSpace([[0.0, 1.0], [-4.0, -0.4]], [[0.0], [1.0]], [[1.0, 0.0]])
    >>> w = np.logspace(-1, 1.5, 60)
    >>> fit = sysid.frd_subspace(sysid.FRD(w, ct.freqresp(w)), 2, continuous=True)
    >>> bool(np.allclose(np.sort_complex(fit.poles()), np.sort_complex(ct.poles())))
    True
    """
    from ..data.iodata import IOData
    from ..models.frd import FRD
    from ..models.statespace import StateSpaceModel

    left_out = feedthrough is None and isinstance(frd, FRD)  # the default: D checked
    ft = check_feedthrough(False if feedthrough is None else feedthrough)
    scale = check_scale(scale)
    if not isinstance(order, str):
        as_int(order, "order", 1)
    if method not in ("spa", "dft"):
        raise DataError(f"method must be 'spa' or 'dft', got {method!r}")
    if T is not None and (not continuous or isinstance(frd, IOData)):
        raise DataError(f"T (got {T!r}) is the sample time of the bilinear map of an FRD "
                        "fitted with continuous=True; it has no use here: drop it (a discrete "
                        "fit uses frd.dt, a record its own dt)")
    if isinstance(frd, IOData):
        from ..models.continuous import d2c
        from ..nonparametric.frf import spa

        why = None
        if ft == "auto":
            from .estimator import SubspaceEstimator

            ft, why = choose_feedthrough(SubspaceEstimator(frd), order)
        su, sy = record_rms(frd) if scale else (np.ones(frd.n_inputs), np.ones(frd.n_outputs))
        data = frd if np.all(su == 1.0) and np.all(sy == 1.0) else frd._scaled(su, sy)
        if method == "dft":
            dmodel = _from_dft(data, order, horizon, weights, bool(ft))
        else:
            est = spa(data) if lags is None else spa(data, lags=lags)
            dmodel = frd_subspace(est, order, horizon=horizon, weights=weights,
                                  feedthrough=bool(ft), scale=False)
        dmodel = in_record_units(dmodel, su, sy)
        if why is not None:
            dmodel.info["feedthrough_selection"] = why
        if not continuous:
            return dmodel
        ct = d2c(dmodel, "zoh")  # the zero-order hold keeps D: no D stays no D
        ct.info.update(dmodel.info)
        return ct
    if not isinstance(frd, FRD):
        raise DataError(f"frd must be a sysid.FRD, got {type(frd).__name__}")
    if ft == "auto":  # decided on held-out lines, then fitted on all of them
        from .feedthrough_frd import choose_feedthrough_frd

        if continuous != (frd.dt is None):
            raise DataError("feedthrough='auto' decides with the FRD's own time base: a "
                            "discrete FRD fitted discrete, a continuous one continuous")
        use, why = choose_feedthrough_frd(frd, order, lambda g, n, d: frd_subspace(
            g, n, continuous=continuous, feedthrough=d, scale=scale, warp=warp))
        model = frd_subspace(frd, order, horizon=horizon, continuous=continuous, T=T,
                             weights=weights, feedthrough=use, scale=scale, warp=warp)
        model.info["feedthrough_selection"] = why
        return model
    if method != "spa":
        raise DataError(f"method={method!r} applies to a time record (IOData); an FRD is "
                        "fitted as it is: drop method")
    omega = np.asarray(frd.omega, dtype=float)
    g = np.asarray(frd.response, dtype=complex)
    nf, l, m = g.shape
    if np.any(omega < 0) or not np.all(np.isfinite(omega)):
        raise DataError(f"frequencies must be finite and >= 0, got min {omega.min():g} rad/s; "
                        "keep the non-negative half of a two-sided response")
    if warp is True and continuous:
        raise DataError("warp=True is the discrete fit's option (continuous=True always fits "
                        "at warped frequencies): drop it")
    if left_out:  # fitted without D, then checked against the fit with it
        from .feedthrough_frd import warn_if_left_out_frd

        def fit(d: bool) -> Any:
            return frd_subspace(frd, order, horizon=horizon, continuous=continuous, T=T,
                                weights=weights, feedthrough=d, scale=scale, warp=warp)
        model = fit(False)
        warn_if_left_out_frd(frd, model, fit, "frd_subspace")
        return model
    if not continuous and frd.dt is not None and warp is not False:
        warped = _warped(frd, order, horizon, weights, bool(ft), scale, warp)
        if warped is not None:
            return warped
    if continuous:
        pos = omega[omega > 0]
        if pos.size == 0:
            raise DataError("continuous-time identification needs positive frequencies")
        if T is None:
            T = 2.0 / float(np.sqrt(pos.min() * pos.max()))
        T = float(T)
        if not np.isfinite(T) or T <= 0:
            raise DataError(f"T must be a positive number, got {T}")
        wd = 2.0 * np.arctan(omega * T / 2.0)
        dt = T
    else:
        if frd.dt is None:
            raise DataError("discrete-time identification needs frd.dt; give the FRD a sample "
                            "time or use continuous=True")
        dt = float(frd.dt)
        wd = omega * dt
        if np.any(np.abs(wd) > np.pi * (1 + 1e-12)):
            raise DataError("frequencies above the Nyquist frequency pi / dt")
    if horizon is None:
        horizon = int(min(20, max(3, nf // 4)))
        if not isinstance(order, str):
            horizon = max(horizon, int(order) + 1)
    q = as_int(horizon, "horizon", 2)
    if q * l > 2 * nf * m:  # the Hankel matrix has q*l rows and 2*nf*m real columns
        raise DataError(f"horizon={q} needs at least {-(-q * l // (2 * m))} frequencies "
                        f"({nf} given): lower the horizon or measure more frequencies")
    n = None
    if isinstance(order, str):
        if order != "auto":
            raise DataError(f"order must be an integer or 'auto', got {order!r}")
    else:
        n = as_int(order, "order", 1)
    w = None if weights is None else _weights(weights, nf, "frequency of the FRD")
    su, sy = (balanced_scales(g, "frequency responses", frd.input_names, frd.output_names)
              if scale else (np.ones(m), np.ones(l)))
    if not (np.all(su == 1.0) and np.all(sy == 1.0)):
        g = g * su[None, None, :] / sy[None, :, None]
    flat = g.reshape(nf, l * m)
    mode = "estimate" if ft else ("zero-at-nyquist" if continuous else "zero")
    res = _sysid.frd_subspace(np.ascontiguousarray(wd), np.ascontiguousarray(flat.real),
                              np.ascontiguousarray(flat.imag), l, q, n, w, mode)
    info = {"method": "frequency-subspace", "horizon": q, "order": res["A"].shape[0],
            "singular_values": res["singular_values"], "feedthrough": bool(ft)}
    if not continuous:
        info["warped"] = False
    model = StateSpaceModel(res["A"], res["B"], res["C"], res["D"], dt=dt,
                            input_names=frd.input_names, output_names=frd.output_names,
                            info=info)
    model = in_record_units(model, su, sy, basis="frequency response")
    info = model.info
    if not continuous:
        return model
    from ..models.continuous import d2c

    ct = d2c(model, "tustin")
    ct.info.update(info)
    ct.info["bilinear_T"] = T
    return ct


#: ``warp="auto"``: the lines must lie below this share of the Nyquist frequency ...
WARP_BELOW = 0.9
#: ... and warping must widen the arc of the unit circle they span at least this much
WARP_GAIN = 1.5


def _warp_pays(wd: np.ndarray) -> bool:
    """Whether warping the lines ``wd`` (rad/sample) spreads them (``warp="auto"``): all
    below ``WARP_BELOW`` Nyquist, and the arc they span at least ``WARP_GAIN`` times wider
    after the map of :func:`_warped` (which centres their geometric mean)."""
    if np.count_nonzero(wd > 0) < 2 or wd.max() >= WARP_BELOW * np.pi:
        return False
    wc = 2.0 * np.tan(wd / 2.0)  # the continuous frequencies of the lines (dt = 1)
    T = 2.0 / float(np.sqrt(wc[wc > 0].min() * wc.max()))
    spread = 2.0 * np.arctan(wc * T / 2.0)
    return bool(np.ptp(spread) >= WARP_GAIN * np.ptp(wd))


def _warped(frd: Any, order: Order, horizon: int | None, weights: Any, ft: bool,
            scale: bool, warp: bool | str) -> Any:
    """The discrete fit at warped frequencies, or None when ``warp="auto"`` finds no gain.

    ``G(e^{j w dt})`` is the response of the continuous model ``d2c(G, "tustin")`` at
    ``(2 / dt) tan(w dt / 2)``; that continuous model is fitted (``continuous=True``, whose
    own bilinear map centres the lines on the unit circle) and mapped back with Tustin's
    rule at ``dt``: exact for an exact response, of the same order. Without ``feedthrough``
    the continuous fit keeps its direct term, and ``B`` is fitted again with ``D = 0`` on
    the lines (weighted least squares, ``A`` and ``C`` fixed)."""
    from ..models.continuous import c2d
    from ..models.frd import FRD

    if warp not in (True, "auto"):
        raise DataError(f"warp must be True, False or 'auto', got {warp!r}")
    dt = float(frd.dt)
    wd = np.asarray(frd.omega, float) * dt
    if wd.max() >= np.pi * (1 - 1e-9):
        if warp == "auto":
            return None
        raise DataError("warp=True needs every line below the Nyquist frequency (the warp "
                        "sends it to infinity): drop that line or pass warp=False")
    if warp == "auto" and not _warp_pays(wd):
        return None
    ct_frd = FRD(2.0 * np.tan(wd / 2.0) / dt, frd.response, input_names=frd.input_names,
                 output_names=frd.output_names)
    ct = frd_subspace(ct_frd, order, horizon=horizon, continuous=True, weights=weights,
                      feedthrough=True, scale=scale)
    model = c2d(ct, dt, "tustin")
    D = model.D
    B = model.B if ft else _fit_b(model.A, model.C, wd, np.asarray(frd.response, complex),
                                   weights)
    if not ft:
        D = np.zeros_like(D)
    info = dict(ct.info)
    info.pop("bilinear_T", None)
    info.update(method="frequency-subspace", feedthrough=ft, warped=True,
                warp_T=float(ct.info.get("bilinear_T", np.nan)) / dt)
    return type(model)(model.A, B, model.C, D, dt=dt, input_names=frd.input_names,
                       output_names=frd.output_names, info=info)


def _fit_b(A: np.ndarray, C: np.ndarray, wd: np.ndarray, g: np.ndarray,
           weights: Any) -> np.ndarray:
    """``B`` minimising ``sum_k w_k |C (z_k I - A)^-1 B - G_k|^2`` (``z_k = e^{j wd_k}``),
    each output row divided by its root mean square over the lines and inputs (the fit is
    then the same whatever the outputs' units); lines in blocks of 256."""
    n, (nf, l, m) = A.shape[0], g.shape
    w = np.ones(nf) if weights is None else _weights(weights, nf, "frequency of the FRD")
    sy = np.sqrt(np.mean(np.abs(g) ** 2, axis=(0, 2)))
    sy[sy == 0] = 1.0
    rows_r, rows_i, rhs_r, rhs_i = [], [], [], []
    eye = np.eye(n)
    for s in range(0, nf, 256):
        z = np.exp(1j * wd[s:s + 256])
        # Y_k = C (z_k I - A)^-1: l x n per line, by solves with the transposes
        Y = np.linalg.solve(z[:, None, None] * eye - A.T, np.broadcast_to(
            C.T, (z.size, n, l))).transpose(0, 2, 1)
        sw = np.sqrt(w[s:s + 256])[:, None, None] / sy[None, :, None]
        Yw, Gw = Y * sw, g[s:s + 256] * sw
        rows_r.append(Yw.real.reshape(-1, n))
        rows_i.append(Yw.imag.reshape(-1, n))
        rhs_r.append(Gw.real.reshape(-1, m))
        rhs_i.append(Gw.imag.reshape(-1, m))
    M = np.vstack(rows_r + rows_i)
    R = np.vstack(rhs_r + rhs_i)
    return np.linalg.lstsq(M, R, rcond=None)[0]


def _from_dft(data: Any, order: Order, horizon: int | None, weights: Any,
              feedthrough: bool) -> Any:
    """Discrete model from the DFTs of a single-experiment record."""
    from ..models.statespace import StateSpaceModel

    if data.n_experiments != 1:
        raise DataError("method='dft' needs a single-experiment record")
    u, y = data.experiments[0]
    n = y.shape[0]
    U = np.fft.rfft(u, axis=0) / np.sqrt(n)
    Y = np.fft.rfft(y, axis=0) / np.sqrt(n)
    wd = 2 * np.pi * np.arange(U.shape[0]) / n
    if horizon is None:
        horizon = 20 if isinstance(order, str) else max(10, int(order) + 1)
    q = as_int(horizon, "horizon", 2)
    nord = None if isinstance(order, str) else as_int(order, "order", 1)
    if isinstance(order, str) and order != "auto":
        raise DataError(f"order must be an integer or 'auto', got {order!r}")
    w = None if weights is None else _weights(
        weights, wd.size, f"DFT frequency of the {n}-sample record (N // 2 + 1)")
    c = np.ascontiguousarray
    res = _sysid.spectra_subspace(c(wd), c(U.real), c(U.imag), c(Y.real), c(Y.imag), q, nord,
                                  w, True, "estimate" if feedthrough else "zero")
    info = {"method": "frequency-subspace-dft", "horizon": q, "order": res["A"].shape[0],
            "singular_values": res["singular_values"], "feedthrough": feedthrough}
    return StateSpaceModel(res["A"], res["B"], res["C"], res["D"], dt=data.dt,
                           input_names=data.input_names, output_names=data.output_names,
                           info=info)


def _weights(weights: Any, n: int, what: str) -> np.ndarray:
    """``weights`` as one number per frequency (a single number is repeated); another
    length is a :class:`ShapeError` (it was numpy's broadcast error)."""
    w = np.asarray(weights, dtype=float)
    if w.ndim > 1 or (w.ndim == 1 and w.size != n):
        raise ShapeError(f"weights has shape {w.shape} but should be ({n},): one weight per "
                         f"{what}, or a single number")
    return np.ascontiguousarray(np.broadcast_to(w, (n,)))
