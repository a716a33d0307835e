r"""Stochastic subspace identification of vibration records without a measured input.

A structure driven by unmeasured broadband forces is the stochastic state-space model
``x(t+1) = A x + w``, ``y = C x + v``. Its output covariances
``R_k = E[y(t+k) y(t)^T] = C A^(k-1) G`` factor like Markov parameters, so

* **SSI-cov** (covariance driven): the block Toeplitz matrix ``T[a, b] = R_(i+a-b)``
  (``i`` block rows, lags 1..2i-1) equals ``O_i Gamma_i``; its SVD truncated at order ``n``
  gives the observability matrix ``O = U_n S_n^(1/2)``, ``C`` its first block row and ``A``
  from its shift invariance ``O_up A = O_down`` (least squares);
* **SSI-data** (data driven): the output-only N4SID projection of future on past outputs
  (:class:`sysid.SubspaceEstimator` on data without input), then ``A, C`` the same way.

Poles become frequencies and damping ratios through ``s = ln(z) / dt``; mode shapes are
``C`` times the eigenvectors. One SVD serves every order of the stabilisation diagram: a
mode is *stable* when a mode of the previous order lies within ``freq_tol`` in frequency,
``damping_tol`` in damping ratio and has a MAC above ``min_mac``.

Standard deviations come from the delete-a-block jackknife: the record is cut into ``blocks``
contiguous segments, the model is identified again at the same order with each segment left
out in turn (the two remaining pieces as separate experiments), each mode is matched to the
full record's (nearest frequency with MAC above 0.8; shapes aligned in scale and phase), and

.. math:: \hat\sigma^2 = \frac{B - 1}{B} \sum_{b=1}^{B} (\theta_{(b)} - \bar\theta)^2

over the ``B`` leave-one-out estimates ``theta_(b)`` that found the mode. Each of them uses
``(B - 1) / B`` of the record, so the estimator behaves as on the full record (short
segments alone would bias the damping and inflate its spread: batch means of separate
segments over-predicted the damping std by about 30 % at ``B = 10``). It assumes the
segments are long against the correlation time of the response.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import (
    as_int,
    experiment_arrays,
    require_inputs_vary,
    stability_criteria,
    user_stacklevel,
)
from ..errors import DataError, InsufficientDataError, NonFiniteError, SysidWarning

_METHODS = ("cov", "data")


def mac(phi1: Any, phi2: Any) -> np.ndarray:
    """Modal assurance criterion between mode shapes: ``|phi1_i^H phi2_j|^2 /
    (|phi1_i|^2 |phi2_j|^2)``.

    Parameters
    ----------
    phi1, phi2 : array_like (n_modes, n_channels) or (n_channels,)
        Complex or real mode shapes, one per row.

    Returns
    -------
    ndarray (n_modes1, n_modes2)
        1 for collinear shapes, 0 for orthogonal ones.

    Examples
    --------
    >>> import sysid
    >>> sysid.mac([[1, 2], [1, -1]], [[2, 4], [0, 1]]).round(3)
    array([[1. , 0.8],
           [0.1, 0.5]])
    """
    a = np.atleast_2d(np.asarray(phi1, dtype=complex))
    b = np.atleast_2d(np.asarray(phi2, dtype=complex))
    if a.shape[1] != b.shape[1]:
        raise DataError(f"mode shapes have {a.shape[1]} and {b.shape[1]} channels; compare "
                        "shapes over the same channels")
    for arr, name in ((a, "phi1"), (b, "phi2")):
        if not np.isfinite(arr).all():
            raise NonFiniteError(f"{name} has non-finite entries (NaN or Inf): the MAC of "
                                 "such a mode shape is undefined; drop or recompute that mode")
    # each shape to unit length first (the MAC does not depend on scale): shapes in units that
    # make their squares overflow or underflow (1e+-200) gave NaN or 0 for identical shapes
    a, b = _unit_rows(a), _unit_rows(b)
    return np.minimum(np.abs(a.conj() @ b.T) ** 2, 1.0)


def _unit_rows(x: np.ndarray) -> np.ndarray:
    """Rows scaled to unit 2-norm (an all-zero row stays zero: its MAC is 0)."""
    big = np.max(np.abs(x), axis=1, keepdims=True)
    big = np.where(big > 0, big, 1.0)
    x = x.real / big + 1j * (x.imag / big)  # real divisions: no overflow for subnormal scales
    norm = np.sqrt(np.sum(np.abs(x) ** 2, axis=1, keepdims=True))
    return x / np.where(norm > 0, norm, 1.0)


def _correlations(ys: list[np.ndarray], kmax: int) -> np.ndarray:
    """``R_k = E[y(t+k) y(t)^T]``, k = 0..kmax, pooled over the experiments."""
    l = ys[0].shape[1]
    R = np.zeros((kmax + 1, l, l))
    count = np.zeros(kmax + 1)
    for y in ys:
        N = y.shape[0]
        for k in range(min(kmax + 1, N)):     # a piece shorter than the lags adds none
            R[k] += y[k:].T @ y[: N - k]
            count[k] += N - k
    return R / count[:, None, None]


def _cov_svd(ys: list[np.ndarray], i: int) -> tuple[np.ndarray, np.ndarray]:
    R = _correlations(ys, 2 * i)
    l = R.shape[1]
    T = np.empty((i * l, i * l))
    for a in range(i):
        for b in range(i):
            T[a * l:(a + 1) * l, b * l:(b + 1) * l] = R[i + a - b]
    U, s, _ = np.linalg.svd(T)
    return U, s


def _ac_from_observability(U: np.ndarray, s: np.ndarray, n: int, l: int
                           ) -> tuple[np.ndarray, np.ndarray]:
    O = U[:, :n] * np.sqrt(s[:n])
    A = np.linalg.lstsq(O[:-l], O[l:], rcond=None)[0]
    return A, O[:l]


def _systems(ys: list[np.ndarray], dt: float, orders: list[int], i: int,
             method: str) -> tuple[list[tuple[np.ndarray, np.ndarray]], np.ndarray]:
    """``(A, C)`` per order and the singular values."""
    l = ys[0].shape[1]
    if method == "cov":
        # on channels of unit root mean square, C back in the record's units: the modes do
        # not depend on the channels' units (as SubspaceEstimator's scale=True for "data")
        sy = np.sqrt(np.mean(np.vstack(ys) ** 2, axis=0))
        sy = np.where((sy > 0) & np.isfinite(sy), sy, 1.0)
        U, s = _cov_svd([y / sy for y in ys], i)
        return [(A, C * sy[:, None]) for A, C in
                (_ac_from_observability(U, s, n, l) for n in orders)], s
    from ..data.iodata import IOData
    from ..subspace.estimator import SubspaceEstimator

    est = SubspaceEstimator(IOData(None, ys if len(ys) > 1 else ys[0], dt), horizon=i,
                            method="n4sid")
    import warnings

    from ..errors import StabilityWarning

    out = []
    for n in orders:
        # a stabilisation diagram over-fits on purpose: unstable noise modes at high orders
        # are expected and shown (negative damping), not a reason to warn
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StabilityWarning)
            m = est.fit(n, kalman=False)
        out.append((np.asarray(m.A), np.asarray(m.C)))
    return out, np.asarray(est.singular_values)


def _modes(A: np.ndarray, C: np.ndarray, dt: float, names: list[str]) -> Any:
    from ..analysis.modal import modal_analysis
    from ..models.statespace import StateSpaceModel

    m = StateSpaceModel(A, np.zeros((A.shape[0], 0)), C, dt=dt, output_names=names)
    modes = modal_analysis(m)
    return modes.select(np.isfinite(modes.frequencies_hz))


def _status(prev: Any, cur: Any, freq_tol: float, damping_tol: float,
            min_mac: float) -> np.ndarray:
    st = np.zeros(len(cur), dtype=int)
    if prev is None or not len(prev) or not len(cur):
        return st
    M = mac(cur.mode_shapes, prev.mode_shapes)
    for k in range(len(cur)):
        df = np.abs(prev.frequencies_hz - cur.frequencies_hz[k])
        j = int(np.argmin(df))
        if df[j] <= freq_tol * max(cur.frequencies_hz[k], 1e-12):
            st[k] = 1
            if (abs(prev.damping[j] - cur.damping[k]) <= damping_tol * max(
                    abs(cur.damping[k]), 1e-12) and M[k, j] >= min_mac):
                st[k] = 2
    return st


class SSIResult:
    """What :func:`ssi` returns: the stabilisation diagram and the modes at each order.

    Attributes
    ----------
    orders : list of int
    modes : list of ModalAnalysis
        Modes at each order (``frequencies_hz``, ``damping``, ``mode_shapes``).
    status : list of ndarray
        Per mode: 2 stable (frequency, damping and MAC), 1 frequency only, 0 new.
    singular_values : ndarray
        Of the Toeplitz (cov) or projection (data) matrix: a gap suggests the order.
    method, horizon, dt
    """

    def __init__(self, orders: list[int], modes: list[Any], status: list[np.ndarray],
                 s: np.ndarray, method: str, horizon: int, dt: float, ys: list[np.ndarray],
                 blocks: int, names: list[str]) -> None:
        self.orders, self.modes, self.status = orders, modes, status
        self.singular_values, self.method, self.horizon, self.dt = s, method, horizon, dt
        self._ys, self._blocks, self._names = ys, blocks, names

    @property
    def diagram(self) -> Any:
        """The :class:`sysid.StabilizationDiagram` (shared with ERA's)."""
        from ..realization.realize import StabilizationDiagram

        return StabilizationDiagram(self.orders, self.modes, self.status)

    def stable_frequencies(self, min_count: int = 3) -> np.ndarray:
        """Frequencies (Hz) of modes stable at ``min_count`` or more orders (clustered)."""
        return np.asarray(self.diagram.stable_frequencies(min_count))

    def plot(self, *, ax: Any = None) -> Any:
        """The stabilisation diagram (frequency against order); returns the axes."""
        return self.diagram.plot(ax=ax)

    def to_pandas(self) -> Any:
        """The diagram's modes, one row per mode and order
        (:meth:`sysid.StabilizationDiagram.to_pandas`)."""
        return self.diagram.to_pandas()

    def summary(self, min_count: int = 3) -> str:
        """The diagram's summary (:meth:`sysid.StabilizationDiagram.summary`) under this
        result's line; :meth:`modes_at` gives an order's modes with their standard
        deviations."""
        return "\n".join([repr(self)] + self.diagram.summary(min_count).splitlines()[1:])

    def modes_at(self, order: int, *, std: bool = True) -> Any:
        """The modes at ``order`` (one of :attr:`orders`) with, when ``std``, the jackknife
        standard deviations ``extra["sd_hz"]``, ``extra["sd_damping"]`` and
        ``mode_shape_std`` (complex: std of real and imaginary parts; shapes normalised with
        their largest entry 1)."""
        if order not in self.orders:
            raise DataError(f"order {order} is not in the diagram's orders {self.orders}; "
                            "pick one of them or run ssi with it")
        full = self.modes[self.orders.index(order)]
        if not std:
            return full
        return _block_std(full, self._ys, self.dt, order, self.horizon, self.method,
                          self._blocks, self._names)

    def __repr__(self) -> str:
        return (f"SSIResult(SSI-{self.method}, horizon {self.horizon}, orders "
                f"{self.orders[0]}..{self.orders[-1]}, stable modes at "
                f"{np.round(self.stable_frequencies(), 3).tolist()} Hz)")


def _leave_out(ys: list[np.ndarray], b: int, blocks: int) -> list[np.ndarray]:
    """The experiments without segment ``b`` of each (the pieces around it kept apart)."""
    out = []
    for y in ys:
        edges = np.linspace(0, y.shape[0], blocks + 1).round().astype(int)
        out += [piece for piece in (y[:edges[b]], y[edges[b + 1]:]) if piece.shape[0]]
    return out


def _block_std(full: Any, ys: list[np.ndarray], dt: float, order: int, i: int, method: str,
               blocks: int, names: list[str]) -> Any:
    segs = []
    for b in range(blocks):
        (A, C), = _systems(_leave_out(ys, b, blocks), dt, [order], i, method)[0]
        segs.append(_modes(A, C, dt, names))
    k = len(full)
    f = np.full((blocks, k), np.nan)
    z = np.full((blocks, k), np.nan)
    sh = np.full((blocks, k, full.mode_shapes.shape[1]), np.nan, dtype=complex)
    for b, seg in enumerate(segs):
        if not len(seg):
            continue
        M = mac(full.mode_shapes, seg.mode_shapes)
        for j in range(k):
            cand = np.where(M[j] >= 0.8)[0]
            if cand.size == 0:
                continue
            c = cand[np.argmin(np.abs(seg.frequencies_hz[cand] - full.frequencies_hz[j]))]
            f[b, j], z[b, j] = seg.frequencies_hz[c], seg.damping[c]
            phi, ref = seg.mode_shapes[c], full.mode_shapes[j]
            sh[b, j] = phi * (np.vdot(phi, ref) / np.vdot(phi, phi))
    out = full.select(np.arange(k))
    found = np.sum(np.isfinite(f), axis=0)
    import warnings

    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # modes found in < 3 runs: NaN
        # jackknife: (B - 1) / B times the sum of squares = (B - 1)^2 / B times the variance
        scale = np.where(found >= 3, (found - 1) / np.sqrt(np.maximum(found, 1)), np.nan)
        out.extra["sd_hz"] = np.nanstd(f, axis=0, ddof=1) * scale
        out.extra["sd_damping"] = np.nanstd(z, axis=0, ddof=1) * scale
        out.mode_shape_std = (np.nanstd(sh.real, axis=0, ddof=1)
                              + 1j * np.nanstd(sh.imag, axis=0, ddof=1)) * scale[:, None]
    out.extra["blocks_found"] = found.astype(float)
    return out


#: The longest default horizon (block rows): the covariances to lag ``2 i - 1`` and an SVD
#: of ``i l`` columns stay seconds long; a record that needs more is told to decimate.
LONGEST_HORIZON = 300
#: The fraction of the output power below the slowest frequency the horizon must resolve.
SLOW_POWER = 0.02
#: A resonance peak counts for the default horizon when its density is at least this share of
#: the highest and this many times the density around it; the horizon then resolves the
#: peak's frequency divided by the margin (on displacement records the power share lands
#: there, 1.6 times below a dominant slowest mode).
PEAK_SHARE, PEAK_PROMINENCE, PEAK_MARGIN = 0.01, 10.0, 3.3


def _mean_spectrum(ys: list[np.ndarray], dt: float, seg: int
                   ) -> tuple[np.ndarray, np.ndarray | None]:
    """Welch spectra of every channel normalised to unit power, channels and experiments
    averaged (None when every channel is constant)."""
    from scipy.signal import welch

    spectra = []
    for y in ys:
        f, P = welch(y - y.mean(axis=0), fs=1.0 / dt, nperseg=seg, axis=0)
        total = P.sum(axis=0)
        spectra.append(P[:, total > 0] / total[total > 0])
    if not any(S.shape[1] for S in spectra):
        return f, None
    return f, np.mean([S.mean(axis=1) for S in spectra if S.shape[1]], axis=0)


def default_horizon(ys: list[np.ndarray], dt: float, least: int, blocks: int) -> int:
    """Block rows whose ``2 i - 1`` covariance lags span a fifth of the period of the
    record's slowest content: ``i = fs / (10 f)``, with ``f`` the frequency below which
    :data:`SLOW_POWER` of the output power lies (each channel's Welch spectrum normalised to
    unit power, the channels and experiments averaged), or the slowest resonance peak (at
    least :data:`PEAK_SHARE` of the highest density and :data:`PEAK_PROMINENCE` times its
    surroundings) divided by :data:`PEAK_MARGIN`, whichever is lower; at least ``least``, at
    most :data:`LONGEST_HORIZON` and what the record's length allows (then a warning:
    decimate first). Measured on simulated three-mode structures (2, 5, 11 Hz, 2 % damping,
    three displacements or three accelerations under white forces, 100 Hz, 200 Hz and 1 kHz,
    three seeds each, 18 diagrams of orders 2-30): the power share alone found 40 of the 54
    modes (a strong slowest mode holds the 2 % itself, so ``f`` fell on its peak: on
    accelerations the 2 Hz mode was missed at 200 Hz and 1 kHz) with 6 spurious stable modes;
    with the peak rule 52 of 54, with 11 spurious ones. On the F-16 ground vibration levels it
    gives 18-19 block rows (the power share alone 10-11; its modal test here uses 30).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(20000) * 0.001                    # 1 kHz, a 2 Hz oscillation
    >>> y = np.sin(2 * np.pi * 2.0 * t)[:, None] + 0.01 * np.cos(t)[:, None]
    >>> default_horizon([y], 0.001, 10, 10)   # a peak at 2 Hz: a tenth of 3.3 periods
    165
    """
    import warnings

    from scipy.signal import find_peaks

    shortest = min(y.shape[0] for y in ys)
    f, mean = _mean_spectrum(ys, dt, min(shortest, 4096))
    if mean is None:
        return least  # constant channels: nothing to resolve (refused by the caller)
    k = int(np.searchsorted(np.cumsum(mean), SLOW_POWER))
    slow, what = float(f[max(k, 1)]), "2 % of the output power lies below it"
    # peaks on an average of at least 15 segments, so that no ripple of the estimate passes
    # for a resonance
    seg = min(shortest // 8, 4096)
    if seg >= 16:
        fp, level = _mean_spectrum(ys, dt, seg)
        with np.errstate(divide="ignore"):
            level = np.log(level[1:])
        peaks, _ = find_peaks(level, height=np.log(PEAK_SHARE) + level.max(),
                              prominence=np.log(PEAK_PROMINENCE))
        if len(peaks) and float(fp[peaks[0] + 1]) / PEAK_MARGIN < slow:
            slow = float(fp[peaks[0] + 1]) / PEAK_MARGIN
            what = f"a resonance peak at {float(fp[peaks[0] + 1]):.3g} Hz, over {PEAK_MARGIN:g}"
    need = int(np.ceil(1.0 / (10.0 * slow * dt)))
    room = min(y.shape[0] for y in ys) // (4 * blocks)
    i = max(least, min(need, LONGEST_HORIZON, room))
    if need > i:
        k = int(np.ceil(need / i))
        warnings.warn(
            f"ssi: the record's slowest content ({what}) is at {slow:.3g} Hz, and resolving "
            f"it needs "
            f"a horizon of about {need} block rows (a tenth of its period, at dt = {dt:g} s); the "
            f"default stops at {i} (" + ("what the record's length allows"
                                         if room < LONGEST_HORIZON else "its longest")
            + f"), so modes below about "
            f"{1.0 / (10.0 * i * dt):.3g} Hz may be missed: decimate first "
            f"(sysid.decimate(data, {k})) or pass horizon=", SysidWarning,
            stacklevel=user_stacklevel())
    return i


def ssi(data: Any, orders: Any, *, method: str = "cov", horizon: int | None = None,
        blocks: int = 10, freq_tol: float = 0.01, damping_tol: float = 0.05,
        min_mac: float = 0.95) -> SSIResult:
    """Output-only modal analysis by stochastic subspace identification.

    Parameters
    ----------
    data : IOData
        Response records (accelerations, velocities, strains), ``(n_samples, n_channels)``;
        inputs, if the record has any, are ignored (output-only). Remove the means first.
    orders : iterable of int
        Increasing model orders for the stabilisation diagram (two per mode).
    method : {"cov", "data"}
        Covariance-driven (SSI-cov, default) or data-driven (SSI-data, output-only N4SID).
    horizon : int, optional
        Block rows ``i``; ``(i - 1) * n_channels`` must reach the largest order (the shift
        equation of the observability matrix). Default: ``fs / (10 f)`` with 2 % of the
        output power below ``f`` (the covariance lags span a fifth of the period of the
        record's slowest content, :func:`default_horizon`), at least that minimum and 10, at
        most 300 (a record sampled far faster than its modes is told to decimate first,
        :func:`sysid.decimate`). Longer horizons resolve closer and slower modes.
    blocks : int
        Segments of the delete-a-block jackknife that gives the standard deviations of
        :meth:`SSIResult.modes_at` (>= 3 for a std).
    freq_tol, damping_tol, min_mac : float
        Stability criteria of the diagram.

    Returns
    -------
    SSIResult

    Examples
    --------
    >>> import numpy as np, sysid
    >>> A = np.array([[0.98, 0.15], [-0.15, 0.98]])     # one mode at ~0.24 Hz, dt = 0.1
    >>> rng = np.random.default_rng(0)
    >>> x = np.zeros(2); y = np.empty((20000, 2))
    >>> for t in range(20000):
    ...     y[t] = [x[0], x[0] + 0.5 * x[1]]; x = A @ x + rng.standard_normal(2)
    >>> res = sysid.ssi(sysid.IOData(None, y, 0.1), range(2, 21, 2))
    >>> f_true = np.angle(np.linalg.eigvals(A)).max() / (2 * np.pi * 0.1)
    >>> bool(abs(res.stable_frequencies()[0] - f_true) < 0.01)
    True
    """
    from ..data.iodata import IOData

    if not isinstance(data, IOData):
        raise DataError("data must be an IOData record: sysid.IOData(None, y, dt) for "
                        "output-only response data")
    from ..data.offsets import check_offsets

    check_offsets(data)  # response data on an offset lose their modes to it (as any fit)
    if method not in _METHODS:
        raise DataError(f"method must be 'cov' (SSI-cov) or 'data' (SSI-data), got {method!r}")
    ords = [as_int(o, "orders", 1) for o in np.atleast_1d(np.asarray(orders, dtype=object))]
    freq_tol, damping_tol, min_mac = stability_criteria(freq_tol, damping_tol, min_mac)
    if not ords or any(b <= a for a, b in zip(ords, ords[1:])):
        raise DataError(f"orders must be a non-empty increasing sequence, got {ords}")
    blocks = as_int(blocks, "blocks", 2)
    ys = [y for _, y in experiment_arrays(data)]
    l = ys[0].shape[1]
    # the shift equation O[:-l] A = O[l:] has (i - 1) l rows for n unknowns per column
    least = max(10, -(-ords[-1] // l) + 1)
    i = as_int(horizon, "horizon", 1) if horizon is not None else default_horizon(
        ys, float(data.dt), least, blocks)
    if (i - 1) * l < ords[-1]:
        raise DataError(f"horizon {i} with {l} channel(s) allows orders up to {(i - 1) * l}, "
                        f"got {ords[-1]}; choose horizon >= {-(-ords[-1] // l) + 1}")
    shortest = min(y.shape[0] for y in ys)
    if shortest < blocks * 4 * i:
        raise InsufficientDataError(
            f"ssi with horizon {i} and {blocks} blocks needs at least {blocks * 4 * i} samples "
            f"per experiment, got {shortest}; use a longer record, fewer blocks or a shorter "
            "horizon")
    # a constant channel has no modes: on all-constant outputs the covariances are
    # round-off, and their "stable modes" an artefact
    require_inputs_vary(experiment_arrays(data), "ssi", data.output_names, side=1)
    systems, s = _systems(ys, float(data.dt), ords, i, method)
    names = list(data.output_names)
    modes, status, prev = [], [], None
    for A, C in systems:
        cur = _modes(A, C, float(data.dt), names)
        status.append(_status(prev, cur, freq_tol, damping_tol, min_mac))
        modes.append(cur)
        prev = cur
    return SSIResult(ords, modes, status, s, method, i, float(data.dt), ys, blocks, names)
