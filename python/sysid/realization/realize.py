"""Realisation: state-space models from Markov parameters.

State-space models from Markov parameters ``h_0 = D, h_k = C A^{k-1} B``:

- :func:`ho_kalman` (Ho and Kalman 1966): exact Markov parameters, order = rank of the
  block-Hankel matrix;
- :func:`kung` (Kung 1978): SVD truncation and the shift invariance of the observability
  matrix, for noisy Markov parameters;
- :func:`era` (Juang and Pappa 1985): any Hankel shape, MIMO, with the Hankel singular values
  for the order and the modal accuracy indicators MAC (modal amplitude coherence) and MPC
  (modal phase collinearity) that separate physical modes from noise modes.

Markov parameters from input/output data (:func:`impulse_response`, :func:`okid`,
:func:`impulse_from_frf`) are estimated in :mod:`sysid.realization.markov` and arrive here as
:class:`MarkovEstimate`.

Markov parameters are arrays shaped ``(count, noutputs, ninputs)``, the layout of
:meth:`sysid.StateSpaceModel.markov`. The numerics run in the Rust core.

The Hankel SVD weighs every entry in its own units, so with several channels the truncated
model changes with them (an output recorded in units 1000 times smaller and an input in units
1000 times larger moved the poles of a noisy 2 x 2 realisation by 0.017). With
``scale=True`` (the default) each output row is divided and each input column multiplied by
the scales that give every output row and input column of the Markov parameters a unit root
mean square over the lags and the other channels
(:func:`sysid.subspace.scaling.balanced_scales`); the model is realised from those and
returned in the record's units, the scales in ``info["channel_scaling"]``. It is then the
same whatever the units. ``scale=False`` realises the Markov parameters as given.

Examples
--------
>>> import numpy as np, sysid
>>> true = sysid.StateSpaceModel([[0.9, 0.2], [-0.2, 0.9]], [[1.0], [0.0]], [[1.0, 0.5]])
>>> r = sysid.era(true.markov(40))
>>> r.model.nstates
2
>>> bool(np.allclose(np.sort_complex(r.model.poles()), np.sort_complex(true.poles())))
True
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int, stability_criteria, user_stacklevel
from ..analysis.modal import ModalAnalysis, modal_analysis
from ..errors import DataError, NonFiniteError, ShapeError, StabilityWarning
from ..models.checks import warn_unstable
from ..models.statespace import StateSpaceModel
from ..subspace.scaling import balanced_scales, check_scale, in_record_units

__all__ = [
    "ho_kalman",
    "kung",
    "era",
    "EraResult",
    "MarkovEstimate",
    "era_stabilization",
    "StabilizationDiagram",
]


def _markov(markov: Any) -> tuple[np.ndarray, float | None]:
    """Markov parameters as a finite float array ``(count, l, m)`` and the dt they carry."""
    dt = None
    if isinstance(markov, MarkovEstimate):
        dt = markov.dt
        markov = markov.markov
    if isinstance(markov, (str, bytes)):
        raise ShapeError("markov must be a numeric array (count, noutputs, ninputs), got a string")
    h = np.asarray(markov)
    if h.dtype.kind not in "biuf":
        raise DataError(f"markov must be real and numeric, got dtype {h.dtype}")
    h = h.astype(np.float64, copy=False)
    if h.ndim == 1:
        h = h[:, None, None]
    if h.ndim != 3:
        raise ShapeError(
            f"markov must have shape (count, noutputs, ninputs) like StateSpaceModel.markov(), "
            f"got {h.ndim}-D with shape {h.shape}"
        )
    if 0 in h.shape:
        raise ShapeError(f"markov is empty (shape {h.shape})")
    if not np.isfinite(h).all():
        k, i, j = np.argwhere(~np.isfinite(h))[0]
        raise NonFiniteError(
            f"markov has a non-finite value (NaN or Inf) in Markov parameter {k}, output {i}, "
            f"input {j}; the realisation needs finite impulse responses"
        )
    return h, dt


def _count(x: int | None, name: str) -> int | None:
    return None if x is None else as_int(x, name, alt="None")


def _model(d: dict[str, Any], dt: float, method: str, **info: Any) -> StateSpaceModel:
    """The realised model in the record's units (``d["scales"]``: those it was realised in)."""
    model = StateSpaceModel(
        d["a"], d["b"], d["c"], d["d"], dt=dt,
        info={"method": method, "singular_values": d["singular_values"],
              "rows": d["rows"], "cols": d["cols"], **info},
    )
    out = in_record_units(model, *d["scales"], basis="markov parameters")
    if out is not model and np.array_equal(d["d"], d["h0"][1]):
        out.D = d["h0"][0].copy()  # h_0 as given, not its round trip through the scales
    return out


