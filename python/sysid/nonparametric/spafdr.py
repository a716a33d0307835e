"""Spectral analysis with frequency-dependent resolution (MATLAB's ``spafdr``).

:func:`spa` and :func:`welch_frf` resolve every frequency equally finely: on a logarithmic
axis their estimate is noisy at high frequencies and coarse at low ones. ``spafdr`` smooths
the cross-periodograms of the record's Fourier transform around each requested frequency
``w_k`` with a Hann window of half-width ``R_k`` (the resolution, rad/s), so that a grid
from a decade below a resonance to the Nyquist frequency gets a resolution proportional to
frequency: fine near the slow modes, averaging many lines at high frequencies.

Per frequency the smoothed spectral matrix gives ``G = S_yu S_uu^{-1}``, the coherence and
the noise spectrum, as the other estimators in :mod:`sysid.nonparametric.frf`; the
equivalent number of averages is ``K_k = (sum W)^2 / sum W^2`` over the lines the window
covers (all experiments). The standard deviation of each entry uses its own ``K_k``; the
:class:`~sysid.FRD` carries one number of degrees of freedom for its band, the smallest
``2 (K_k - m)`` (a band that is conservative where more lines were averaged).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_between, as_int, check_elements, require_inputs_vary
from ..data.iodata import IOData
from ..errors import DataError, ExcitationError, InsufficientDataError
from ..models.frd import FRD
from .frf import _units, check_omega
from .spectra import _frf_from_S, _need_data, _z_scaled

__all__ = ["spafdr"]


def _grid(data: IOData, omega: Any, n_freq: int) -> np.ndarray:
    nyquist = np.pi / data.dt
    if omega is None:
        n_freq = as_int(n_freq, "n_freq", 2)
        check_elements(n_freq * (data.n_inputs + data.n_outputs) ** 2 * 4,
                       f"n_freq = {n_freq}", "pass a smaller n_freq (a few hundred "
                       "frequencies resolve any response) or omega")
        lowest = 2 * np.pi / (min(data.lengths) * data.dt)  # the first line of the record
        return np.logspace(np.log10(2 * lowest), np.log10(nyquist), n_freq)
    return check_omega(omega, data.dt, positive=True)


def _resolution(w: np.ndarray, resolution: Any) -> np.ndarray:
    if resolution is None:  # the grid's own spacing: constant resolution per decade
        lw = np.log(w)
        step = np.gradient(lw) if w.size > 1 else np.array([np.log(2.0)])
        return w * np.abs(step)
    r = np.asarray(resolution, dtype=float)
    if r.ndim == 0:
        r = np.full(w.size, float(r))
    if r.shape != w.shape:
        raise DataError(f"resolution must be one number or one per frequency ({w.size}), got "
                        f"shape {r.shape}")
    if not (np.all(np.isfinite(r)) and np.all(r > 0)):
        raise DataError("resolution must hold finite positive widths in rad/s")
    return r


def _window(omega: np.ndarray, P: np.ndarray, wk: float, rk: float, nyquist: float
            ) -> tuple[np.ndarray, np.ndarray]:
    """Hann weights of the lines within ``rk`` of ``wk`` and their periodograms. The part of
    the window beyond the Nyquist frequency (or below zero) takes the lines mirrored there:
    the spectra of real signals are conjugate-symmetric about both (at the Nyquist frequency
    itself the window was one-sided, and a resonance there came out 27 % low and complex)."""
    lo, hi = np.searchsorted(omega, [wk - rk, wk + rk], side="right")
    d, Pk = [omega[lo:hi] - wk], [P[lo:hi]]
    if wk + rk > nyquist:  # lines at 2 nyquist - omega, below the Nyquist line itself
        a, b = np.searchsorted(omega, [2 * nyquist - wk - rk, nyquist], side="left")
        d.append(2 * nyquist - omega[a:b] - wk)
        Pk.append(P[a:b].conj())
    if wk - rk < 0:  # lines at -omega
        b = np.searchsorted(omega, rk - wk, side="left")
        d.append(-omega[:b] - wk)
        Pk.append(P[:b].conj())
    dd = np.concatenate(d)
    return 0.5 * (1.0 + np.cos(np.pi * dd / rk)), np.concatenate(Pk)


def spafdr(
    data: IOData,
    resolution: Any = None,
    omega: Any = None,
    *,
    n_freq: int = 128,
    confidence: float = 0.99,
) -> FRD:
    """Frequency response with frequency-dependent resolution (MATLAB's ``spafdr``).

    Parameters
    ----------
    data : IOData
        One or several experiments (each's mean removed); any number of inputs and outputs.
    resolution : float or array_like, optional
        Half-width (rad/s) of the Hann frequency window at each frequency; default the
        spacing of the logarithmic grid (about ``w / 20`` at 128 frequencies over three
        decades), widened where it would hold fewer than ``m + 2`` lines of the record
        (``info["resolution"]`` holds what was used).
    omega : array_like, optional
        Frequencies (rad/s, up to ``pi / dt``); default ``n_freq`` logarithmically spaced
        from twice the record's first line to the Nyquist frequency.
    n_freq : int
    confidence : float
        Level of the band.

    Returns
    -------
    FRD
        With coherence and a band; ``info``: ``resolution``, ``averages`` (``K_k``),
        ``dropped`` (frequencies without input power).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> g = sysid.StateSpaceModel([[1.6, -0.9], [1.0, 0.0]], [[1.0], [0.0]], [[0.1, 0.0]])
    >>> u = rng.standard_normal((20000, 1))
    >>> frd = sysid.spafdr(sysid.IOData(u=u, y=g.simulate(u)))
    >>> err = frd.compare(g).relative_error   # noise-free: leakage and smoothing only
    >>> frd.omega.size, bool(np.median(err) < 0.01), bool(err.max() < 0.1)
    (128, True, True)
    """
    data = _need_data(data, who="spafdr")
    confidence = as_between(confidence, "confidence", 0.0, 1.0)  # before the spectra
    if min(data.lengths) < 2:
        raise InsufficientDataError(f"spafdr needs experiments of at least 2 samples, got "
                                    f"{min(data.lengths)}")
    # inputs constant or recorded twice: named, not "0.0 spectra ... widen the resolution"
    require_inputs_vary(data.experiments, "spafdr", data.input_names, error=ExcitationError)
    w = _grid(data, omega, n_freq)
    m = data.n_inputs
    zs, s = _z_scaled(data)
    nc = zs[0].shape[1]
    check_elements(sum(z.shape[0] for z in zs) * nc * nc * 2 + w.size * nc * nc * 2,
                   f"spafdr of {data.n_samples} samples with {nc} channels",
                   "decimate the record (sysid.decimate) or pass fewer channels")
    lines, grams = [], []
    for z in zs:
        n = z.shape[0]
        Z = np.fft.rfft(z - z.mean(axis=0), axis=0)[1:]  # no zero line: the mean is removed
        lines.append(2 * np.pi * np.fft.rfftfreq(n, data.dt)[1:])
        grams.append(np.einsum("fa,fb->fab", Z, Z.conj()) / n)
    omega_all = np.concatenate(lines)
    P = np.concatenate(grams)
    order = np.argsort(omega_all, kind="stable")
    omega_all, P = omega_all[order], P[order]
    spacing = 2 * np.pi / (max(data.lengths) * data.dt)
    R = np.maximum(_resolution(w, resolution), (m + 2) * spacing)
    S = np.empty((w.size, nc, nc), dtype=complex)
    K = np.empty(w.size)
    nyquist = np.pi / data.dt
    for k, (wk, rk) in enumerate(zip(w, R)):
        W, Pk = _window(omega_all, P, wk, rk, nyquist)
        if W.sum() <= 0:
            raise InsufficientDataError(f"no line of the record lies within {rk:.3g} rad/s "
                                        f"of {wk:.4g} rad/s: widen the resolution")
        S[k] = np.einsum("f,fab->ab", W / W.sum(), Pk)
        K[k] = W.sum() ** 2 / (W * W).sum()
    G, coh, mcoh, ratio, keep, _ = _frf_from_S(S, m, averages=float(K.min()))
    Kk = K[keep]
    if not np.any(keep) or np.any(Kk - m < 1.0):
        raise InsufficientDataError(
            f"the windows average the equivalent of {Kk.min() if Kk.size else 0:.1f} "
            f"spectra at some frequency for {m} input(s): too few for a band; widen the "
            "resolution or measure a longer record")
    G, std = _units(G, np.sqrt(ratio / (Kk - m)[:, None, None]), s, m)
    return FRD(w[keep], G, coherence=coh, std=std, dof=2.0 * float((Kk - m).min()),
               confidence=confidence, dt=data.dt, input_names=data.input_names,
               output_names=data.output_names, method="spafdr",
               info={"resolution": R[keep], "averages": Kk, "multiple_coherence": mcoh,
                     "dropped": w[~keep]})
