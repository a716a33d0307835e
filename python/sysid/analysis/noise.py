"""A model's noise part as a model of its own (MATLAB's ``noise2meas``) and the output
spectrum it implies (MATLAB's ``spectrum``).

An innovations-form model ``x(t+1) = A x + B u + K e, y = C x + D u + e`` with ``cov(e) =
Lambda`` has the disturbance ``v = H(q) e``, ``H = C (qI - A)^-1 K + I``.
:func:`noise2meas` returns ``H`` as a model whose inputs are the noise channels (``"innovations"``:
``(A, K, C, I)`` driven by ``e``; ``"normalize"``: ``(A, K L, C, L)`` driven by white noise of
unit variance, ``Lambda = L L^T``). :func:`spectrum` returns the disturbance's power spectral
density ``Phi_v(w) = 2 dt H Lambda H^*`` (one-sided, units^2/Hz, at angular frequencies in
rad/s), the convention of :func:`sysid.spectra`, so that a model's spectrum and the spectrum
of its residuals or of a time series lie on one plot; for a time-series model (no inputs) it
is the output spectrum the model predicts.

Examples
--------
>>> import numpy as np, sysid
>>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], K=[[0.3]], noise_cov=[[0.04]])
>>> h = sysid.noise2meas(m)
>>> h.B.tolist(), h.D.tolist()
([[0.3]], [[1.0]])
>>> s = sysid.spectrum(m, omega=[0.0])
>>> round(float(s.psd("y0")[0].real), 6)  # 2 * 0.04 * |1 + 0.3 / (1 - 0.5)|^2
0.2048
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..models.statespace import StateSpaceModel

__all__ = ["noise2meas", "spectrum"]


def _innovations_model(model: Any, what: str) -> StateSpaceModel:
    ss = model
    if not isinstance(ss, StateSpaceModel):
        if not hasattr(ss, "to_statespace") or getattr(ss, "dt", 1.0) == 0:
            raise DataError(f"{what} needs a discrete model with a noise model (a "
                            f"StateSpaceModel, or a polynomial model), got "
                            f"{type(model).__name__}")
        ss = ss.to_statespace()
    if ss.noise_cov is None:
        raise DataError(f"{what}: the model has no noise covariance (a fit with no noise "
                        "model, such as focus='simulation'); estimate one with "
                        "focus='prediction', or sysid.pem(data, model, noise='estimate')")
    return ss


def noise2meas(model: Any, noise: str = "innovations") -> StateSpaceModel:
    """The noise part ``H`` of a model as a model with the noise channels as inputs.

    Parameters
    ----------
    model : StateSpaceModel or a discrete model with ``to_statespace()``
        Needs its noise covariance (``noise_cov``); a model without ``K`` has ``H = I``.
    noise : {"innovations", "normalize"}
        Inputs the innovations ``e`` (``cov Lambda``), or white noise of unit variance
        (``H L`` with ``Lambda = L L^T``; MATLAB's ``"normalize"``).

    Returns
    -------
    StateSpaceModel
        Its parameter uncertainty that of the model, through the same map.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], K=[[0.3]], noise_cov=[[0.04]])
    >>> sysid.noise2meas(m, "normalize").D.tolist()
    [[0.2]]
    """
    if noise not in ("innovations", "normalize"):
        raise DataError(f"noise must be 'innovations' or 'normalize', got {noise!r}")
    ss = _innovations_model(model, "noise2meas")
    n, l = ss.nstates, ss.noutputs
    K = ss.K if ss.K is not None else np.zeros((n, l))
    L = np.eye(l)
    if noise == "normalize":
        lam = 0.5 * (ss.noise_cov + ss.noise_cov.T)
        w, V = np.linalg.eigh(lam)
        if w.min() < -1e-12 * max(1.0, w.max()):
            raise DataError("the noise covariance is not positive semi-definite")
        L = V * np.sqrt(np.clip(w, 0, None))  # Lambda = L L^T
    names = [f"e@{o}" for o in ss.output_names]
    out = StateSpaceModel(ss.A, K @ L, ss.C, L, dt=ss.dt, input_names=names,
                          output_names=ss.output_names,
                          info={"method": f"noise2meas ({noise})"})
    unc = getattr(model, "uncertainty", None)
    if unc is not None:  # the same parameters, seen through the map
        cov = ss.noise_cov

        def mapped(b: Any) -> StateSpaceModel:
            # drawn models carry no noise covariance: the estimate's
            b = b if isinstance(b, StateSpaceModel) else b.to_statespace()
            return noise2meas(StateSpaceModel(b.A, b.B, b.C, b.D, K=b.K, dt=b.dt,
                                              noise_cov=cov), noise)

        out.uncertainty = unc.through(mapped)
    return out


def spectrum(model: Any, omega: Any = None, n_freq: int = 256) -> Any:
    """Power spectral density of the disturbance a model implies (its output spectrum for a
    time-series model), in :func:`sysid.spectra`'s convention.

    Parameters
    ----------
    model : StateSpaceModel or a discrete model with ``to_statespace()``
        With its noise covariance.
    omega : array_like, optional
        Angular frequencies (rad/s); default ``n_freq`` points from 0 to the Nyquist
        frequency.
    n_freq : int

    Returns
    -------
    Spectra
        ``matrix[:, a, b]`` the one-sided cross density of outputs ``a, b`` (units^2/Hz),
        ``2 dt H Lambda H^*`` (SciPy's ``welch`` convention; MATLAB's ``spectrum`` is the
        two-sided ``dt H Lambda H^*``, half of it); ``psd(name)``, ``plot()``,
        ``to_pandas()``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> y = np.random.default_rng(0).standard_normal((4096, 1))
    >>> m = sysid.arma(sysid.IOData(u=np.zeros((4096, 0)), y=y), 1, 0)
    >>> bool(abs(sysid.spectrum(m, omega=[1.0]).psd("y0")[0].real - 2.0) < 0.2)
    True
    """
    from ..nonparametric.spectra import Spectra

    ss = _innovations_model(model, "spectrum")
    dt = float(ss.dt)
    if omega is None:
        omega = np.linspace(0.0, np.pi / dt, int(n_freq))
    w = np.asarray(omega, dtype=float).ravel()
    if w.size == 0 or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise DataError("omega must be non-negative, finite angular frequencies (rad/s)")
    H = noise2meas(ss).freqresp(w)  # (n_freq, l, l)
    phi = 2.0 * dt * np.einsum("fij,jk,flk->fil", H, ss.noise_cov, np.conj(H))
    return Spectra(w, phi, list(ss.output_names), "model (2 dt H Lambda H*)",
                   info={"model": type(model).__name__})