_MAX_MARKOV = 1e150


def _warned(model: StateSpaceModel, method: str) -> StateSpaceModel:
    """``model``, with a :class:`~sysid.StabilityWarning` when a pole is on or outside the
    unit circle (the ball-and-beam record's ERA model returned |p| = 1.05 silently)."""
    warn_unstable(model, method, advice=(
        "Unless the system itself is unstable, try another order (the singular values), "
        "more Hankel rows and columns, or Markov parameters from a longer record; "
        "sysid.pem(data, model, focus='simulation') refines it to a stable model."))
    return model


def _realize(method: str, markov: Any, order: int | None, rows: int | None, cols: int | None,
             dt: float | None, rank_tol: float = 1e-8, scale: bool | None = None
             ) -> tuple[dict[str, Any], float]:
    scale = check_scale(scale)
    if not (isinstance(rank_tol, (int, float, np.number)) and 0 < float(rank_tol) < 1):
        raise DataError(f"rank_tol must lie strictly between 0 and 1 (a fraction of the "
                        f"largest singular value), got {rank_tol!r}")
    h, dt_h = _markov(markov)
    dt = float(dt if dt is not None else (dt_h if dt_h is not None else 1.0))
    count, l, m = h.shape
    # OKID's Markov parameters have a Hankel rank of p l by construction (its observer of p
    # past samples): the automatic order stops below it (the core's RealizationOptions)
    cap = None
    if isinstance(markov, MarkovEstimate) and markov.method == "okid":
        cap = max(1, int(markov.info["observer_order"]) * l - 1)
    big = float(np.max(np.abs(h))) if h.size else 0.0
    if big > _MAX_MARKOV:  # products in the Hankel SVD would overflow double precision
        raise DataError(f"Markov parameters up to {big:.3g} are too large to realise in double "
                        f"precision (limit {_MAX_MARKOV:g}); divide them by a common scale "
                        "(for example their largest magnitude) and scale B and D back")
    su, sy = balanced_scales(h, "Markov parameters") if scale else (np.ones(m), np.ones(l))
    h0 = h[0]
    if scale and not (np.all(su == 1.0) and np.all(sy == 1.0)):
        h = h * su[None, None, :] / sy[None, :, None]
    out = _sysid.realize(
        method, np.ascontiguousarray(h.reshape(count * l, m)), l,
        _count(order, "order"), _count(rows, "rows"), _count(cols, "cols"), float(rank_tol),
        cap if method != "ho_kalman" else None,
    )
    out["scales"], out["h0"] = (su, sy), (h0, h[0])
    return out, dt


