"""Frequency-response data: a measured or estimated ``G(e^{j omega dt})`` on a grid.

:class:`FRD` is the model that non-parametric estimators return (:func:`sysid.welch_frf`,
:func:`sysid.spa`, :func:`sysid.etfe`), with a confidence band when the estimator gives one;
:meth:`FRD.from_model` samples any model with ``freqresp(omega)`` onto a grid, and
:meth:`FRD.compare` measures a model against the data (:class:`FRDComparison`).
``G[i, j]`` picks outputs and inputs; ``+``, ``-``, ``*`` (series), ``/``, :meth:`FRD.inv` and
:meth:`FRD.feedback` combine responses on one grid (:mod:`sysid.models.frd_algebra`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._checks import as_between
from ..data.formats import _pandas
from ..data.iodata import IOData
from ..errors import DataError, ShapeError
from .attributes import SampleTime
from .checks import require_freqresp
from .frd_algebra import FRDAlgebra, check_grid
from .subsystem import channels, selection_key

__all__ = ["FRD", "FRDComparison", "band_quantile"]

#: Frequency units an FRD takes and shows, with their size in rad/s.
UNITS = {"rad/s": 1.0, "Hz": 2 * np.pi}


def _unit(units: str | None) -> str | None:
    if units is None:
        return None
    for name in UNITS:
        if isinstance(units, str) and units.strip().lower() == name.lower():
            return name
    raise DataError(f"units must be one of {list(UNITS)} (or None for rad/s), got {units!r}")


def band_quantile(confidence: float, dof: float | None, real: Any = False) -> np.ndarray:
    """``q`` with ``P(|G_hat - G|^2 <= q std^2) = confidence`` for an estimate with
    ``E|G_hat - G|^2 = std^2``: at a complex line the error has two real degrees of freedom,
    ``|e|^2 / std^2 ~ chi2_2 / 2`` (``F(2, dof)`` with the std estimated on ``dof``); where
    the line is real (``real``: zero frequency, Nyquist) it has one, ``chi2_1`` (``F(1, dof
    / 2)``: each average holds half as many). The complex rule there gave a 99 % band that
    held the truth 96 % of the time.

    Examples
    --------
    >>> from sysid.models.frd import band_quantile
    >>> band_quantile(0.99, None, [False, True]).round(3)  # -ln(0.01), chi2_1's 6.635
    array([4.605, 6.635])
    """
    from scipy import special, stats  # importing stats costs a second; most fits never ask

    p, real = float(confidence), np.asarray(real, dtype=bool)
    if dof is None:
        complex_q, real_q = -np.log1p(-p), 2.0 * float(special.erfinv(p)) ** 2
    else:
        complex_q = float(stats.f.ppf(p, 2, dof))
        real_q = float(stats.f.ppf(p, 1, dof / 2.0)) if real.any() else 0.0
    return np.where(real, real_q, complex_q)


class FRD(FRDAlgebra):
    """Frequency-response data: a measured or estimated ``G(e^{j omega dt})``.

    Parameters
    ----------
    omega : array_like
        Frequencies, shape ``(n_freq,)``: angular frequencies in rad/s, or in ``units``.
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
        (``2 (K - m)``); ``None`` for the large-sample (complex normal) limit. At a real line
        (zero frequency, Nyquist: :meth:`real_lines`) half of it, with one numerator degree
        of freedom (:func:`band_quantile`).
    dt : float, optional
        Sample time of the data it came from.
    input_names, output_names : list of str, optional
    method : str
        How it was estimated.
    info : dict, optional
        Settings (window, lags, averages, dropped frequencies).
    units : {None, "rad/s", "Hz"}
        Unit of ``omega`` as given, shown by ``repr`` and on the plots' frequency axis
        (MATLAB's ``FrequencyUnit``). :attr:`omega` is always kept in rad/s (``freqresp`` and
        models take rad/s); :attr:`frequencies` is in ``units``. ``None`` (the default) is
        rad/s as before units existed: shown in rad/s, plotted in Hz.

    Notes
    -----
    ``G[i, j]`` selects outputs and inputs (indices, slices, names, lists); ``+``, ``-``,
    ``*`` (series: ``G1 * G2`` is G1 after G2), ``/``, unary ``-``, :meth:`inv` and
    :meth:`feedback` combine it with another FRD on the same grid, a model (evaluated on this
    grid) or a gain, carrying the std to first order for independent operands, or for one
    response used twice (``G - G``, ``G * G``: the same FRD object) with its full derivative
    (:mod:`sysid.models.frd_algebra`).

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

    #: sample time of the data it came from (``None``: continuous time), checked whenever
    #: it is written (:class:`~sysid.models.attributes.SampleTime`)
    dt = SampleTime(continuous=None)

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
        units: str | None = None,
    ) -> None:
        self.units = _unit(units)
        w = np.asarray(omega, dtype=float).ravel() * UNITS[self.units or "rad/s"]
        g = _as_complex(response, "response")
        if g.ndim == 1:
            g = g[:, None, None]
        if g.ndim != 3 or g.shape[0] != w.size:
            raise ShapeError(
                f"response must be (n_freq, n_outputs, n_inputs) with n_freq = {w.size}, "
                f"got {g.shape}"
            )
        if not (np.isfinite(w).all() and np.isfinite(g).all()):
            raise DataError("omega and response must be finite")
        confidence = as_between(confidence, "confidence", 0.0, 1.0)
        # one response per frequency, in increasing order (the phase is unwrapped along it)
        order = np.argsort(w, kind="stable")
        same = np.flatnonzero(np.diff(w[order]) == 0)
        if same.size:
            unit = self.units or "rad/s"
            raise DataError(f"omega holds {w[order][same[0]] / UNITS[unit]:g} {unit} more than "
                            "once: give each frequency once (average repeated measurements of "
                            "it first)")
        self.omega = w[order]
        self.response = g[order]
        self.coherence = (None if coherence is None
                          else self._same(coherence, "coherence", float)[order])
        self.std = None if std is None else self._same(std, "std", float)[order]
        self.confidence = float(confidence)
        if dof is not None and not dof > 0:
            raise DataError(f"dof must be positive, got {dof}")
        self.dof = None if dof is None else float(dof)
        self.dt = dt  # None (or 0): continuous; checked by SampleTime, as later
        l, m = g.shape[1:]
        self.input_names = IOData._names(input_names, m, "u", "input")
        self.output_names = IOData._names(output_names, l, "y", "output")
        self.method = method
        self.info = dict(info or {})

    def _same(self, x: Any, name: str, dtype: type) -> np.ndarray:
        a: np.ndarray = np.asarray(x, dtype=dtype)
        if a.ndim == 1 and self.response.shape[1:] == (1, 1):
            a = a[:, None, None]  # one pair: (n_freq,) as the response itself is accepted
        if a.shape != self.response.shape:
            raise ShapeError(f"{name} has shape {a.shape} but the response {self.response.shape}")
        hi = 1.0 if name == "coherence" else np.inf
        if not (np.isfinite(a).all() and (a >= 0).all() and (a <= hi).all()):
            rng = "in [0, 1]" if name == "coherence" else "finite and >= 0"
            raise DataError(f"{name} must be {rng} at every frequency and pair (got min "
                            f"{np.nanmin(a):.3g}, max {np.nanmax(a):.3g}, "
                            f"{int(np.sum(~np.isfinite(a)))} non-finite)")
        return a

    @property
    def hz(self) -> np.ndarray:
        """Frequencies in Hz."""
        return self.omega / (2 * np.pi)

    @property
    def frequencies(self) -> np.ndarray:
        """Frequencies in :attr:`units` (rad/s when ``units`` is ``None``)."""
        return self.frequencies_in(self.units or "rad/s")

    def frequencies_in(self, units: str) -> np.ndarray:
        """The frequencies in ``units`` (``"rad/s"`` or ``"Hz"``).

        Examples
        --------
        >>> import sysid
        >>> f = sysid.FRD([1.0, 2.0], [1.0, 1.0], units="Hz")
        >>> f.frequencies_in("rad/s") / 3.141592653589793
        array([2., 4.])
        >>> f.frequencies_in("Hz")
        array([1., 2.])
        """
        unit = _unit(units)
        if unit is None:
            raise DataError(f"units must be one of {list(UNITS)}, got None")
        return self.omega / UNITS[unit]

    def __getitem__(self, key: Any) -> FRD:
        """``G[outputs, inputs]``: the sub-response of some outputs and inputs (MATLAB's
        ``G(i, j)``), with its std and coherence.

        Each of the two may be an index, a slice, a channel name or a list of indices or
        names; the result is always an FRD ``(n_freq, n_out, n_in)``. See :meth:`select`.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> g = sysid.FRD([1.0, 2.0], np.ones((2, 3, 2)), output_names=["a", "b", "c"])
        >>> g[0, :].response.shape, g["c", 1].response.shape, g[1:, [1, 0]].input_names
        ((2, 1, 2), (2, 1, 1), ['u1', 'u0'])
        """
        outputs, inputs = selection_key(key, self.output_names, self.input_names, "an FRD")
        return self.select(outputs=outputs, inputs=inputs)

    @property
    def n_inputs(self) -> int:
        return self.response.shape[2]

    @property
    def n_outputs(self) -> int:
        return self.response.shape[1]

    # the frequency-domain part of the model protocol (sysid.Model): an FRD has no time
    # response, but the Bode and sigma plots and FRD.compare take it like any model
    ninputs = property(lambda self: self.n_inputs, doc="Number of inputs (protocol name).")
    noutputs = property(lambda self: self.n_outputs, doc="Number of outputs (protocol name).")

    def freqresp(self, omega: Any) -> np.ndarray:
        """The response at ``omega`` (rad/s), interpolated linearly in real and imaginary
        parts between the measured frequencies; outside their range is an error.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> f = sysid.FRD([1.0, 2.0], np.array([1.0, 3.0j]))
        >>> f.freqresp([1.5])[0, 0, 0]
        np.complex128(0.5+1.5j)
        """
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        order = np.argsort(self.omega, kind="stable")
        ws, g = self.omega[order], self.response[order]
        if w.ndim != 1 or not np.isfinite(w).all():
            raise DataError("omega must be a finite 1-D array of angular frequencies (rad/s)")
        lo, hi = ws[0], ws[-1]
        if w.size and (w.min() < lo * (1 - 1e-12) or w.max() > hi * (1 + 1e-12)):
            raise DataError(f"omega must lie within the measured {lo:g}..{hi:g} rad/s; an FRD "
                            "does not extrapolate (fit a model to it first)")
        flat = g.reshape(ws.size, -1)
        out = np.empty((w.size, flat.shape[1]), dtype=complex)
        for k in range(flat.shape[1]):
            out[:, k] = np.interp(w, ws, flat[:, k].real) + 1j * np.interp(w, ws, flat[:, k].imag)
        return out.reshape(w.size, *g.shape[1:])

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
        """Radius of the confidence circle at :attr:`confidence` (``None`` without ``std``):
        ``std sqrt(q)`` with ``q`` the :func:`band_quantile` of the line, complex or real
        (:meth:`real_lines`)."""
        if self.std is None:
            return None
        return self.std * np.sqrt(band_quantile(self.confidence, self.dof, self.real_lines()))

    def real_lines(self) -> np.ndarray:
        """Where the response of real signals is real, bool ``(n_freq, l, m)``: zero
        frequency and, sampled every ``dt``, the Nyquist frequency ``pi / dt`` (the DFT line
        of a real record is real there, and so is the error of an estimate), each where
        the response is real (to rounding)."""
        w = self.omega
        at = w == 0.0
        if self.dt:
            at |= np.isclose(w, np.pi / float(self.dt), rtol=1e-9, atol=0.0)
        g = self.response
        return at[:, None, None] & (np.abs(g.imag) <= 1e-9 * np.abs(g))

    def _other(self, other: Any) -> np.ndarray:
        # an FRD first: it has freqresp too, which interpolated it linearly onto this grid
        # (between coarse lines across a resonance: a made-up response, compared as measured)
        if isinstance(other, FRD):
            check_grid(self, other, "estimate both on one grid (spa's omega=, the same nperseg "
                       "/ lines), or compare with other.freqresp(frd.omega) to interpolate on "
                       "purpose")
            g = other.response
        elif hasattr(other, "freqresp"):
            dt = getattr(other, "dt", None)
            if dt and self.dt and not np.isclose(float(dt), float(self.dt), rtol=1e-9):
                # a discrete model's response is periodic in its own dt: another's differs
                # beyond any error of the measurement (as sysid.compare refuses it)
                raise DataError(f"the model has sample time {dt} but the FRD {self.dt}: "
                                "resample the model (sysid.d2c / sysid.c2d / sysid.d2d) or "
                                "compare on the FRD of its own sample time")
            g = np.asarray(other.freqresp(self.omega))
        else:
            g = _as_complex(other, "other", "a model with freqresp, an FRD or ")
            if g.ndim == 1 and self.response.shape[1:] == (1, 1):
                g = g[:, None, None]  # one pair, as the constructor takes it
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
        iu = channels(inputs, self.input_names, "input")
        iy = channels(outputs, self.output_names, "output")

        def sub(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else a[:, iy][:, :, iu]

        return self._new(
            sub(self.response), coherence=sub(self.coherence), std=sub(self.std),
            confidence=self.confidence, dof=self.dof, dt=self.dt,
            input_names=[self.input_names[i] for i in iu],
            output_names=[self.output_names[i] for i in iy], method=self.method, info=self.info,
            units=self.units,
        )

    def fselect(self, lo: Any = None, hi: Any = None, *, units: str | None = None) -> FRD:
        """The response at some of its frequencies (MATLAB's ``fselect``), with its std and
        coherence: those from ``lo`` to ``hi`` (both included; ``None``: no bound) in
        ``units`` (default the FRD's own, rad/s unless it was given in Hz), or, with ``hi``
        left out, those at the indices (or boolean mask) ``lo``. A frequency-domain fit
        (``tfest``, ``ssest``, ``frd_subspace``) of the result fits that band only.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> g = sysid.FRD([1.0, 2.0, 5.0, 10.0], np.ones(4), units="Hz")
        >>> g.fselect(2, 6).frequencies, g.fselect([0, 3]).frequencies
        (array([2., 5.]), array([ 1., 10.]))
        >>> g.fselect(20, None)
        Traceback (most recent call last):
        ...
        sysid.errors.DataError: no frequency from 20 to inf Hz: the FRD spans 1 to 10 Hz
        """
        unit = _unit(units) or self.units or "rad/s"
        f = self.omega / UNITS[unit]
        if hi is None and np.ndim(lo) == 1:  # indices or a mask
            sel = np.asarray(lo)
            if sel.dtype == bool:
                if sel.shape != f.shape:
                    raise ShapeError(f"a mask of frequencies has {f.size} entries (one per "
                                     f"frequency), got {sel.size}")
                idx = np.flatnonzero(sel)
            elif sel.dtype.kind in "iu" and sel.size and sel.min() >= -f.size and \
                    sel.max() < f.size:
                idx = np.unique(sel % f.size)
            else:
                raise DataError(f"frequency indices must be integers from 0 to {f.size - 1} "
                                f"(or a boolean mask), got {lo!r:.60}")
        else:
            a = -np.inf if lo is None else float(lo)
            b = np.inf if hi is None else float(hi)
            if not a <= b:
                raise DataError(f"fselect needs lo <= hi, got {lo} and {hi}")
            idx = np.flatnonzero((f >= a) & (f <= b))
            if not idx.size:
                raise DataError(f"no frequency from {a:g} to {b:g} {unit}: the FRD spans "
                                f"{f[0]:g} to {f[-1]:g} {unit}")
        if not idx.size:
            raise DataError("the selection holds no frequency")

        def sub(x: np.ndarray | None) -> np.ndarray | None:
            return None if x is None else x[idx]

        out = type(self)(self.omega[idx], self.response[idx], coherence=sub(self.coherence),
                         std=sub(self.std), confidence=self.confidence, dof=self.dof,
                         dt=self.dt, input_names=self.input_names,
                         output_names=self.output_names, method=self.method, info=self.info)
        out.units = self.units
        return out

    def _new(self, response: Any, *, units: str | None, **kw: Any) -> FRD:
        """An FRD on this grid (:attr:`omega` bit for bit) shown in ``units``."""
        out = type(self)(self.omega, response, **kw)
        out.units = units
        return out

    @classmethod
    def from_model(cls, model: Any, omega: Any, *, units: str | None = None) -> FRD:
        """The frequency response of a model (anything with ``freqresp(omega)``) as an FRD,
        ``omega`` in rad/s or in ``units``.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]], dt=0.1)
        >>> sysid.FRD.from_model(m, np.linspace(0.1, 30.0, 10))
        FRD (model): 10 frequencies 0.1..30 rad/s, 1 output x 1 input
        """
        require_freqresp(model, "model")
        w = np.asarray(omega, dtype=float) * UNITS[_unit(units) or "rad/s"]
        return cls(  # a continuous model (dt = 0) gives an FRD without a sample time
            omega, model.freqresp(w), units=units,
            dt=getattr(model, "dt", None) or None,
            input_names=getattr(model, "input_names", None),
            output_names=getattr(model, "output_names", None), method="model",
        )

    def to_pandas(self) -> Any:
        """A long-format DataFrame: one row per frequency and output/input pair with
        ``omega``, ``hz``, ``output``, ``input``, ``real``, ``imag``, ``magnitude``,
        ``phase`` (rad) and, when known, ``coherence`` and ``std``."""
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

    def _repr_html_(self) -> str:
        """Notebook display: frequency range and magnitude plots (see :mod:`sysid._display`)."""
        from .._display import frd_html

        return frd_html(self)

    def __repr__(self) -> str:
        l, m = self.n_outputs, self.n_inputs
        meth = f" ({self.method})" if self.method else ""
        f = self.frequencies
        return (
            f"FRD{meth}: {f.size} frequencies {f[0]:.3g}..{f[-1]:.3g} "
            f"{self.units or 'rad/s'}, {l} output{'s' * (l != 1)} x "
            f"{m} input{'s' * (m != 1)}"
        )


def _as_complex(x: Any, name: str, what: str = "") -> np.ndarray:
    """``x`` as a complex array; a :class:`DataError` naming ``name`` when it is not numeric."""
    if not isinstance(x, (str, bytes)):
        try:
            arr = np.asarray(x)
            if arr.dtype.kind in "biufc":
                return arr.astype(complex, copy=False)
        except (TypeError, ValueError):
            pass
    raise DataError(f"{name} must be {what}a numeric (complex) array of responses, got "
                    f"{type(x).__name__}" + (f" {x!r}" if isinstance(x, (str, bytes)) else ""))


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
