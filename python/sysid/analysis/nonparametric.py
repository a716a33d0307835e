"""Non-parametric estimates: spectra, coherence, correlation and frequency responses.

Conventions. Channels are stacked ``z = [u; y]``. The cross-spectrum of channels ``a`` and
``b`` is ``S_ab = E[Z_a Z_b^*]`` (``scipy.signal.csd(z_b, z_a)``), so for ``y = G u + v``
with ``v`` independent of ``u``

.. math::

    S_{yu} = G S_{uu}, \\qquad G = S_{yu} S_{uu}^{-1}, \\qquad
    S_{vv} = S_{yy} - S_{yu} S_{uu}^{-1} S_{uy}.

Each method averages the equivalent of ``K`` independent spectral estimates (Ljung, *System
Identification*, 1999, ch. 6): ``K = N / sum(w(tau)^2)`` for a lag window ``w``
(Blackman-Tukey), the effective number of Welch averages (overlap accounted for, Welch 1967),
``1 / sum(W_k^2)`` per experiment for a normalised frequency window ``W`` (smoothed ETFE).
With ``m`` inputs the variance of each entry is estimated as ``sigma^2 = [S_vv]_ii
[S_uu^{-1}]_jj / (K - m)`` and the error, normalised by it, follows an F distribution with
``(2, 2 (K - m))`` degrees of freedom (Gaussian data): the confidence band at level ``p`` is the
circle of radius ``sigma sqrt(F^{-1}(p))`` around the estimate, which tends to
``sigma sqrt(-ln(1 - p))`` for large ``K``. Frequencies are angular, in rad/s.

Spectra are one-sided densities in units^2/Hz, as ``scipy.signal.welch``. Several
experiments are averaged (no segment or lag spans two). Frequencies where the input
spectrum is singular (no excitation) are left out of frequency responses and listed in
``FRD.info["dropped"]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import ndimage, signal, stats

from .._checks import as_int
from ..data.iodata import IOData
from ..errors import DataError, InsufficientDataError, ShapeError

__all__ = [
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
]

_COND_LIMIT = 1e10


def _need_data(data: Any, inputs: bool = True) -> IOData:
    if not isinstance(data, IOData):
        raise DataError(f"data must be a sysid.IOData, got {type(data).__name__}")
    if inputs and data.n_inputs == 0:
        raise DataError("a frequency response needs inputs; this record is a time series")
    return data


def _z(data: IOData) -> list[np.ndarray]:
    return [np.hstack([u, y]) for u, y in data.experiments]


def _names(data: IOData) -> list[str]:
    return list(data.input_names) + list(data.output_names)


# --------------------------------------------------------------------------------------------
# frequency-response data
# --------------------------------------------------------------------------------------------


class FRD:
    """Frequency-response data: a measured or estimated ``G(e^{j omega dt})``.

    Parameters
    ----------
    omega : array_like
        Angular frequencies in rad/s, shape ``(n_freq,)``.
    response : array_like
        Complex response, ``(n_freq, n_outputs, n_inputs)``.
    coherence : array_like, optional
        Magnitude-squared coherence per output/input pair, same shape (real, 0..1).
    std : array_like, optional
        Standard deviation of each complex entry, same shape (``E|G_hat - G|^2 = std^2``).
    confidence : float
        Level of the band drawn and tested by :meth:`within_band`.
    dof : float, optional
        Denominator degrees of freedom of the F distribution of the normalised error
        (``2 (K - m)``); ``None`` for the large-sample (complex normal) limit.
    dt : float, optional
        Sample time of the data it came from.
    input_names, output_names : list of str, optional
    method : str
        How it was estimated.
    info : dict, optional
        Settings (window, lags, averages, dropped frequencies).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> w = np.linspace(0.1, 3.0, 5)
    >>> f = sysid.FRD(w, m.freqresp(w))
    >>> f
    FRD: 5 frequencies 0.1..3 rad/s, 1 output x 1 input
    >>> f.compare(m).max_error < 1e-12
    True
    """

    def __init__(
        self,
        omega: Any,
        response: Any,
        *,
        coherence: Any = None,
        std: Any = None,
        confidence: float = 0.99,
        dof: float | None = None,
        dt: float | None = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        method: str = "",
        info: dict[str, Any] | None = None,
    ) -> None:
        w = np.asarray(omega, dtype=float).ravel()
        g = np.asarray(response, dtype=complex)
        if g.ndim == 1:
            g = g[:, None, None]
        if g.ndim != 3 or g.shape[0] != w.size:
            raise ShapeError(
                f"response must be (n_freq, n_outputs, n_inputs) with n_freq = {w.size}, "
                f"got {g.shape}"
            )
        if not (np.isfinite(w).all() and np.isfinite(g).all()):
            raise DataError("omega and response must be finite")
        if not 0.0 < confidence < 1.0:
            raise DataError(f"confidence must lie in (0, 1), got {confidence}")
        self.omega = w
        self.response = g
        self.coherence = None if coherence is None else self._same(coherence, "coherence", float)
        self.std = None if std is None else self._same(std, "std", float)
        self.confidence = float(confidence)
        if dof is not None and not dof > 0:
            raise DataError(f"dof must be positive, got {dof}")
        self.dof = None if dof is None else float(dof)
        self.dt = dt
        l, m = g.shape[1:]
        self.input_names = IOData._names(input_names, m, "u", "input")
        self.output_names = IOData._names(output_names, l, "y", "output")
        self.method = method
        self.info = dict(info or {})

    def _same(self, x: Any, name: str, dtype: type) -> np.ndarray:
        a: np.ndarray = np.asarray(x, dtype=dtype)
        if a.shape != self.response.shape:
            raise ShapeError(f"{name} has shape {a.shape} but the response {self.response.shape}")
        return a

    @property
    def hz(self) -> np.ndarray:
        """Frequencies in Hz."""
        return self.omega / (2 * np.pi)

    @property
    def n_inputs(self) -> int:
        return self.response.shape[2]

    @property
    def n_outputs(self) -> int:
        return self.response.shape[1]

    @property
    def magnitude(self) -> np.ndarray:
        """``|G|``, shape ``(n_freq, n_outputs, n_inputs)``."""
        return np.abs(self.response)

    @property
    def phase(self) -> np.ndarray:
        """Unwrapped phase in radians along frequency."""
        return np.unwrap(np.angle(self.response), axis=0)

    @property
    def radius(self) -> np.ndarray | None:
        """Radius of the confidence circle at :attr:`confidence` (``None`` without ``std``)."""
        if self.std is None:
            return None
        if self.dof is None:
            return self.std * np.sqrt(-np.log1p(-self.confidence))
        return self.std * np.sqrt(stats.f.ppf(self.confidence, 2, self.dof))

    def _other(self, other: Any) -> np.ndarray:
        if hasattr(other, "freqresp"):
            g = np.asarray(other.freqresp(self.omega))
        elif isinstance(other, FRD):
            if other.omega.shape != self.omega.shape or not np.allclose(other.omega, self.omega):
                raise DataError("the two FRDs are on different frequency grids")
            g = other.response
        else:
            g = np.asarray(other, dtype=complex)
        if g.shape != self.response.shape:
            raise ShapeError(f"the other response has shape {g.shape}, this one "
                             f"{self.response.shape}")
        return g

    def within_band(self, other: Any) -> np.ndarray:
        """Whether ``other`` (a model with ``freqresp``, an FRD or an array) lies inside the
        confidence circle at every frequency and pair; bool ``(n_freq, l, m)``."""
        if self.radius is None:
            raise DataError(f"this FRD ({self.method or 'given'}) carries no confidence band")
        return np.abs(self._other(other) - self.response) <= self.radius

    def compare(self, other: Any) -> FRDComparison:
        """Compare with a model's (or another FRD's) response on this grid."""
        g = self._other(other)
        err = np.abs(g - self.response)
        rel = err / np.maximum(np.abs(self.response), np.finfo(float).tiny)
        inside = None if self.std is None else float(self.within_band(g).mean())
        return FRDComparison(self.omega, self.response, g, err, rel, inside)

    def select(self, outputs: Any = None, inputs: Any = None) -> FRD:
        """The sub-response of some outputs and inputs (names or indices)."""
        dummy = IOData(u=np.zeros((1, self.n_inputs)), y=np.zeros((1, self.n_outputs)),
                       input_names=self.input_names, output_names=self.output_names)
        iu = dummy._index(inputs, self.input_names, "input")
        iy = dummy._index(outputs, self.output_names, "output")

        def sub(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else a[:, iy][:, :, iu]

        return FRD(
            self.omega, sub(self.response), coherence=sub(self.coherence), std=sub(self.std),
            confidence=self.confidence, dof=self.dof, dt=self.dt,
            input_names=[self.input_names[i] for i in iu],
            output_names=[self.output_names[i] for i in iy], method=self.method, info=self.info,
        )

    @classmethod
    def from_model(cls, model: Any, omega: Any) -> FRD:
        """The frequency response of a model (anything with ``freqresp(omega)``) as an FRD.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
        >>> sysid.FRD.from_model(m, np.linspace(0.1, 30.0, 10))
        FRD (model): 10 frequencies 0.1..30 rad/s, 1 output x 1 input
        """
        return cls(
            omega, model.freqresp(np.asarray(omega, dtype=float)), dt=getattr(model, "dt", None),
            input_names=getattr(model, "input_names", None),
            output_names=getattr(model, "output_names", None), method="model",
        )

    def to_pandas(self) -> Any:
        """A long-format DataFrame: one row per frequency and output/input pair with
        ``omega``, ``hz``, ``output``, ``input``, ``real``, ``imag``, ``magnitude``,
        ``phase`` (rad) and, when known, ``coherence`` and ``std``."""
        from ..data.iodata import _pandas

        pd = _pandas()
        nf, l, m = self.response.shape
        idx = np.indices((nf, l, m)).reshape(3, -1)
        g = self.response.reshape(-1)
        cols: dict[str, Any] = {
            "omega": self.omega[idx[0]],
            "hz": self.hz[idx[0]],
            "output": np.array(self.output_names, dtype=object)[idx[1]],
            "input": np.array(self.input_names, dtype=object)[idx[2]],
            "real": g.real,
            "imag": g.imag,
            "magnitude": np.abs(g),
            "phase": self.phase.reshape(-1),
        }
        if self.coherence is not None:
            cols["coherence"] = self.coherence.reshape(-1)
        if self.std is not None:
            cols["std"] = self.std.reshape(-1)
        return pd.DataFrame(cols)

    def plot(self, models: Any = None, *, fig: Any = None) -> Any:
        """Bode plot with the confidence band and coherence; ``models`` are overlaid."""
        from ..plot.frequency import plot_frd

        return plot_frd(self, models=models, fig=fig)

    def __repr__(self) -> str:
        l, m = self.n_outputs, self.n_inputs
        meth = f" ({self.method})" if self.method else ""
        return (
            f"FRD{meth}: {self.omega.size} frequencies {self.omega[0]:.3g}.."
            f"{self.omega[-1]:.3g} rad/s, {l} output{'s' * (l != 1)} x "
            f"{m} input{'s' * (m != 1)}"
        )


class FRDComparison:
    """Measured against model response on the FRD's grid (from :meth:`FRD.compare`).

    Attributes
    ----------
    omega, measured, model : ndarray
    error : ndarray
        ``|model - measured|``.
    relative_error : ndarray
        ``error / |measured|``.
    fraction_within_band : float or None
        Share of frequency/pair entries inside the FRD's confidence band.
    """

    def __init__(self, omega: np.ndarray, measured: np.ndarray, model: np.ndarray,
                 error: np.ndarray, relative_error: np.ndarray, inside: float | None) -> None:
        self.omega = omega
        self.measured = measured
        self.model = model
        self.error = error
        self.relative_error = relative_error
        self.fraction_within_band = inside

    @property
    def max_error(self) -> float:
        return float(self.error.max())

    def __repr__(self) -> str:
        band = ("" if self.fraction_within_band is None
                else f", {self.fraction_within_band:.1%} within the confidence band")
        return (f"FRDComparison: median relative error {np.median(self.relative_error):.3g}, "
                f"max {self.relative_error.max():.3g}{band}")


# --------------------------------------------------------------------------------------------
# spectral machinery
# --------------------------------------------------------------------------------------------


def _welch_matrix(
    zs: list[np.ndarray], nperseg: int, noverlap: int, window: Any, nfft: int | None,
    dt: float, detrend: bool,
) -> tuple[np.ndarray, np.ndarray, float, int]:
    """One-sided density cross-spectral matrix ``(n_freq, nc, nc)``, freqs (Hz), K_eff, K."""
    win = signal.get_window(window, nperseg) if not isinstance(window, np.ndarray) else window
    if win.size != nperseg:
        raise DataError(f"window has {win.size} samples, nperseg is {nperseg}")
    nfft = nperseg if nfft is None else int(nfft)
    step = nperseg - noverlap
    nc = zs[0].shape[1]
    nf = nfft // 2 + 1
    S = np.zeros((nf, nc, nc), dtype=complex)
    count = 0
    for z in zs:
        if z.shape[0] < nperseg:
            continue
        segs = np.lib.stride_tricks.sliding_window_view(z, nperseg, axis=0)[::step]
        segs = segs.transpose(0, 2, 1)  # (K, nperseg, nc)
        if detrend:
            segs = segs - segs.mean(axis=1, keepdims=True)
        Z = np.fft.rfft(segs * win[None, :, None], n=nfft, axis=1)  # (K, nf, nc)
        S += np.einsum("kfa,kfb->fab", Z, Z.conj())
        count += Z.shape[0]
    if count == 0:
        raise InsufficientDataError(
            f"every experiment is shorter than nperseg = {nperseg}; lower nperseg"
        )
    scale = dt / (win @ win) / count
    S *= scale
    S[1 : nf - (1 if nfft % 2 == 0 else 0)] *= 2.0
    f = np.fft.rfftfreq(nfft, dt)
    # effective number of averages (Welch 1967): overlapping segments are correlated
    rho = 0.0
    w2 = win * win
    j = 1
    while j * step < nperseg:
        c = (win[: nperseg - j * step] * win[j * step :]).sum() / w2.sum()
        rho += (1.0 - j / max(count, 1)) * c * c
        j += 1
    k_eff = count / (1.0 + 2.0 * rho)
    return S, f, k_eff, count


def _frf_from_S(
    S: np.ndarray, m: int, min_power: float = 1e-12
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """G, pairwise coherence, multiple coherence, noise-to-input ratio factor, kept mask."""
    Suu = S[:, :m, :m]
    Syu = S[:, m:, :m]
    Syy = S[:, m:, m:]
    nf, l = S.shape[0], S.shape[1] - m
    keep = np.ones(nf, dtype=bool)
    top = max(np.abs(np.einsum("fii->f", Suu)).max(), np.finfo(float).tiny)
    for k in range(nf):
        tr = np.trace(Suu[k]).real
        if tr <= min_power * top or np.linalg.cond(Suu[k]) > _COND_LIMIT:
            keep[k] = False
    Suu, Syu, Syy = Suu[keep], Syu[keep], Syy[keep]
    Suu_inv = np.linalg.inv(Suu)
    G = Syu @ Suu_inv
    du = np.einsum("fjj->fj", Suu).real
    dy = np.einsum("fii->fi", Syy).real
    tiny = np.finfo(float).tiny
    coh = np.abs(Syu) ** 2 / np.maximum(dy[:, :, None] * du[:, None, :], tiny)
    explained = np.einsum("fij,fji->fi", G, np.conj(np.swapaxes(Syu, 1, 2))).real
    mcoh = explained / np.maximum(dy, tiny)
    Svv = np.maximum(dy - explained, 0.0)
    ratio = Svv[:, :, None] * np.einsum("fjj->fj", Suu_inv).real[:, None, :]
    return G, np.clip(coh, 0, 1), np.clip(mcoh, 0, 1), np.maximum(ratio, 0.0), keep, l


def _band(ratio: np.ndarray, K: float, m: int, fix: str) -> tuple[np.ndarray, float]:
    """Standard deviation and F degrees of freedom from ``K`` equivalent averages."""
    if K - m < 1.0:
        raise InsufficientDataError(
            f"the estimate averages the equivalent of {K:.1f} spectra for {m} input(s): too "
            f"few for a confidence band; {fix}"
        )
    return np.sqrt(ratio / (K - m)), 2.0 * (K - m)


def _default_nperseg(data: IOData) -> int:
    shortest = min(data.lengths)
    return int(min(256, 2 ** max(3, int(np.log2(max(shortest // 4, 8))))))


# --------------------------------------------------------------------------------------------
# frequency responses
# --------------------------------------------------------------------------------------------


def welch_frf(
    data: IOData,
    *,
    nperseg: int | None = None,
    noverlap: int | None = None,
    window: str = "hann",
    nfft: int | None = None,
    confidence: float = 0.99,
) -> FRD:
    """Frequency response ``G = S_yu S_uu^{-1}`` from Welch-averaged cross spectra (the H1
    estimator, MIMO), with coherence and a confidence band.

    Parameters
    ----------
    data : IOData
        Inputs and outputs (several experiments are averaged).
    nperseg : int, optional
        Segment length (default ``min(256, shortest experiment / 4)`` rounded to a power of 2).
    noverlap : int, optional
        Overlap (default half a segment).
    window : str
        Window name for ``scipy.signal.get_window``.
    nfft : int, optional
        FFT length (zero padding).
    confidence : float
        Level of the band.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> g = sysid.StateSpaceModel([[0.6]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal((4000, 1))
    >>> frd = sysid.welch_frf(sysid.IOData(u=u, y=g.simulate(u)), nperseg=128)
    >>> bool(frd.compare(g).relative_error.max() < 0.05)
    True
    """
    data = _need_data(data)
    nperseg = _default_nperseg(data) if nperseg is None else as_int(nperseg, "nperseg", 2)
    noverlap = nperseg // 2 if noverlap is None else as_int(noverlap, "noverlap", 0)
    if noverlap >= nperseg:
        raise DataError(f"noverlap ({noverlap}) must be smaller than nperseg ({nperseg})")
    S, f, k_eff, count = _welch_matrix(_z(data), nperseg, noverlap, window, nfft, data.dt, True)
    m = data.n_inputs
    if count <= m:
        raise InsufficientDataError(
            f"{count} segment(s) for {m} input(s): the H1 estimate needs more segments than "
            "inputs; lower nperseg"
        )
    # segment means are removed: the zero-frequency bin carries no information
    S, f = S[1:], f[1:]
    G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m)
    std, dof = _band(ratio, k_eff, m, "lower nperseg")
    return FRD(
        2 * np.pi * f[keep], G, coherence=coh, std=std, dof=dof,
        confidence=confidence, dt=data.dt, input_names=data.input_names,
        output_names=data.output_names, method="welch",
        info={"nperseg": nperseg, "noverlap": noverlap, "window": window, "segments": count,
              "effective_averages": k_eff, "multiple_coherence": mcoh,
              "dropped": 2 * np.pi * f[~keep]},
    )


def _lag_covariances(
    zs: list[np.ndarray], max_lag: int, remove_mean: bool
) -> tuple[np.ndarray, int]:
    """``R[tau] = (1/N) sum_t z(t + tau) z(t)^T`` for tau = 0..max_lag, over experiments."""
    nc = zs[0].shape[1]
    R = np.zeros((max_lag + 1, nc, nc))
    total = 0
    for z in zs:
        x = z - z.mean(axis=0) if remove_mean else z
        n = x.shape[0]
        total += n
        nfft = int(2 ** np.ceil(np.log2(2 * n)))
        X = np.fft.rfft(x, n=nfft, axis=0)
        # R_ab(tau) = sum_t x_a(t + tau) x_b(t): inverse FFT of X_a conj(X_b)
        C = np.fft.irfft(np.einsum("fa,fb->fab", X, X.conj()), n=nfft, axis=0)
        L = min(max_lag, n - 1)
        R[: L + 1] += C[: L + 1]
    return R / total, total


def spa(
    data: IOData,
    *,
    lags: int | None = None,
    omega: Any = None,
    n_freq: int = 128,
    remove_mean: bool = True,
    confidence: float = 0.99,
) -> FRD:
    """Blackman-Tukey spectral analysis (as MATLAB's ``spa``): covariances up to ``lags``
    with a Hann lag window, Fourier transformed; ``G = S_yu S_uu^{-1}`` with coherence and a
    confidence band.

    Parameters
    ----------
    data : IOData
    lags : int, optional
        Lag window width ``M`` (default ``min(N / 10, 30)``); larger ``M`` means less bias,
        more variance.
    omega : array_like, optional
        Angular frequencies (rad/s); default ``n_freq`` points up to Nyquist.
    remove_mean : bool
        Subtract each experiment's mean first.
    confidence : float
        Level of the band.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> g = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal((3000, 1))
    >>> frd = sysid.spa(sysid.IOData(u=u, y=g.simulate(u)), lags=40)
    >>> bool(frd.compare(g).relative_error.max() < 0.05)
    True
    """
    data = _need_data(data)
    N = data.n_samples
    M = int(min(N // 10, 30)) if lags is None else as_int(lags, "lags", 1)
    if M >= min(data.lengths):
        raise InsufficientDataError(
            f"lags = {M} needs experiments longer than {M} samples (shortest: "
            f"{min(data.lengths)})"
        )
    if omega is None:
        n_freq = as_int(n_freq, "n_freq", 2)
        w = np.arange(1, n_freq + 1) * np.pi / (n_freq * data.dt)
    else:
        w = np.asarray(omega, dtype=float).ravel()
        if not (np.isfinite(w).all() and (w >= 0).all()):
            raise DataError("omega must hold finite non-negative frequencies in rad/s")
    R, total = _lag_covariances(_z(data), M, remove_mean)
    tau = np.arange(M + 1)
    lagw = 0.5 * (1.0 + np.cos(np.pi * tau / M))
    # Phi(w) = sum_{tau=-M}^{M} w(tau) R(tau) e^{-i w tau dt}, R(-tau) = R(tau)^T
    E = np.exp(-1j * np.outer(w * data.dt, tau)) * lagw  # (n_freq, M+1)
    S = np.einsum("ft,tab->fab", E, R) + np.einsum("ft,tba->fab", E.conj(), R)
    S -= R[0][None]  # tau = 0 counted twice
    S *= 2.0 * data.dt  # one-sided density, as the Welch estimate
    m = data.n_inputs
    G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m)
    std, dof = _band(ratio, total / (lagw[0] ** 2 + 2.0 * (lagw[1:] ** 2).sum()), m,
                     "lower lags")
    return FRD(
        w[keep], G, coherence=coh, std=std, dof=dof, confidence=confidence,
        dt=data.dt, input_names=data.input_names, output_names=data.output_names,
        method="blackman-tukey",
        info={"lags": M, "window": "hann", "multiple_coherence": mcoh, "dropped": w[~keep]},
    )


def etfe(
    data: IOData,
    *,
    smoothing: int | None = None,
    window: str = "hann",
    min_power: float = 1e-12,
    confidence: float = 0.99,
) -> FRD:
    """Empirical transfer-function estimate ``Y(omega_k) / U(omega_k)`` on the FFT grid.

    Parameters
    ----------
    data : IOData
        Single-input records: one experiment, or several of equal length (averaged as
        ``sum Y U^* / sum |U|^2``). With ``m`` inputs: ``m`` or more experiments of equal
        length (``G = (sum Y U^H)(sum U U^H)^{-1}`` per frequency), or ``smoothing``.
    smoothing : int, optional
        Width in FFT bins of a frequency window (``window``) that smooths ``Y U^H`` and
        ``U U^H`` before dividing: trades resolution for variance, gives coherence and a
        confidence band, and makes MIMO estimates from one experiment possible
        (``smoothing > m``).
    window : str
        Frequency-window shape (``scipy.signal.get_window`` name).
    min_power : float
        Bins whose input power (trace of ``U U^H``) is below this fraction of the largest
        are left out: with a periodic multisine, ``1e-3`` keeps the excited lines only.
    confidence : float
        Level of the band (smoothed estimates only).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.random.default_rng(0).standard_normal(64)
    >>> y = np.convolve(u, [1.0, 0.5])[:64]
    >>> frd = sysid.etfe(sysid.IOData(u=u, y=y))
    >>> Y, U = np.fft.rfft(y), np.fft.rfft(u)
    >>> bool(np.allclose(frd.response[:, 0, 0], Y / U))
    True
    """
    data = _need_data(data)
    m, l = data.n_inputs, data.n_outputs
    lens = set(data.lengths)
    if len(lens) != 1:
        raise DataError(
            f"etfe needs experiments of equal length (got {sorted(lens)}); cut them to one "
            "length or use spa / welch_frf"
        )
    n = lens.pop()
    Zs = [np.fft.rfft(z, axis=0) for z in _z(data)]  # (nf, m+l)
    nf = Zs[0].shape[0]
    Puu = sum(np.einsum("fa,fb->fab", Z[:, :m], Z[:, :m].conj()) for Z in Zs) / n
    Pyu = sum(np.einsum("fa,fb->fab", Z[:, m:], Z[:, :m].conj()) for Z in Zs) / n
    Pyy = sum(np.einsum("fa,fb->fab", Z[:, m:], Z[:, m:].conj()) for Z in Zs) / n
    info: dict[str, Any] = {"smoothing": smoothing, "n_fft": n}
    if smoothing is None:
        if data.n_experiments < m:
            raise DataError(
                f"an unsmoothed ETFE with {m} inputs needs at least {m} experiments; give "
                f"smoothing > {m} (bins) or use spa / welch_frf"
            )
        S = np.zeros((nf, m + l, m + l), dtype=complex)
        S[:, :m, :m], S[:, m:, :m] = Puu, Pyu
        S[:, :m, m:] = np.conj(np.swapaxes(Pyu, 1, 2))
        S[:, m:, m:] = Pyy
        G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m, min_power)
        w = 2 * np.pi * np.fft.rfftfreq(n, data.dt)
        info["dropped"] = w[~keep]
        coh_out = coh if data.n_experiments > m else None
        return FRD(w[keep], G, coherence=coh_out, dt=data.dt, confidence=confidence,
                   input_names=data.input_names, output_names=data.output_names,
                   method="etfe", info=info)
    width = as_int(smoothing, "smoothing", 2)
    if width <= m:
        raise DataError(f"smoothing must exceed the number of inputs ({m}), got {width}")
    W = signal.get_window(window, width + 2)[1:-1] if window != "boxcar" else np.ones(width)
    W = W / W.sum()
    # smooth over the two-sided spectrum (periodic in frequency): mirror the one-sided one
    def smooth(P: np.ndarray) -> np.ndarray:
        full = np.concatenate([np.conj(P[1 : nf - (n % 2 == 0)][::-1]), P, ], axis=0)
        pad = nf - 1 - (n % 2 == 0)
        sm = (ndimage.convolve1d(full.real, W, axis=0, mode="wrap")
              + 1j * ndimage.convolve1d(full.imag, W, axis=0, mode="wrap"))
        return sm[pad:]

    S = np.zeros((nf, m + l, m + l), dtype=complex)
    S[:, :m, :m], S[:, m:, :m] = smooth(Puu), smooth(Pyu)
    S[:, :m, m:] = np.conj(np.swapaxes(S[:, m:, :m], 1, 2))
    S[:, m:, m:] = smooth(Pyy)
    G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m, min_power)
    w = 2 * np.pi * np.fft.rfftfreq(n, data.dt)
    info.update({"window": window, "multiple_coherence": mcoh, "dropped": w[~keep]})
    std, dof = _band(ratio, data.n_experiments / float((W**2).sum()), m, "increase smoothing")
    return FRD(w[keep], G, coherence=coh, std=std, dof=dof, confidence=confidence,
               dt=data.dt, input_names=data.input_names, output_names=data.output_names,
               method="etfe", info=info)


# --------------------------------------------------------------------------------------------
# spectra, coherence, correlation
# --------------------------------------------------------------------------------------------


class Spectra:
    """Auto and cross power spectral densities of every channel pair.

    Attributes
    ----------
    omega : ndarray
        Angular frequencies (rad/s).
    matrix : ndarray
        ``(n_freq, nc, nc)`` complex, ``matrix[:, a, b] = S_ab`` (one-sided density,
        units^2/Hz), channels ordered inputs then outputs.
    names : list of str
        Channel names in that order.
    method : str

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.random.default_rng(0).standard_normal(2048), y=np.zeros(2048))
    >>> s = sysid.spectra(d, nperseg=256)
    >>> s.psd("u0").shape
    (129,)
    """

    def __init__(self, omega: np.ndarray, matrix: np.ndarray, names: list[str], method: str,
                 info: dict[str, Any] | None = None) -> None:
        self.omega = omega
        self.matrix = matrix
        self.names = names
        self.method = method
        self.info = dict(info or {})

    @property
    def hz(self) -> np.ndarray:
        return self.omega / (2 * np.pi)

    def _i(self, name: str) -> int:
        if name not in self.names:
            raise DataError(f"no channel {name!r}; channels are {self.names}")
        return self.names.index(name)

    def psd(self, name: str) -> np.ndarray:
        """Power spectral density of one channel (real, units^2/Hz)."""
        i = self._i(name)
        return self.matrix[:, i, i].real.copy()

    def csd(self, a: str, b: str) -> np.ndarray:
        """Cross spectral density ``S_ab = E[Z_a Z_b^*]`` (equals ``scipy.signal.csd(b, a)``)."""
        return self.matrix[:, self._i(a), self._i(b)].copy()

    def plot(self, channels: Sequence[str] | None = None, *, ax: Any = None) -> Any:
        """Log-log plot of the auto spectra."""
        from ..plot.data import plot_spectra

        return plot_spectra(self, channels=channels, ax=ax)

    def __repr__(self) -> str:
        return (f"Spectra ({self.method}): {self.omega.size} frequencies up to "
                f"{self.omega[-1]:.3g} rad/s, channels {self.names}")


def spectra(
    data: IOData,
    *,
    nperseg: int | None = None,
    noverlap: int | None = None,
    window: str = "hann",
    nfft: int | None = None,
    detrend: bool = True,
) -> Spectra:
    """Welch estimate of all auto and cross spectra (as ``scipy.signal.welch``/``csd``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> x = np.random.default_rng(1).standard_normal(4096)
    >>> s = sysid.spectra(sysid.IOData(u=None, y=x, dt=0.5), nperseg=128)
    >>> bool(abs(s.psd("y0")[1:-1].mean() - 2 * 0.5) < 0.1)   # white: 2 sigma^2 dt
    True
    """
    data = _need_data(data, inputs=False)
    nperseg = _default_nperseg(data) if nperseg is None else as_int(nperseg, "nperseg", 2)
    noverlap = nperseg // 2 if noverlap is None else as_int(noverlap, "noverlap", 0)
    if noverlap >= nperseg:
        raise DataError(f"noverlap ({noverlap}) must be smaller than nperseg ({nperseg})")
    S, f, k_eff, count = _welch_matrix(_z(data), nperseg, noverlap, window, nfft, data.dt,
                                       detrend)
    return Spectra(2 * np.pi * f, S, _names(data), "welch",
                   {"nperseg": nperseg, "segments": count, "effective_averages": k_eff})


def periodogram(data: IOData, *, window: str = "boxcar", detrend: bool = True) -> Spectra:
    """Periodogram of every channel pair (one segment per experiment, the longest setting
    the FFT length; experiments averaged). As ``scipy.signal.periodogram``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> x = np.random.default_rng(2).standard_normal(100)
    >>> p = sysid.periodogram(sysid.IOData(u=None, y=x))
    >>> bool(np.allclose(p.psd("y0"), signal.periodogram(x)[1]))
    True
    """
    data = _need_data(data, inputs=False)
    nfft = max(data.lengths)
    S = None
    for z in _z(data):
        s, f, _, _ = _welch_matrix([z], z.shape[0], 0, window, nfft, data.dt, detrend)
        S = s * z.shape[0] if S is None else S + s * z.shape[0]
    assert S is not None
    return Spectra(2 * np.pi * f, S / data.n_samples, _names(data), "periodogram",
                   {"window": window})


class Coherence:
    """Magnitude-squared coherence of every output with every input.

    Attributes
    ----------
    omega : ndarray
        rad/s.
    values : ndarray
        ``(n_freq, n_outputs, n_inputs)``, ``|S_yu|^2 / (S_yy S_uu)`` in [0, 1].
    multiple : ndarray
        ``(n_freq, n_outputs)``: share of each output's power explained linearly by all
        inputs together (equals ``values`` for one input).
    """

    def __init__(self, omega: np.ndarray, values: np.ndarray, multiple: np.ndarray,
                 input_names: list[str], output_names: list[str]) -> None:
        self.omega = omega
        self.values = values
        self.multiple = multiple
        self.input_names = input_names
        self.output_names = output_names

    @property
    def hz(self) -> np.ndarray:
        return self.omega / (2 * np.pi)

    def pair(self, output: str, input: str) -> np.ndarray:
        """Coherence of one output/input pair."""
        if output not in self.output_names or input not in self.input_names:
            raise DataError(f"unknown pair ({output!r}, {input!r}); outputs "
                            f"{self.output_names}, inputs {self.input_names}")
        return self.values[:, self.output_names.index(output), self.input_names.index(input)]

    def band(self, threshold: float = 0.6) -> np.ndarray:
        """Boolean ``(n_freq, l, m)``: where the coherence exceeds ``threshold`` (flight-test
        practice trusts frequency responses only there)."""
        return self.values > threshold

    def plot(self, *, fig: Any = None, threshold: float | None = 0.6) -> Any:
        """One panel per input, every output's coherence against frequency."""
        from ..plot.data import plot_coherence

        return plot_coherence(self, fig=fig, threshold=threshold)

    def __repr__(self) -> str:
        mean = self.values.mean(axis=0)
        pairs = ", ".join(
            f"{o}/{i} {mean[a, b]:.2f}" for a, o in enumerate(self.output_names)
            for b, i in enumerate(self.input_names)
        )
        return f"Coherence: {self.omega.size} frequencies; mean per pair: {pairs}"


def coherence(
    data: IOData,
    *,
    nperseg: int | None = None,
    noverlap: int | None = None,
    window: str = "hann",
) -> Coherence:
    """Magnitude-squared coherence per output/input pair (Welch; as
    ``scipy.signal.coherence``) and the multiple coherence of each output.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.random.default_rng(0).standard_normal(4096)
    >>> c = sysid.coherence(sysid.IOData(u=u, y=np.convolve(u, [1.0, 0.5])[:4096]))
    >>> bool(c.values.min() > 0.99)
    True
    """
    data = _need_data(data)
    s = spectra(data, nperseg=nperseg, noverlap=noverlap, window=window)
    m = data.n_inputs
    S = s.matrix
    du = np.einsum("fjj->fj", S[:, :m, :m]).real
    dy = np.einsum("fii->fi", S[:, m:, m:]).real
    tiny = np.finfo(float).tiny
    vals = np.abs(S[:, m:, :m]) ** 2 / np.maximum(dy[:, :, None] * du[:, None, :], tiny)
    mult = np.zeros_like(dy)
    for k in range(S.shape[0]):
        Suu = S[k, :m, :m]
        if np.linalg.cond(Suu) < _COND_LIMIT:
            Syu = S[k, m:, :m]
            mult[k] = np.einsum("ij,ji->i", Syu @ np.linalg.inv(Suu), Syu.conj().T).real
    mult = mult / np.maximum(dy, tiny)
    return Coherence(s.omega, np.clip(vals, 0, 1), np.clip(mult, 0, 1), list(data.input_names),
                     list(data.output_names))


class Correlation:
    """Auto and cross correlation coefficients of every channel pair with confidence bounds.

    Attributes
    ----------
    lags : ndarray
        ``-max_lag .. max_lag`` (samples).
    values : ndarray
        ``(n_lags, nc, nc)``: ``values[k, a, b] = r_ab(lags[k])``, the correlation of
        ``z_a(t + tau)`` with ``z_b(t)`` normalised by ``sqrt(R_aa(0) R_bb(0))``.
    bound : float
        ``z_{(1+p)/2} / sqrt(N)``: under the hypothesis of white, mutually uncorrelated
        channels, a coefficient lies within +- bound with probability ``confidence``.
    names : list of str
    """

    def __init__(self, lags: np.ndarray, values: np.ndarray, bound: float, confidence: float,
                 names: list[str], dt: float) -> None:
        self.lags = lags
        self.values = values
        self.bound = bound
        self.confidence = confidence
        self.names = names
        self.dt = dt

    def pair(self, a: str, b: str) -> np.ndarray:
        """``r_ab(tau)`` for all lags."""
        for n in (a, b):
            if n not in self.names:
                raise DataError(f"no channel {n!r}; channels are {self.names}")
        return self.values[:, self.names.index(a), self.names.index(b)]

    def significant(self, a: str, b: str) -> np.ndarray:
        """Lags where ``|r_ab|`` exceeds the bound (auto-correlations: lag 0 excluded)."""
        r = self.pair(a, b)
        out = np.abs(r) > self.bound
        if a == b:
            out &= self.lags != 0
        return self.lags[out]

    def plot(self, a: str, b: str, *, ax: Any = None) -> Any:
        """Stem plot of ``r_ab`` with the confidence bounds."""
        from ..plot.data import plot_correlation

        return plot_correlation(self, a, b, ax=ax)

    def __repr__(self) -> str:
        return (f"Correlation: lags {self.lags[0]}..{self.lags[-1]}, channels {self.names}, "
                f"{self.confidence:.0%} bound +-{self.bound:.3g}")


def correlation(
    data: IOData, max_lag: int = 25, *, confidence: float = 0.99, remove_mean: bool = True
) -> Correlation:
    """Auto and cross correlations of all channels (inputs then outputs) up to ``max_lag``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.random.default_rng(0).standard_normal(2000)
    >>> y = np.concatenate([[0.0, 0.0, 0.0], u[:-3]])        # a pure delay of 3 samples
    >>> c = sysid.correlation(sysid.IOData(u=u, y=y), 10)
    >>> c.significant("y0", "u0").tolist()
    [3]
    """
    data = _need_data(data, inputs=False)
    L = as_int(max_lag, "max_lag", 0)
    if L >= min(data.lengths):
        raise InsufficientDataError(f"max_lag = {L} needs experiments longer than {L} samples")
    if not 0.0 < confidence < 1.0:
        raise DataError(f"confidence must lie in (0, 1), got {confidence}")
    R, total = _lag_covariances(_z(data), L, remove_mean)
    d = np.sqrt(np.maximum(np.einsum("aa->a", R[0]), np.finfo(float).tiny))
    Rn = R / np.outer(d, d)[None]
    # negative lags: r_ab(-tau) = r_ba(tau)
    vals = np.concatenate([np.swapaxes(Rn[1:][::-1], 1, 2), Rn], axis=0)
    bound = float(stats.norm.ppf(0.5 + confidence / 2) / np.sqrt(total))
    return Correlation(np.arange(-L, L + 1), vals, bound, confidence, _names(data), data.dt)