def ho_kalman(markov: Any, order: int | None = None, *, rows: int | None = None,
              cols: int | None = None, rank_tol: float = 1e-8, dt: float | None = None,
              scale: bool | None = None) -> StateSpaceModel:
    """Ho-Kalman realisation from exact Markov parameters.

    Parameters
    ----------
    markov : array_like or MarkovEstimate
        ``(count, noutputs, ninputs)``: ``h_0 = D, h_1 = CB, ...``.
    order : int, optional
        Model order; by default the numerical rank of the block-Hankel matrix.
    rows, cols : int, optional
        Block rows and columns of the Hankel matrix; ``rows + cols <= count - 1`` (the shifted
        matrix needs one more parameter). By default the parameters are split evenly.
    rank_tol : float
        Singular values below ``rank_tol`` times the largest do not count towards the rank.
    dt : float, optional
        Sample time of the model (taken from a MarkovEstimate, else 1).
    scale : bool, optional
        Realise from the Markov parameters with every output row and input column at unit
        root mean square (see :mod:`sysid.realization.realize`) and return the model in the
        record's units: the same model whatever the channels' units. Default True
        (:data:`sysid.subspace.scaling.SCALE_DEFAULT`); ``False`` realises the parameters as
        given. Nothing changes with one input and one output.

    Returns
    -------
    StateSpaceModel
        ``info["singular_values"]`` holds the Hankel singular values (of the scaled
        parameters), ``info["channel_scaling"]`` the scales.

    Examples
    --------
    >>> import sysid
    >>> true = sysid.StateSpaceModel([[0.5, 0.1], [0.0, -0.3]], [[1.0], [1.0]], [[1.0, 2.0]])
    >>> sysid.ho_kalman(true.markov(12)).nstates
    2
    """
    out, dt = _realize("ho_kalman", markov, order, rows, cols, dt, rank_tol, scale)
    return _warned(_model(out, dt, "ho_kalman"), "ho_kalman")


def kung(markov: Any, order: int | None = None, *, rows: int | None = None,
         cols: int | None = None, dt: float | None = None, scale: bool | None = None
         ) -> StateSpaceModel:
    """Kung's SVD realisation from (noisy) Markov parameters.

    The order is ``order`` or chosen from the Hankel singular values as :func:`era` does; A
    comes from the shift invariance of the observability matrix (least squares over all
    block rows).

    Parameters
    ----------
    markov : array_like or MarkovEstimate
        ``(count, noutputs, ninputs)``.
    order : int, optional
        Model order; by default chosen from the Hankel singular values as :func:`era`
        chooses it.
    rows, cols : int, optional
        Block rows (at least 2) and columns of the Hankel matrix.
    dt : float, optional
        Sample time of the model.
    scale : bool, optional
        Realise from the Markov parameters with every output row and input column at unit
        root mean square (see :mod:`sysid.realization.realize`) and return the model in the
        record's units: the same model whatever the channels' units. Default True
        (:data:`sysid.subspace.scaling.SCALE_DEFAULT`); ``False`` realises the parameters as
        given. Nothing changes with one input and one output.

    Returns
    -------
    StateSpaceModel

    Examples
    --------
    >>> import numpy as np, sysid
    >>> h = 0.8 ** np.arange(30.0)
    >>> h[0] = 0.0
    >>> m = sysid.kung(h, order=1)
    >>> round(float(m.A[0, 0]), 10)
    0.8
    """
    out, dt = _realize("kung", markov, order, rows, cols, dt, scale=scale)
    return _warned(_model(out, dt, "kung"), "kung")


