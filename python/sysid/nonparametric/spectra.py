"""Power spectra and coherence of every channel pair, and the spectral machinery that the
frequency-response estimators share.

Conventions (as :mod:`sysid.nonparametric.frf`): channels are stacked ``z = [u; y]``; the
cross-spectrum of channels ``a`` and ``b`` is ``S_ab = E[Z_a Z_b^*]``
(``scipy.signal.csd(z_b, z_a)``); spectra are one-sided densities in units^2/Hz, as
``scipy.signal.welch``, at angular frequencies in rad/s. Several experiments are averaged (no
segment spans two).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import signal

from .._checks import as_int, check_elements, constant_channels, user_stacklevel
from ..data.iodata import IOData, require_record
from ..errors import DataError, ExcitationError, InsufficientDataError, SysidWarning

__all__ = ["Spectra", "Coherence", "spectra", "periodogram", "coherence"]

_COND_LIMIT = 1e10


def _need_data(data: Any, inputs: bool = True, who: str = "spectra") -> IOData:
    # the frequency axis follows the sample time: a bare (u, y) pair is refused
    data = require_record(data, who, pairs=False)
    if inputs and data.n_inputs == 0:
        # MATLAB's spa(y), etfe(y) and spafdr(y) give the spectrum of a time series
        raise DataError(f"{who} relates the outputs to the inputs, and this record is a time "
                        f"series (no inputs): its spectrum is sysid.spectra(data) (Welch, every "
                        f"output pair, with coherence) or sysid.periodogram(data) (as "
                        f"etfe(y)), a model of it sysid.ar(data, na) or sysid.n4sid(data)")
    return data


def _z(data: IOData) -> list[np.ndarray]:
    return [np.hstack([u, y]) for u, y in data.experiments]


#: channels whose largest magnitude lies outside ``[2**-100, 2**100]`` are divided by a power
#: of two before their products are summed (:func:`_z_scaled`)
_ORDINARY = 2.0**100


def _z_scaled(data: IOData, per_channel: bool = False) -> tuple[list[np.ndarray], np.ndarray]:
    """:func:`_z` in units in which the squares neither overflow nor underflow, and the
    units ``s`` (one per channel: ``z_true = z * s``).

    A magnitude outside ``[2**-100, 2**100]`` (data near 1e300 made every spectrum NaN, near
    1e-200 zero) is divided by the power of two that brings it into ``[0.5, 1)``; ordinary
    data are used as they are (``s = 1``). Dividing by a power of two is exact. Unless
    ``per_channel``, all inputs share one unit and all outputs another, so that the input
    spectral matrix's trace and conditioning tests keep their meaning and a frequency
    response is the scaled one times ``s_y / s_u``.
    """
    zs = _z(data)
    mag = np.max([np.max(np.abs(z), axis=0, initial=0.0) for z in zs], axis=0)
    if not per_channel:
        m = data.n_inputs
        mag = np.concatenate([np.full(m, mag[:m].max(initial=0.0)),
                              np.full(mag.size - m, mag[m:].max(initial=0.0))])
    odd = (mag > 0) & ((mag > _ORDINARY) | (mag < 1.0 / _ORDINARY))
    s = np.where(odd, np.ldexp(1.0, np.frexp(np.where(odd, mag, 1.0))[1]), 1.0)
    return (zs, s) if not odd.any() else ([z / s for z in zs], s)


def _unscaled(S: np.ndarray, s: np.ndarray, names: list[str]) -> np.ndarray:
    """A spectral matrix of :func:`_z_scaled` data in the data's own units; a
    :class:`DataError` when those overflow double precision."""
    if np.all(s == 1.0):
        return S
    with np.errstate(over="ignore", invalid="ignore"):
        S = S * np.outer(s, s)[None]
    bad = [k for k in range(len(names)) if not np.all(np.isfinite(S[:, k, k]))]
    if bad:
        raise DataError(
            f"the spectra of channel(s) {[names[k] for k in bad]} (magnitudes of order "
            f"{s[bad].max():.1e}) overflow double precision in their units squared; rescale "
            "those channels (other units, e.g. divide by 1e100) before computing spectra")
    return S


def _names(data: IOData) -> list[str]:
    return list(data.input_names) + list(data.output_names)


def _need_varying(data: IOData, who: str, what: str, centred: bool = True) -> None:
    """Refuse channels without variation: constant within every experiment (``centred``:
    each experiment's mean is removed, leaving zeros; :func:`sysid._checks.
    constant_channels`), else zero in every sample. A
    coherence or correlation with such a channel is 0 / 0, undefined (it was reported as 0,
    "no relation"). A flat input raises an :class:`ExcitationError` (as the frequency
    responses do), a flat output a :class:`DataError`; both name the channels."""
    names = _names(data)
    zs = [np.hstack([u, y]) for u, y in data.experiments]
    if centred:
        varies = ~constant_channels(zs, "each")
    else:
        varies = np.any([np.any(z != 0.0, axis=0) for z in zs], axis=0)
    if varies.all():
        return
    m = data.n_inputs
    flat_in = [n for n, v in zip(names[:m], varies[:m]) if not v]
    flat_out = [n for n, v in zip(names[m:], varies[m:]) if not v]
    side, flat = ("input", flat_in) if flat_in else ("output", flat_out)
    how = ("constant within every experiment (no variation about the mean)" if centred
           else "zero in every sample")
    one = len(flat) == 1
    raise (ExcitationError if flat_in else DataError)(
        f"{who}: {side}{'' if one else 's'} {', '.join(flat)} {'is' if one else 'are'} {how}, "
        f"so {'its' if one else 'their'} {what} with any channel is 0 / 0, undefined; check "
        f"the channel (the wrong column, a stuck {'actuator' if flat_in else 'sensor'}?) or "
        f"leave {'it' if one else 'them'} out (data.select({side}s=...))")


# --------------------------------------------------------------------------------------------
# spectral machinery
# --------------------------------------------------------------------------------------------


def _welch_matrix(
    zs: list[np.ndarray], nperseg: int, noverlap: int, window: Any, nfft: int | None,
    dt: float, detrend: bool,
) -> tuple[np.ndarray, np.ndarray, float, int]:
    """One-sided density cross-spectral matrix ``(n_freq, nc, nc)``, freqs (Hz), K_eff, K."""
    if all(z.shape[0] < nperseg for z in zs):  # before a window of nperseg samples is built
        raise InsufficientDataError(
            f"every experiment is shorter than nperseg = {nperseg}; lower nperseg"
        )
    nfft = nperseg if nfft is None else as_int(nfft, "nfft", 2)
    if nfft < nperseg:  # np.fft.rfft(n=nfft) would cut every segment to its first nfft samples
        raise DataError(
            f"nfft ({nfft}) must be at least nperseg ({nperseg}): a shorter FFT drops the end "
            "of every segment; nfft pads with zeros (finer grid), it cannot shorten a segment "
            "(lower nperseg for a coarser grid)"
        )
    step = nperseg - noverlap
    nc = zs[0].shape[1]
    # the zero-padded segments of the longest experiment, their FFTs and the spectral matrix
    segments = max((z.shape[0] - nperseg) // step + 1 for z in zs if z.shape[0] >= nperseg)
    check_elements(nfft * nc * (2 * segments + nc), f"nfft = {nfft}",
                   f"nfft pads each segment of nperseg = {nperseg} samples with zeros for a "
                   f"finer frequency grid; a few times nperseg is plenty: pass a smaller nfft")
    win = _window(window, nperseg) if not isinstance(window, np.ndarray) else window
    if win.size != nperseg:
        raise DataError(f"window has {win.size} samples, nperseg is {nperseg}")
    if not (np.all(np.isfinite(win)) and np.any(win != 0)):
        raise DataError(f"window {window if not isinstance(window, np.ndarray) else 'array'!r} "
                        "gives non-finite or all-zero weights (a number is read as a Kaiser "
                        "window's beta); use a name such as 'hann' or finite weights")
    nf = nfft // 2 + 1
    S = np.zeros((nf, nc, nc), dtype=complex)
    count = 0
    short = [f"{k} ({z.shape[0]} samples)" for k, z in enumerate(zs) if z.shape[0] < nperseg]
    if short and len(short) < len(zs):
        warnings.warn(f"experiment(s) {', '.join(short)} shorter than nperseg = {nperseg} were "
                      f"left out of the spectra; lower nperseg to use them", SysidWarning,
                      stacklevel=user_stacklevel())
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


def _window(window: Any, n: int, fftbins: bool = True) -> np.ndarray:
    """``scipy.signal.get_window(window, n, fftbins)`` (periodic, or ``fftbins=False``
    symmetric); an unknown name is a :class:`DataError`."""
    try:
        return np.asarray(signal.get_window(window, n, fftbins=fftbins), dtype=float)
    except (ValueError, TypeError) as exc:
        raise DataError(
            f"window {window!r} is not a window scipy.signal.get_window knows ({exc}); use a "
            "name such as 'hann', 'hamming', 'blackman' or 'boxcar', or a tuple such as "
            "('tukey', 0.25)"
        ) from None


def _frf_from_S(
    S: np.ndarray, m: int, min_power: float = 1e-12, averages: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """G, pairwise coherence, multiple coherence, noise-to-input ratio factor, kept mask.

    ``averages``: the equivalent number of averaged spectra ``K`` behind the estimate. Where
    the estimate leaves no noise at all (its multiple coherence at or above 1, which a
    lag-windowed estimate reaches on short records), the noise spectrum is taken as ``1 /
    K`` of the output's, the smallest share a ``K``-average estimate resolves: a standard
    deviation of zero would claim an exact response (tfest refuses it as a weight)."""
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
    # a lag-windowed estimate (spa) can put an auto-spectrum at or below zero on a short
    # record: the coherence is undefined there and reported 0 (no evidence of a relation),
    # not |Syu|^2 / tiny (an overflow clipped to 1)
    den = dy[:, :, None] * du[:, None, :]
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        coh = np.where(den > tiny, np.abs(Syu) ** 2 / np.where(den > tiny, den, 1.0), 0.0)
        explained = np.einsum("fij,fji->fi", G, np.conj(np.swapaxes(Syu, 1, 2))).real
        mcoh = np.where(dy > tiny, explained / np.where(dy > tiny, dy, 1.0), 0.0)
    Svv = np.maximum(dy - explained, 0.0)
    if averages:  # only where the estimate left no noise at all (else calibrated as it is)
        Svv = np.where(Svv > 0, Svv, np.abs(dy) / averages)
    # |.|: a lag-windowed input spectrum can be indefinite (a negative diagonal of its
    # inverse), which made the ratio, and the standard deviation, zero
    ratio = Svv[:, :, None] * np.abs(np.einsum("fjj->fj", Suu_inv).real)[:, None, :]
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
    """The default segment length: the largest power of two up to 256 that every
    experiment holds and that gives at least seven half-overlapping segments in all (one
    record: a quarter of it). Each experiment's segments are averaged together, so a record
    cut into experiments is not held to a quarter of its shortest piece (the dryer cut at
    four gaps into 100-299 samples got 16-sample segments, 9 frequencies; now 64, 33).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nonparametric.spectra import _default_nperseg
    >>> one = sysid.IOData(u=np.zeros(1000), y=np.zeros(1000))
    >>> cut = sysid.IOData([np.zeros(n) for n in (100, 199, 249, 149, 299)],
    ...                    [np.zeros(n) for n in (100, 199, 249, 149, 299)])
    >>> _default_nperseg(one), _default_nperseg(cut)
    (128, 64)
    """
    lengths = list(data.lengths)
    for p in (256, 128, 64, 32, 16):
        if min(lengths) >= p and sum((n - p) // (p // 2) + 1 for n in lengths) >= 7:
            return p
    return 8


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

    def to_pandas(self) -> Any:
        """A long-format DataFrame: one row per frequency and channel pair ``(a, b)`` with
        ``omega``, ``hz``, ``a``, ``b``, ``real``, ``imag`` and ``magnitude`` of ``S_ab``.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> d = sysid.IOData(u=np.random.default_rng(0).standard_normal(512), y=np.ones(512))
        >>> sysid.spectra(d, nperseg=64).to_pandas().shape
        (132, 7)
        """
        from ..data.formats import _pandas

        nf, nc, _ = self.matrix.shape
        idx = np.indices((nf, nc, nc)).reshape(3, -1)
        s = self.matrix.reshape(-1)
        names = np.array(self.names, dtype=object)
        return _pandas().DataFrame({
            "omega": self.omega[idx[0]], "hz": self.hz[idx[0]], "a": names[idx[1]],
            "b": names[idx[2]], "real": s.real, "imag": s.imag, "magnitude": np.abs(s)})

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
    data = _need_data(data, inputs=False, who="spectra")
    S, f, s, info = _welch_scaled(data, nperseg, noverlap, window, nfft, detrend)
    return Spectra(2 * np.pi * f, _unscaled(S, s, _names(data)), _names(data), "welch", info)


def _welch_scaled(data: IOData, nperseg: int | None, noverlap: int | None, window: Any,
                  nfft: int | None, detrend: bool
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """:func:`spectra`'s Welch matrix of the :func:`_z_scaled` channels, frequencies (Hz),
    the channels' units and the record of the estimate."""
    nperseg = _default_nperseg(data) if nperseg is None else as_int(nperseg, "nperseg", 2)
    noverlap = nperseg // 2 if noverlap is None else as_int(noverlap, "noverlap", 0)
    if noverlap >= nperseg:
        raise DataError(f"noverlap ({noverlap}) must be smaller than nperseg ({nperseg})")
    zs, s = _z_scaled(data)
    S, f, k_eff, count = _welch_matrix(zs, nperseg, noverlap, window, nfft, data.dt, detrend)
    return S, f, s, {"nperseg": nperseg, "segments": count, "effective_averages": k_eff}


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
    data = _need_data(data, inputs=False, who="periodogram")
    if max(data.lengths) < 2:
        raise InsufficientDataError(f"a periodogram needs an experiment of at least 2 "
                                    f"samples, got {max(data.lengths)}")
    nfft = max(data.lengths)
    S = None
    zs, scale = _z_scaled(data)
    for z in zs:
        s, f, _, _ = _welch_matrix([z], z.shape[0], 0, window, nfft, data.dt, detrend)
        S = s * z.shape[0] if S is None else S + s * z.shape[0]
    assert S is not None
    return Spectra(2 * np.pi * f, _unscaled(S / data.n_samples, scale, _names(data)),
                   _names(data), "periodogram",
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

    def to_pandas(self) -> Any:
        """A long-format DataFrame: one row per frequency and output/input pair with
        ``omega``, ``hz``, ``output``, ``input``, ``coherence`` and the output's
        ``multiple`` coherence.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> u = np.random.default_rng(0).standard_normal(1024)
        >>> sysid.coherence(sysid.IOData(u, u), nperseg=64).to_pandas().shape
        (33, 6)
        """
        from ..data.formats import _pandas

        nf, l, m = self.values.shape
        idx = np.indices((nf, l, m)).reshape(3, -1)
        return _pandas().DataFrame({
            "omega": self.omega[idx[0]], "hz": self.hz[idx[0]],
            "output": np.array(self.output_names, dtype=object)[idx[1]],
            "input": np.array(self.input_names, dtype=object)[idx[2]],
            "coherence": self.values.reshape(-1), "multiple": self.multiple[idx[0], idx[1]]})

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

    A channel constant within every experiment has no spectrum (each segment's mean is
    removed), so its coherence with anything is 0 / 0: such an input raises an
    :class:`~sysid.ExcitationError`, such an output a :class:`~sysid.DataError`, naming it
    (``scipy.signal.coherence`` gives NaN with a warning; the value was 0).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.random.default_rng(0).standard_normal(4096)
    >>> c = sysid.coherence(sysid.IOData(u=u, y=np.convolve(u, [1.0, 0.5])[:4096]))
    >>> bool(c.values.min() > 0.99)
    True
    """
    data = _need_data(data, who="coherence")
    _need_varying(data, "coherence", "coherence")  # every segment is detrended
    # coherence is unitless: taken of the scaled channels, it never overflows
    S, f, _, _ = _welch_scaled(data, nperseg, noverlap, window, None, True)
    m = data.n_inputs
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
    return Coherence(2 * np.pi * f, np.clip(vals, 0, 1), np.clip(mult, 0, 1),
                     list(data.input_names), list(data.output_names))
