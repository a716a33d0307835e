"""Non-parametric frequency-response estimates: Welch (:func:`welch_frf`), Blackman-Tukey
(:func:`spa`) and the smoothed empirical transfer-function estimate (:func:`etfe`), each an
:class:`~sysid.FRD` with a confidence band. Spectra and coherence are in
:mod:`sysid.nonparametric.spectra`, correlation in :mod:`sysid.nonparametric.correlation`.

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
``sigma sqrt(-ln(1 - p))`` for large ``K``. At zero frequency and at the Nyquist frequency
the spectra of real records are real, and so is the error: ``(1, K - m)`` degrees of freedom
there (:func:`sysid.models.frd.band_quantile`). Frequencies are angular, in rad/s.

Spectra are one-sided densities in units^2/Hz, as ``scipy.signal.welch``. Several
experiments are averaged (no segment or lag spans two). Frequencies where the input
spectrum is singular (no excitation) are left out of frequency responses and listed in
``FRD.info["dropped"]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage

from .._checks import as_between, as_int, as_nonnegative, check_elements, constant_channels
from ..data.iodata import IOData
from ..errors import DataError, ExcitationError, InsufficientDataError
from ..models.frd import FRD, band_quantile
from .correlation import _lag_covariances
from .spectra import (
    _band,
    _default_nperseg,
    _frf_from_S,
    _need_data,
    _welch_matrix,
    _window,
    _z_scaled,
)

__all__ = ["welch_frf", "spa", "etfe", "default_lags"]

#: Lag window width over the last significant lag, the first width the bias check tries: the
#: Hann window then weighs every lag with a visible correlation by at least
#: ``0.5 (1 + cos(pi / 6)) = 0.93``.
LAGS_PER_SIGNIFICANT_LAG = 6
#: A correlation is significant above this many standard deviations of its noise.
SIGNIFICANCE = 4.5
#: The bias check's chance of a false alarm: the two estimates it compares must agree within
#: the band whose level leaves this probability to be shared by every compared point
#: (frequency and output/input pair; see :func:`default_lags`).
BIAS_CHECK_ALPHA = 0.1


def _hann_lags(M: int) -> np.ndarray:
    """The Hann lag window ``0.5 (1 + cos(pi tau / M))`` at ``tau = 0..M``."""
    return 0.5 * (1.0 + np.cos(np.pi * np.arange(M + 1) / M))


def _bias_check(R: np.ndarray, total: int, m: int, M: int) -> bool:
    """Whether the Blackman-Tukey frequency responses with ``M // 2`` and ``M`` lags (Hann
    windows, from the covariances ``R``) agree within the band of the one with ``M // 2``,
    at every frequency of a grid that resolves the wider window (four points per main lobe)
    and every output/input pair; frequencies without input power are not compared. The
    band's level is ``1 - BIAS_CHECK_ALPHA / points`` (Bonferroni), so noise alone fails
    the check rarely however many points are compared."""
    nfft = max(256, 1 << int(np.ceil(np.log2(2 * M))))
    out = []
    for lags in (M // 2, M):
        lagw = _hann_lags(lags)
        c = R[: lags + 1] * lagw[:, None, None]
        F = np.fft.rfft(c, n=nfft, axis=0)[1:]  # sum_tau c(tau) e^{-i w tau}, w > 0
        S = F + np.conj(np.swapaxes(F, 1, 2)) - c[0][None]  # R(-tau) = R(tau)^T
        k_eff = total / (lagw[0] ** 2 + 2.0 * (lagw[1:] ** 2).sum())
        G, _, _, ratio, keep, _ = _frf_from_S(S, m, averages=k_eff)
        full = np.full((keep.size,) + G.shape[1:], np.nan, dtype=complex)
        sd = np.full((keep.size,) + G.shape[1:], np.nan)
        full[keep] = G
        sd[keep] = np.sqrt(ratio / max(k_eff - m, 1.0))
        out.append((full, sd, k_eff))
    (G1, sd1, k1), (G2, _, _) = out
    both = np.isfinite(G1) & np.isfinite(G2)
    level = 1.0 - BIAS_CHECK_ALPHA / max(int(both.sum()), 1)
    nyquist = np.arange(1, G1.shape[0] + 1) == nfft // 2  # a real line: band_quantile's rule
    radius = sd1 * np.sqrt(band_quantile(level, 2.0 * max(k1 - m, 1.0),
                                         nyquist[:, None, None] & (nfft % 2 == 0)))
    return bool(np.all(np.abs(G1 - G2)[both] <= radius[both]))


def default_lags(data: IOData, remove_mean: bool = True) -> tuple[int, dict[str, Any]]:
    """Lag window width for :func:`spa` chosen from where the covariances decay into noise
    and checked for the lag window's bias.

    The correlation coefficients ``r_ab(tau)`` of the input-input and output-input channel
    pairs (both signs of the lag) are compared with their noise level under independence,
    ``sqrt((1 + 2 sum_k r_aa(k) r_bb(k)) / N)`` (Bartlett's formula), for lags up to
    ``min(N / 10, shortest experiment - 1, 2000)``. The last lag ``tau_d`` at which any of
    them exceeds ``4.5`` noise levels is where the response has decayed into the noise.

    That alone does not bound the bias: the Hann window's bias falls as ``1 / M^2`` while
    the band narrows only as ``sqrt(M / N)``, so at any fixed multiple of ``tau_d`` a
    resonance on a long, quiet record is smoothed beyond its band (at ``M = 6 tau_d``, of
    ``(0.3 q^-1 + 0.2 q^-2) / (1 - 1.2 q^-1 + 0.6 q^-2)`` with 2000-32000 samples, the 99 %
    band held the truth near the resonance in 36-94 % of runs). Hence a bias check: starting
    at ``M = 6 tau_d`` (at least 10), ``M`` is doubled until the estimate with ``M / 2`` lags
    lies within the band of its own around the estimate with ``M``, at every frequency and
    output/input pair (the band's level ``1 - 0.1 / points``, Bonferroni over the compared
    points, so that noise alone rarely fails it). The bias falling as ``1 / M^2``, their
    difference is three quarters of the bias at ``M / 2``, and the bias left at ``M`` at most
    about 0.65 (one pair, ``M`` up to 128) to 0.8 (many pairs and frequencies) standard
    deviations of the estimate: the 99 % band then holds the truth with probability at
    least 0.97 to 0.95 (measured on the system above: at least 0.96 at every frequency in
    200 runs). A chance disagreement only doubles ``M``, widening the band.
    ``M`` stops at the lag limit; ``info["bias_check"]`` then reads ``"lag limit reached"``
    when the estimates with ``limit / 2`` and ``limit`` lags still disagree (pass ``lags=``
    and compare, or measure longer), else ``"passed"``.

    Returns
    -------
    (int, dict)
        ``M`` and the record of the choice (``lags_rule``, ``significant_lag``,
        ``max_lag``, ``bias_check``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((20000, 1))
    >>> slow = sysid.StateSpaceModel([[0.95]], [[1.0]], [[1.0]])
    >>> fast = sysid.StateSpaceModel([[0.3]], [[1.0]], [[1.0]])
    >>> m_slow = sysid.default_lags(sysid.IOData(u=u, y=slow.simulate(u)))[0]
    >>> m_fast = sysid.default_lags(sysid.IOData(u=u, y=fast.simulate(u)))[0]
    >>> bool(m_slow > 4 * m_fast)
    True
    """
    data = _need_data(data, who="default_lags")
    shortest = min(data.lengths)
    limit = int(max(1, min(data.n_samples // 10, shortest - 1, 2000)))
    R, total = _lag_covariances(_z_scaled(data, per_channel=True)[0], limit, remove_mean)
    sd = np.sqrt(np.clip(np.diag(R[0]), np.finfo(float).tiny, None))
    rho = R / np.outer(sd, sd)
    auto = np.einsum("kaa->ka", rho)
    spread = 1.0 + 2.0 * np.einsum("ka,kb->ab", auto[1:], auto[1:])
    noise = np.sqrt(np.clip(spread, 1.0, None) / total)
    m = data.n_inputs
    pairs = np.ones_like(noise, dtype=bool)
    pairs[m:, m:] = False  # output-output correlations carry the noise model, not G
    if m == 0:
        pairs[:] = True
    big = (np.abs(rho[1:]) > SIGNIFICANCE * noise[None]) & pairs[None]
    hits = np.nonzero(big.any(axis=(1, 2)))[0]
    tau_d = int(hits[-1] + 1) if hits.size else 0
    M = max(10, LAGS_PER_SIGNIFICANT_LAG * tau_d)
    # the responses are ratios of the scaled channels' spectra: their units cancel in the check
    while M < limit and not _bias_check(R, total, m, M):
        M *= 2
    if M >= limit:
        M = limit
        check = "passed" if limit >= 2 and _bias_check(R, total, m, limit) else \
            "lag limit reached"
    else:
        check = "passed"
    rule = "data: 6 x last significant lag, doubled until the bias check passes"
    return int(M), {"lags_rule": rule, "significant_lag": tau_d, "max_lag": limit,
                    "bias_check": check}


# --------------------------------------------------------------------------------------------
# frequency responses
# --------------------------------------------------------------------------------------------


def check_omega(omega: Any, dt: float, positive: bool = False) -> np.ndarray:
    """A requested frequency grid (rad/s) as a 1-D array: non-empty, finite, non-negative
    (``positive``: above zero), at most the Nyquist frequency ``pi / dt``; else a
    :class:`DataError` that says which."""
    w = np.asarray(omega, dtype=float)
    if np.squeeze(w).ndim > 1 or w.size == 0:  # a column vector is one grid too
        raise DataError(f"omega must be a non-empty 1-D array of frequencies in rad/s, got "
                        f"shape {w.shape}")
    w = w.ravel()
    if not (np.isfinite(w).all() and ((w > 0) if positive else (w >= 0)).all()):
        raise DataError(f"omega must hold finite {'positive' if positive else 'non-negative'} "
                        "frequencies in rad/s")
    nyquist = np.pi / dt
    if w.max() > nyquist * (1 + 1e-9):
        raise DataError(
            f"omega reaches {w.max():.4g} rad/s, above the Nyquist frequency pi/dt = "
            f"{nyquist:.4g} rad/s: sampled data say nothing there (the estimate would be "
            "an alias of a lower frequency). Give omega in rad/s up to pi/dt (in Hz? "
            "multiply by 2 pi)")
    return w


def _constant_inputs(data: IOData) -> np.ndarray:
    """Per input, whether it is constant in every experiment (:func:`sysid._checks.
    constant_channels`, each experiment about its own level): it has no power but at zero
    frequency."""
    return constant_channels([u for u, _ in data.experiments], "each")


def _need_excitation(keep: np.ndarray, what: str, data: IOData | None = None) -> None:
    """Raise when no frequency is left: no input power, constant inputs, or inputs that are
    linearly dependent at every frequency (a singular input spectral matrix)."""
    if np.any(keep):
        return
    if data is not None and data.n_inputs > 1:
        varying = ~_constant_inputs(data)
        names = list(data.input_names)
        if varying.any() and not varying.all():
            flat = [n for n, v in zip(names, varying) if not v]
            raise ExcitationError(
                f"{what}: input(s) {flat} are constant, so their responses cannot be "
                "estimated and the input spectral matrix is singular; leave them out "
                "(data.select(inputs=...)) or excite them")
        if varying.all():
            raise ExcitationError(
                f"{what}: the {len(names)} inputs {names} are linearly dependent at every "
                "frequency (their spectral matrix is singular: one input a copy, a multiple "
                "or a filtered version of another, or a sum of others), so their separate "
                "responses cannot be told apart; excite the inputs independently, or "
                "estimate the response to one input at a time (data.select(inputs=...))")
    raise ExcitationError(
        f"{what}: the input has no power at any frequency (an all-zero or constant "
        "input?), so there is no frequency response to estimate; check the input "
        "channels, or use output-only analysis (sysid.spectra) for time series"
    )


def _units(G: np.ndarray, std: np.ndarray | None, s: np.ndarray, m: int
           ) -> tuple[np.ndarray, np.ndarray | None]:
    """A frequency response and its standard deviation estimated from :func:`_z_scaled`
    channels (units ``s``), in the data's units (``s_y / s_u``); a :class:`DataError` when
    they overflow double precision."""
    if np.all(s == 1.0):
        return G, std
    with np.errstate(over="ignore", invalid="ignore"):
        k = s[m:][:, None] / s[:m][None, :]
        G, std = G * k, None if std is None else std * k
    if not (np.all(np.isfinite(G)) and (std is None or np.all(np.isfinite(std)))):
        raise DataError(
            f"the outputs (magnitudes of order {s[m:].max():.1e}) over the inputs (of order "
            f"{s[:m].max():.1e}) give a frequency response beyond double precision; rescale "
            "the channels (other units) so that their magnitudes are comparable")
    return G, std


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
        Segment length (default: a power of two up to 256, a quarter of a single record; with
        several experiments the largest every one holds that gives seven segments in all).
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
    data = _need_data(data, who="welch_frf")
    confidence = as_between(confidence, "confidence", 0.0, 1.0)  # before the spectra
    nperseg = _default_nperseg(data) if nperseg is None else as_int(nperseg, "nperseg", 2)
    noverlap = nperseg // 2 if noverlap is None else as_int(noverlap, "noverlap", 0)
    if noverlap >= nperseg:
        raise DataError(f"noverlap ({noverlap}) must be smaller than nperseg ({nperseg})")
    zs, s = _z_scaled(data)
    S, f, k_eff, count = _welch_matrix(zs, nperseg, noverlap, window, nfft, data.dt, True)
    m = data.n_inputs
    if count <= m:
        raise InsufficientDataError(
            f"{count} segment(s) for {m} input(s): the H1 estimate needs more segments than "
            "inputs; lower nperseg"
        )
    # segment means are removed: the zero-frequency bin carries no information
    S, f = S[1:], f[1:]
    G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m, averages=k_eff)
    _need_excitation(keep, "welch_frf", data)
    std, dof = _band(ratio, k_eff, m, "lower nperseg")
    G, std = _units(G, std, s, m)
    return FRD(
        2 * np.pi * f[keep], G, coherence=coh, std=std, dof=dof,
        confidence=confidence, dt=data.dt, input_names=data.input_names,
        output_names=data.output_names, method="welch",
        info={"nperseg": nperseg, "noverlap": noverlap, "window": window, "segments": count,
              "effective_averages": k_eff, "multiple_coherence": mcoh,
              "dropped": 2 * np.pi * f[~keep]},
    )


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
        Lag window width ``M``; larger ``M`` means less bias, more variance. Default: chosen
        from the data by :func:`default_lags` (six times the last lag at which an input-input
        or output-input correlation stands out of its noise, doubled until the estimates
        with ``M / 2`` and ``M`` lags agree within the band), so that the lag window does
        not bias the estimate beyond its band (up to the lag limit ``min(N / 10, 2000)``);
        the rule and the lag are recorded in ``info`` (``"lags"``, ``"lags_rule"``,
        ``"significant_lag"``, ``"bias_check"``). MATLAB's fixed ``min(N / 10, 30)``
        truncates slowly decaying responses and makes the band dishonest.
    omega : array_like, optional
        Angular frequencies (rad/s) up to the Nyquist frequency ``pi / dt`` (above it: an
        error); default ``n_freq`` points up to Nyquist.
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
    data = _need_data(data, who="spa")
    confidence = as_between(confidence, "confidence", 0.0, 1.0)  # before the spectra
    N = data.n_samples
    lag_info: dict[str, Any] = {"lags_rule": "given"}
    if lags is None:
        if N // 10 < 2:
            raise InsufficientDataError(
                f"spa's default lag window needs at least 20 samples, the record has {N}; "
                f"pass lags=... (>= 1, below the shortest experiment) or use more data"
            )
        M, lag_info = default_lags(data, remove_mean)
    else:
        M = as_int(lags, "lags", 1)
    if M >= min(data.lengths):
        raise InsufficientDataError(
            f"lags = {M} needs experiments longer than {M} samples (shortest: "
            f"{min(data.lengths)})"
        )
    if omega is None:
        n_freq = as_int(n_freq, "n_freq", 2)
        # E (n_freq, M + 1) complex and a few (n_freq, nc, nc) complex spectral matrices
        nc = data.n_inputs + data.n_outputs
        check_elements(n_freq * (2 * (M + 2) + 8 * nc * nc), f"spa with n_freq = {n_freq}",
                       f"pass a smaller n_freq (the lag window of {M} lags resolves about "
                       f"{M} frequencies; a few times that is plenty), or omega=... with "
                       "the frequencies you need")
        w = np.arange(1, n_freq + 1) * np.pi / (n_freq * data.dt)
    else:
        w = check_omega(omega, data.dt)
    zs, s = _z_scaled(data)
    R, total = _lag_covariances(zs, M, remove_mean)
    tau = np.arange(M + 1)
    lagw = 0.5 * (1.0 + np.cos(np.pi * tau / M))
    # Phi(w) = sum_{tau=-M}^{M} w(tau) R(tau) e^{-i w tau dt}, R(-tau) = R(tau)^T
    E = np.exp(-1j * np.outer(w * data.dt, tau)) * lagw  # (n_freq, M+1)
    S = np.einsum("ft,tab->fab", E, R) + np.einsum("ft,tba->fab", E.conj(), R)
    S -= R[0][None]  # tau = 0 counted twice
    S *= 2.0 * data.dt  # one-sided density, as the Welch estimate
    m = data.n_inputs
    k_eff = total / (lagw[0] ** 2 + 2.0 * (lagw[1:] ** 2).sum())
    G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m, averages=k_eff)
    _need_excitation(keep, "spa", data)
    std, dof = _band(ratio, k_eff, m, "lower lags")
    G, std = _units(G, std, s, m)
    return FRD(
        w[keep], G, coherence=coh, std=std, dof=dof, confidence=confidence,
        dt=data.dt, input_names=data.input_names, output_names=data.output_names,
        method="blackman-tukey",
        info={"lags": M, "window": "hann", "multiple_coherence": mcoh, "dropped": w[~keep],
              **lag_info},
    )


def etfe(
    data: IOData,
    *,
    smoothing: int | None = None,
    window: str = "hann",
    min_power: float = 1e-12,
    confidence: float = 0.99,
    remove_mean: bool | None = None,
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
        (``smoothing > m``). The window is centred on each bin, so its width is odd: an
        even ``smoothing`` is rounded up to the next odd width (down when that would exceed
        the ``n`` bins of an ``n``-sample experiment); the width used is
        ``info["window_bins"]``.
    window : str
        Frequency-window shape (``scipy.signal.get_window`` name), taken in its symmetric
        form with its zero end points left out (``"hann"`` over ``w`` bins, ``w`` odd: the
        symmetric Hann window of ``w + 2`` points without its ends).
    min_power : float
        Bins whose input power (trace of ``U U^H``) is below this fraction of the largest
        are left out: with a periodic multisine, ``1e-3`` keeps the excited lines only.
    confidence : float
        Level of the band (smoothed estimates only).
    remove_mean : bool, optional
        Subtract each experiment's mean first (the zero-frequency bin then has no input
        power and is left out). Default: with ``smoothing``, as :func:`spa` and
        :func:`welch_frf` do (an operating point leaks from the zero bin into its smoothed
        neighbours: near DC the estimate was the ratio of the means, coherence 1, a band
        that missed the truth); without, the raw ``Y / U`` on every bin (of a periodic
        record in steady state, the zero bin is the static gain).

    An input constant in every experiment is refused with or without ``smoothing`` (an
    :class:`~sysid.ExcitationError`, as :func:`spa` and :func:`welch_frf` give): unsmoothed,
    it left a one-point response at zero frequency, the ratio of the means.

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
    data = _need_data(data, who="etfe")
    confidence = as_between(confidence, "confidence", 0.0, 1.0)  # before the spectra
    min_power = as_nonnegative(min_power, "min_power")
    m, l = data.n_inputs, data.n_outputs
    lens = set(data.lengths)
    if len(lens) != 1:
        raise DataError(
            f"etfe needs experiments of equal length (got {sorted(lens)}); cut them to one "
            "length or use spa / welch_frf"
        )
    n = lens.pop()
    if n < 4:
        raise InsufficientDataError(
            f"etfe needs at least 4 samples per experiment (got {n}): n samples give "
            f"n // 2 frequencies above zero; measure a longer record"
        )
    if _constant_inputs(data).any():
        # unsmoothed, a constant input gave a one-point FRD at zero frequency, the ratio of
        # the means: refused as spa, welch_frf and smoothed etfe refuse it, in their words
        _need_excitation(np.zeros(1, dtype=bool), "etfe", data)
    if remove_mean is None:
        remove_mean = smoothing is not None
    zs, s = _z_scaled(data)
    Zs = [np.fft.rfft(z - z.mean(axis=0) if remove_mean else z, axis=0)
          for z in zs]  # (nf, m+l)
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
        _need_excitation(keep, "etfe", data)
        w = 2 * np.pi * np.fft.rfftfreq(n, data.dt)
        info["dropped"] = w[~keep]
        coh_out = coh if data.n_experiments > m else None
        G, _ = _units(G, None, s, m)
        return FRD(w[keep], G, coherence=coh_out, dt=data.dt, confidence=confidence,
                   input_names=data.input_names, output_names=data.output_names,
                   method="etfe", info=info)
    width = as_int(smoothing, "smoothing", 2)
    if width <= m:
        raise DataError(f"smoothing must exceed the number of inputs ({m}), got {width}")
    if width > n:
        # a window wider than the n bins of the (two-sided, circular) spectrum wraps onto
        # bins it already holds: 1 / sum(W^2) then counts them twice, and the band shrank
        raise DataError(
            f"smoothing = {width} bins is wider than the spectrum of a {n}-sample experiment "
            f"({n} bins around the circle): give smoothing <= {n} (a few per cent of it keeps "
            "the resolution), or use spa / welch_frf"
        )
    # a window centred on each bin: symmetric, of an odd number of bins (a periodic or
    # even-length one put its centre half a bin off, a phase error of pi D / n rad on a
    # delay of D samples: +6.9 degrees for D = 20, n = 512)
    bins = (width | 1) if width < n else width - 1 + width % 2  # odd, at most n
    W = (_window(window, bins + 2, fftbins=False)[1:-1] if window != "boxcar"
         else np.ones(bins))
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
    k_eff = data.n_experiments / float((W**2).sum())
    G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m, min_power, averages=k_eff)
    _need_excitation(keep, "etfe", data)
    w = 2 * np.pi * np.fft.rfftfreq(n, data.dt)
    info.update({"window": window, "window_bins": bins, "multiple_coherence": mcoh,
                 "dropped": w[~keep]})
    std, dof = _band(ratio, k_eff, m, "increase smoothing")
    G, std = _units(G, std, s, m)
    return FRD(w[keep], G, coherence=coh, std=std, dof=dof, confidence=confidence,
               dt=data.dt, input_names=data.input_names, output_names=data.output_names,
               method="etfe", info=info)