class EraResult:
    """ERA model with its Hankel singular values and per-mode accuracy indicators.

    Attributes
    ----------
    model : StateSpaceModel
        The realised model.
    singular_values : ndarray
        Singular values of the block-Hankel matrix (for the order choice).
    eigenvalues : ndarray
        Discrete-time poles, in the order of ``mac`` and ``mpc``.
    mac : ndarray
        Modal amplitude coherence of each pole, in [0, 1] (near 1: supported by the data).
    mpc : ndarray
        Modal phase collinearity of each pole's mode shape, in [0, 1] (1: a normal mode; always
        1 with a single output).
    rows, cols : int
        Hankel block rows and columns used.
    """

    def __init__(self, d: dict[str, Any], dt: float) -> None:
        self.model = _model(d, dt, "era")
        self.singular_values = np.asarray(d["singular_values"])
        self.eigenvalues = np.asarray(d["eig_re"]) + 1j * np.asarray(d["eig_im"])
        self.mac = np.asarray(d["mac"])
        self.mpc = np.asarray(d["mpc"])
        self.rows = int(d["rows"])
        self.cols = int(d["cols"])
        self.model.info.update(mac=self.mac, mpc=self.mpc)

    @property
    def order(self) -> int:
        """Model order."""
        return self.model.nstates

    def modes(self) -> ModalAnalysis:
        """Modal analysis of the model (frequencies in Hz and rad/s, damping, shapes).

        Each mode carries the MAC and MPC of its pole in ``extra``.
        """
        res = modal_analysis(self.model)
        mac = np.empty(len(res.eigenvalues))
        mpc = np.empty(len(res.eigenvalues))
        for k, z in enumerate(res.eigenvalues):
            i = int(np.argmin(np.abs(self.eigenvalues - z)))
            mac[k], mpc[k] = self.mac[i], self.mpc[i]
        res.extra = {"mac": mac, "mpc": mpc}
        return res

    def plot(self, *, ax: Any = None) -> Any:
        """Hankel singular values with the chosen order (matplotlib axes)."""
        from ..plot.realization import plot_hankel_singular_values

        return plot_hankel_singular_values(self.singular_values, self.order, ax=ax)

    def to_pandas(self) -> Any:
        """The modes with their MAC and MPC (:meth:`modes`)."""
        return self.modes().to_pandas()

    def summary(self) -> str:
        """The order, the Hankel singular values around it, and the modes with their MAC
        and MPC."""
        lo = max(0, self.order - 2)
        near = self.singular_values[lo:self.order + 2]
        lines = repr(self).splitlines()
        return "\n".join(lines[:1] + [f"  Hankel singular values {lo + 1}..{lo + near.size}: "
                                       + ", ".join(f"{v:.4g}" for v in near)] + lines[1:])

    def __repr__(self) -> str:
        head = (f"EraResult(order={self.order}, hankel {self.rows}x{self.cols} blocks, "
                f"min MAC={self.mac.min():.3f}, min MPC={self.mpc.min():.3f})")
        if np.isnan(self.mac).any():  # a defective A: no modes to tabulate
            return head + "\n(A is defective: no modal table)"
        return head + "\n" + self.modes().table()


def era(markov: Any, order: int | None = None, *, rows: int | None = None,
        cols: int | None = None, dt: float | None = None, scale: bool | None = None
        ) -> EraResult:
    """Eigensystem Realisation Algorithm with modal accuracy indicators.

    Parameters
    ----------
    markov : array_like or MarkovEstimate
        ``(count, noutputs, ninputs)``: ``h_0 = D, h_1 = CB, ...``.
    order : int, optional
        Model order; by default the numerical rank of the Hankel matrix on noise-free
        Markov parameters, and on noisy ones the count of its singular values above the
        noise floor (Gavish and Donoho's optimal hard threshold for a noise level from their
        median; the largest gap of their logarithms where the matrix is too small to show
        the floor). For :func:`sysid.okid`'s Markov parameters, whose errors follow its
        observer (their Hankel matrix has rank ``observer_order * noutputs`` by
        construction), the largest gap below that rank.
    rows, cols : int, optional
        Block rows and columns of the Hankel matrix, ``rows + cols <= count - 1``.
        More block rows than the order (times the outputs) and columns spanning the slowest
        decay give the best modal estimates.
    dt : float, optional
        Sample time (taken from a MarkovEstimate, else 1): used for frequencies in Hz.
    scale : bool, optional
        Realise from the Markov parameters with every output row and input column at unit
        root mean square (see :mod:`sysid.realization.realize`) and return the model in the
        record's units: the same model whatever the channels' units. Default True
        (:data:`sysid.subspace.scaling.SCALE_DEFAULT`); ``False`` realises the parameters as
        given. The singular values, MAC and MPC are those of the scaled
        parameters (the same whatever the units). Nothing changes with one input and one output.

    Returns
    -------
    EraResult

    Examples
    --------
    >>> import numpy as np, sysid
    >>> true = sysid.StateSpaceModel([[0.9, 0.3], [-0.3, 0.9]], [[1.0], [0.0]],
    ...                              [[1.0, 0.0], [0.5, 1.0]], dt=0.01)
    >>> r = sysid.era(true.markov(41), rows=10, cols=30, dt=0.01)
    >>> r.order, bool(np.all(r.mac > 0.999))
    (2, True)
    >>> f_true = sysid.modal_analysis(true).frequencies_hz
    >>> bool(np.allclose(r.modes().frequencies_hz, f_true))
    True
    """
    out, dt = _realize("era", markov, order, rows, cols, dt, scale=scale)
    res = EraResult(out, dt)
    _warned(res.model, "era")
    if np.isnan(res.mac).any():
        from ..errors import SysidWarning

        warnings.warn(
            f"the realised A of order {res.order} is defective (repeated poles without a full "
            "set of eigenvectors): its modal indicators (MAC, MPC) and modes are not defined "
            "(NaN); the model stands. Choose another order (the singular values: "
            "result.plot()) for a modal reading", SysidWarning, stacklevel=user_stacklevel())
    return res


class MarkovEstimate:
    """Markov parameters estimated from input/output data.

    The estimate reads as MATLAB's ``impulseest`` model does: :meth:`impulse` and
    :meth:`step` give its responses (:class:`~sysid.TimeResponse`, the impulse response
    with its standard deviations when estimated), :meth:`plot` draws the impulse response
    with its bands (``impulseplot`` with ``showConfidence``), :meth:`summary` and
    :meth:`to_pandas` give it as text and a table.

    Attributes
    ----------
    markov : ndarray
        ``(count, noutputs, ninputs)``, ``h_0 = D`` first.
    dt : float
        Sample time of the data.
    method : str
        ``"fir"`` (least squares), ``"fir-tc"`` (TC-regularised) or ``"okid"``.
    info : dict
        Method details: TC hyperparameters and noise variances, or OKID's observer Markov
        parameters ``(p, l, m + l)`` and residual covariance. A FIR estimate's ``"std"``
        (the shape of ``markov``): each parameter's standard deviation, the least-squares
        one (``"fir"``) or the TC posterior's (``"fir-tc"``, the prior included).
    input_names : list of str
        The record's input names.
    output_names : list of str
        The record's output names.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(400)
    >>> y = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(u)[:, 0]
    >>> est = sysid.impulse_response(sysid.IOData(u, y + 0.01 * rng.standard_normal(400)), 20)
    >>> est.to_pandas()[["y0 <- u0", "y0 <- u0 std"]].round(2).iloc[1:3].values.tolist()
    [[1.0, 0.0], [0.7, 0.0]]
    >>> round(float(est.step().y[-1, 0, 0]), 2)  # the gain 1 / (1 - 0.7)
    3.33
    """

    def __init__(self, markov: np.ndarray, dt: float, method: str, info: dict[str, Any], *,
                 input_names: Any = None, output_names: Any = None) -> None:
        self.markov = markov
        self.dt = dt
        self.method = method
        self.info = info
        _, l, m = np.shape(markov)
        self.input_names = ([f"u{j}" for j in range(m)] if input_names is None
                            else [str(s) for s in input_names])
        self.output_names = ([f"y{i}" for i in range(l)] if output_names is None
                             else [str(s) for s in output_names])

    def impulse(self) -> Any:
        """The impulse response ``h_k`` at ``t = k dt`` as a :class:`~sysid.TimeResponse`,
        with each value's standard deviation when the estimate has them (FIR)."""
        from ..models.protocol import TimeResponse

        t = np.arange(self.markov.shape[0]) * self.dt
        return TimeResponse("impulse", t, self.markov, self, std=self.info.get("std"))

    def step(self) -> Any:
        """The step response, the running sum of the Markov parameters, as a
        :class:`~sysid.TimeResponse` (no standard deviations: those of a sum need the
        parameters' covariance, which the estimate does not keep)."""
        from ..models.protocol import TimeResponse

        t = np.arange(self.markov.shape[0]) * self.dt
        return TimeResponse("step", t, np.cumsum(self.markov, axis=0), self)

    def plot(self, fig: Any = None) -> Any:
        """The impulse response, one axis per ``output <- input`` pair, with its bands."""
        return self.impulse().plot(fig=fig)

    def to_pandas(self) -> Any:
        """The impulse response by time, a column per pair (and its ``std``)."""
        return self.impulse().to_pandas()

    def summary(self) -> str:
        """What was estimated, and per pair the largest Markov parameter and its time."""
        lines = [repr(self)]
        std = self.info.get("std")
        for i, o in enumerate(self.output_names):
            for j, u in enumerate(self.input_names):
                h = self.markov[:, i, j]
                k = int(np.argmax(np.abs(h))) if h.size else 0
                sd = "" if std is None else f" (std {std[k, i, j]:.3g})"
                lines.append(f"  {o} <- {u}: largest {h[k]:.4g}{sd} at t = {k * self.dt:.4g}, "
                             f"sum (the gain) {h.sum():.4g}")
        if "length" in self.info:
            lines.append(f"  length: {self.info['length']}")
        return "\n".join(lines)

    def era(self, order: int | None = None, *, rows: int | None = None,
            cols: int | None = None, scale: bool | None = None) -> EraResult:
        """ERA on these Markov parameters (see :func:`sysid.era`)."""
        return era(self, order, rows=rows, cols=cols, scale=scale)

    def __repr__(self) -> str:
        c, l, m = self.markov.shape
        return (f"MarkovEstimate({self.method}: {c} Markov parameters, {l} output(s), "
                f"{m} input(s), dt={self.dt:g}, {self.info.get('samples', '?')} equations)")


class StabilizationDiagram:
    """ERA modes over a range of orders, each flagged by its stability across orders.

    Attributes
    ----------
    orders : list of int
        Model orders realised.
    modes : list of ModalAnalysis
        The modes at each order (with ``extra["mac"]`` and ``extra["mpc"]``).
    status : list of ndarray
        Per mode: 2 = frequency and damping agree with a mode of the previous order and MAC is
        above ``min_mac``; 1 = frequency agrees only; 0 = new.
    """

    def __init__(self, orders: list[int], modes: list[ModalAnalysis],
                 status: list[np.ndarray]) -> None:
        self.orders = orders
        self.modes = modes
        self.status = status

    def stable_frequencies(self, min_count: int = 3) -> np.ndarray:
        """Frequencies (Hz) of modes fully stable at ``min_count`` or more orders (clustered)."""
        f = np.sort(np.concatenate([m.frequencies_hz[s == 2] for m, s in
                                    zip(self.modes, self.status)] or [np.empty(0)]))
        out: list[float] = []
        start = 0
        for i in range(1, f.size + 1):
            if i == f.size or f[i] > f[i - 1] * 1.01:
                if i - start >= min_count:
                    out.append(float(np.median(f[start:i])))
                start = i
        return np.asarray(out)

    def plot(self, *, ax: Any = None) -> Any:
        """Frequency against order (matplotlib axes)."""
        from ..plot.realization import plot_stabilization

        return plot_stabilization(self, ax=ax)

    def to_pandas(self) -> Any:
        """One row per mode and order: ``order``, ``frequency [Hz]``, ``damping`` and
        ``status`` (``"stable"``: frequency, damping and MAC agree with the previous
        order; ``"frequency"``: the frequency alone; ``"new"``).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> k = np.arange(1, 41)
        >>> h = (0.9 ** k * np.cos(0.5 * k) + 0.8 ** k * np.cos(1.5 * k))[:, None, None]
        >>> df = sysid.era_stabilization(h, [2, 4]).to_pandas()
        >>> list(df.columns), df["order"].tolist()
        (['order', 'frequency [Hz]', 'damping', 'status'], [2, 4, 4])
        """
        import pandas as pd

        names = {2: "stable", 1: "frequency", 0: "new"}
        rows = [(n, f, d, names[int(st)]) for n, m, sts in zip(self.orders, self.modes,
                                                              self.status)
                for f, d, st in zip(m.frequencies_hz, m.damping, sts)]
        return pd.DataFrame(rows, columns=["order", "frequency [Hz]", "damping", "status"])

    def summary(self, min_count: int = 3) -> str:
        """The orders, the modes stable at ``min_count`` or more of them, and per order
        how many modes are stable, agree in frequency only, or are new."""
        lines = [repr(self), f"  stable at {min_count} or more orders (Hz): "
                 + (", ".join(f"{f:.4g}" for f in self.stable_frequencies(min_count))
                    or "none")]
        if len(self.orders) < min_count:
            lines.append(f"  (a mode is stable across orders: give at least {min_count} "
                         "orders, e.g. range(2, 41, 2))")
        for n, st in zip(self.orders, self.status):
            lines.append(f"  order {n}: {int(np.sum(st == 2))} stable, "
                         f"{int(np.sum(st == 1))} frequency only, {int(np.sum(st == 0))} new")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"StabilizationDiagram(orders {self.orders[0]}..{self.orders[-1]}, stable "
                f"modes at {np.round(self.stable_frequencies(), 3).tolist()} Hz)")


def era_stabilization(markov: Any, orders: Any, *, rows: int | None = None,
                      cols: int | None = None, dt: float | None = None,
                      freq_tol: float = 0.01, damping_tol: float = 0.05,
                      min_mac: float = 0.9, scale: bool | None = None
                      ) -> StabilizationDiagram:
    """Stabilisation diagram: ERA at each order, modes compared with the previous order.

    Physical modes reappear at the same frequency and damping as the order grows; noise
    modes wander. A mode is flagged stable when a mode of the previous order lies within
    ``freq_tol`` (relative) in frequency and ``damping_tol`` (relative) in damping and its MAC
    exceeds ``min_mac``.

    Parameters
    ----------
    markov : array_like or MarkovEstimate
        Markov parameters ``(count, noutputs, ninputs)``.
    orders : iterable of int
        Increasing model orders.
    rows, cols : int, optional
        Hankel block rows and columns (as in :func:`era`).
    dt : float, optional
        Sample time (from a MarkovEstimate, else 1).
    freq_tol, damping_tol, min_mac : float
        Stability criteria.
    scale : bool, optional
        Realise with the channels scaled, as :func:`era` (default True).

    Returns
    -------
    StabilizationDiagram

    Examples
    --------
    >>> import numpy as np, sysid
    >>> true = sysid.StateSpaceModel([[0.9, 0.3], [-0.3, 0.9]], [[1.0], [0.0]], [[1.0, 0.0]],
    ...                              dt=0.01)
    >>> h = true.markov(81) + 1e-4 * np.random.default_rng(0).standard_normal((81, 1, 1))
    >>> d = sysid.era_stabilization(h, range(2, 12, 2), dt=0.01)
    >>> f = sysid.modal_analysis(true).frequencies_hz
    >>> bool(np.allclose(d.stable_frequencies(), f, rtol=1e-3))
    True
    """
    if not hasattr(orders, "__iter__") or isinstance(orders, str) or np.ndim(orders) > 1:
        raise DataError(f"orders must be an increasing sequence of model orders (e.g. "
                        f"range(2, 21, 2)), got {orders!r}")
    orders = [as_int(o, "orders") for o in orders]
    freq_tol, damping_tol, min_mac = stability_criteria(freq_tol, damping_tol, min_mac)
    if not orders or any(b <= a for a, b in zip(orders, orders[1:])):
        raise DataError(f"orders must be a non-empty increasing sequence, got {orders}")
    modes_list: list[ModalAnalysis] = []
    status: list[np.ndarray] = []
    prev: ModalAnalysis | None = None
    for order in orders:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StabilityWarning)  # the diagram shows every order
            modes = era(markov, order, rows=rows, cols=cols, dt=dt, scale=scale).modes()
        st = np.zeros(len(modes), dtype=int)
        if prev is not None and len(prev):
            for k in range(len(modes)):
                df = np.abs(prev.frequencies_hz - modes.frequencies_hz[k])
                j = int(np.argmin(df))
                if df[j] <= freq_tol * max(modes.frequencies_hz[k], 1e-12):
                    st[k] = 1
                    dz = abs(prev.damping[j] - modes.damping[k])
                    if (dz <= damping_tol * max(abs(modes.damping[k]), 1e-12)
                            and modes.extra["mac"][k] >= min_mac):
                        st[k] = 2
        modes_list.append(modes)
        status.append(st)
        prev = modes
    return StabilizationDiagram(orders, modes_list, status)
