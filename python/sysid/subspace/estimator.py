"""Subspace identification: one pass compresses the data, every fit reuses the compression.

The estimator builds the triangular factor ``L`` of the block-Hankel data matrix once (the
only step that touches every sample, in the Rust core with the GIL released). The weighted
SVD, the order choice and the system matrices then work on ``L`` alone, so trying other
orders or weightings is cheap.

Methods (``method=``):

``"moesp"`` (default, alias ``"po-moesp"``)
    PO-MOESP (Verhaegen 1994): past inputs and outputs as instruments; consistent with
    process and measurement noise.
``"ordinary-moesp"``
    MOESP without instruments: only future inputs and outputs (Verhaegen & Dewilde 1992,
    the seed slides' ordinary MOESP); consistent for output-error (measurement-noise-only)
    data, biased with process noise.
``"pi-moesp"``
    MOESP with past inputs as instruments (Verhaegen & Dewilde 1992).
``"n4sid"``
    N4SID (Van Overschee & De Moor 1994): oblique projection, unit weights.
``"cva"``
    Canonical variate analysis (Larimore 1990): the future outputs whitened first; the
    singular values are canonical correlations (between 0 and 1).
``"pbsid"``, ``"ssarx"``
    Closed-loop methods (PBSID-opt, Chiuso 2007; SSARX, Jansson 2003): a VARX of the
    predictor first, so that they stay consistent under feedback when the loop has a delay
    (see :mod:`sysid.subspace.closed_loop`). The open-loop methods warn
    (:class:`sysid.FeedbackWarning`) when the record shows feedback.

Singular values follow SLICOT's convention: the data are not divided by ``sqrt(N)``
(``cva`` reports canonical correlations instead, which do not scale with N).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any, Literal, Union

import numpy as np

from .. import _sysid
from .._checks import (
    as_int,
    as_option,
    as_orders,
    check_magnitudes,
    record_stats,
    require_inputs_vary,
    require_samples,
    user_stacklevel,
)
from .._display import pvalue
from ..data.excitation import FLAT_LAGS, RANK_LAGS, spectral_excitation_order
from ..data.input_design import warn_excitation
from ..data.iodata import IOData, require_record
from ..data.offsets import check_offsets
from ..data.segments import long_enough
from ..errors import (
    DataError,
    ExcitationError,
    FeedbackWarning,
    OrderError,
    RiccatiError,
    SysidError,
    SysidWarning,
)
from ..models.checks import warn_unstable
from ..models.statespace import StateSpaceModel
from ..validation.feedback import (
    FEEDBACK_WARNING_LEVEL,
    check_feedback,
    default_lags,
    feedback_statistics,
)
from .data_horizon import available_horizon
from .feedthrough import (
    FEEDTHROUGH_DEFAULT,
    check_feedthrough,
    choose_feedthrough,
    default_feedthrough,
)
from .kalman import schur_gain
from .methods import CLOSED_LOOP, METHODS, _method
from .scaling import check_scale, in_record_units, scaled_experiments
from .series_horizon import refuse_white_noise, series_horizons
from .steptest import refuse_step_test
from .streaming import compression_info, warn_if_fallback

__all__ = ["SubspaceEstimator", "default_horizon", "METHODS"]


Order = Union[int, Literal["auto"], Sequence[int]]


def _preprocessing(data: IOData, from_factor: bool) -> dict[str, Any]:
    """What the record says was done to it before fitting (trend removed, scaling)."""
    if from_factor:
        return {"source": "a precomputed HankelFactor (pre-processing unknown)"}
    detrended, u_scale, y_scale = data._trend_info()
    return {
        "experiments": data.n_experiments,
        "samples": data.lengths,
        "detrended": detrended,
        "input_scale": u_scale.tolist(),
        "output_scale": y_scale.tolist(),
    }


def _check_signals(data: IOData) -> None:
    """Refuse constant outputs and inputs (naming the channel); warn (OffsetWarning) about
    offsets; channels out of double precision's range first (their variance underflows)."""
    require_samples(data.lengths, "the subspace methods")  # else "constant" below
    stats = record_stats(data)  # one pass over the record for the three checks
    check_magnitudes(data, "the subspace methods", stats)
    if 1 in stats:
        _, mean, std = stats[1]
        for j, n in enumerate(data.output_names):
            if std[j] == 0:
                raise DataError(
                    f"output {n} is constant ({mean[j]:g}): there is nothing to identify; "
                    "check the channel (a stuck sensor, the wrong column?) or drop it")
    if data.input_names:  # else the horizon's rank test would refuse it without a name
        require_inputs_vary(data.experiments, "the subspace methods", data.input_names,
                            error=ExcitationError)
    # the one offset check of every linear estimator (sysid.data.offsets)
    check_offsets(data, who="the subspace methods", stats=stats)


def default_horizon(n_samples: int, n_inputs: int, n_outputs: int) -> int:
    """The horizon used when none is given, for one experiment of ``n_samples``.

    ``i = min(20, max(2, N // (20 (m + l))))``: the data matrix ``2 i (m + l)`` rows then has
    at least ten times as many columns as rows, and orders up to about ``i * l`` can be
    identified (:func:`available_horizon` with one experiment; several experiments: that
    function, from the experiments long enough for the window).

    Examples
    --------
    >>> from sysid.subspace.estimator import default_horizon
    >>> default_horizon(1000, 1, 1)
    20
    >>> default_horizon(200, 2, 2)
    2
    """
    return available_horizon([int(n_samples)], n_inputs, n_outputs)


def horizon_for_order(data: IOData, order: Any, horizon: int | None) -> int | None:
    """The horizon for fitting ``order`` states: ``horizon`` when given, else the default
    (:func:`available_horizon`; a time series: the past of
    :func:`~sysid.subspace.series_horizon.series_horizons` when it allows the order, else
    :func:`available_horizon`) or, when that allows fewer than ``order`` states (at most
    ``(i - 1) l``), the smallest horizon that allows them, provided the data have as many
    Hankel columns as its data matrix has rows (``2 i (m + l)``); otherwise the largest
    horizon the data support (whose order error then names the largest order they allow).
    MATLAB's ``n4sid(data, n)`` likewise fits any order the data support.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.subspace.estimator import horizon_for_order
    >>> u = np.random.default_rng(0).standard_normal((60, 5))
    >>> d = sysid.IOData(u, u[:, :3])                   # 60 samples, 5 in, 3 out
    >>> horizon_for_order(d, 3, None), horizon_for_order(d, 4, None), horizon_for_order(d, 9, None)
    (None, 3, 3)
    """
    if horizon is not None or isinstance(order, str) or np.ndim(order) or order is None:
        return horizon
    m, l = data.n_inputs, data.n_outputs
    lengths = list(data.lengths)
    if m == 0 and int(order) <= (series_horizons(data)["past"] - 1) * l:
        return None  # a time series' default (its AIC autoregression's) allows the order
    i0 = available_horizon(lengths, m, l)
    if int(order) <= (i0 - 1) * l:
        return i0 if m == 0 else None  # beyond a time series' autoregression: the record's
    def fits(i: int) -> bool:
        return sum(max(0, n - 2 * i + 1) for n in lengths) >= 2 * i * (m + l)

    need = -(-int(order) // l) + 1
    if need <= 50 and fits(need):
        return need
    # beyond the data: the largest horizon they support, whose order error then names the
    # largest order they allow
    top = max((i for i in range(i0, min(need, 51)) if fits(i)), default=i0)
    return top if top > i0 else None


class SubspaceEstimator:
    """Compress a record once, then fit state-space models of any order and weighting.

    Parameters
    ----------
    data : IOData or (u, y)
        The record (several experiments allowed; no Hankel column spans two).
    horizon : int, optional
        Past and future horizon ``i`` (block rows); default :func:`default_horizon`, with
        several experiments :func:`available_horizon` (experiments shorter than its window
        ``2 i`` are left out, with a warning; pass ``horizon`` to keep them). A time series
        (no input): the order of the autoregression AIC picks, plus one
        (:func:`~sysid.subspace.series_horizon.series_horizons`, recorded in
        :attr:`horizon_selection` and the models' ``info["horizon_selection"]``); ``n4sid``,
        ``moesp`` and ``cva`` then shorten the future to the order's.
    past, future : int, optional
        Separate past and future horizons (override ``horizon``).
    method : str
        Default weighting for :attr:`singular_values` and :meth:`fit`: one of
        :data:`METHODS` (``"moesp"``, ``"ordinary-moesp"``, ``"pi-moesp"``, ``"n4sid"``,
        ``"cva"``, and for closed-loop data ``"pbsid"``, ``"ssarx"``).
    chunk_rows : int, optional
        Hankel columns per QR update in the compressor (memory ``(k + chunk) k`` doubles).
    compressor : {"auto", "qr", "correlation"}
        ``"auto"`` (default): the fast correlation path (lagged correlation sums and
        Cholesky, about ``p + f`` times fewer flops) when its Gram matrix is well enough
        conditioned for the factor to match the exact one, else the exact QR pass
        (``factor.source == "qr-fallback"``); the decision and the relative pivot it was
        made from are in ``model.info["compression"]``. ``"qr"``: always exact;
        ``"correlation"``: fast, with the exact pass and a ``CompressionFallbackWarning``
        only when its Gram matrix is numerically singular. See docs/performance.md.
    scale : bool, optional
        Fit with every input and output at unit root mean square (the record's factor scaled,
        :mod:`sysid.subspace.scaling`) and return the model in the record's units: the
        estimate is then the same whatever the channels' units. Default True; ``False``
        computes in the record's units, as SLICOT's ``IB01AD`` does.
    matrices : {"shift", "states", "auto"}, optional
        How every open-loop fit takes ``A, B, C, D`` from the weighted SVD. ``"shift"``
        (default): ``A``, ``C`` by the shift invariance of the observability matrix, ``B``,
        ``D`` by least squares (Van Overschee & De Moor 1996); ``"states"``: all four by
        least squares on the estimated state sequence, ``x(t+1)`` on ``x(t), u(t)`` (Larimore
        1990; Verhaegen & Verdult 2007; SIPPY's and nfoursid's N4SID), often inside the unit
        circle where the shift's slow poles are not; ``"auto"``: the shift, and where its
        ``A`` is unstable the states' when stable (benches/results/subspace_defaults.md).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8, 0.2], [-0.2, 0.8]], [[1.0], [0.5]], [[1.0, 0.0]])
    >>> u = rng.standard_normal((500, 1))
    >>> est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=true.simulate(u)), horizon=5)
    >>> est.auto_order
    2
    >>> model = est.fit(order="auto")
    >>> np.allclose(np.sort_complex(model.poles()), np.sort_complex(true.poles()))
    True
    """

    def __init__(
        self,
        data: IOData | tuple[Any, Any],
        horizon: int | None = None,
        *,
        past: int | None = None,
        future: int | None = None,
        method: str = "moesp",
        chunk_rows: int | None = None,
        compressor: str = "auto",
        scale: bool | None = None,
        matrices: str | None = None,
    ) -> None:
        data = require_record(data, "SubspaceEstimator")
        matrices = "shift" if matrices is None else as_option(matrices, "matrices")
        method = _method(method)  # both checked before any pass over the data
        note, selection = "", None
        if horizon is None and past is None and future is None:
            # the horizon from the data available (a time series: from its AIC
            # autoregression, :mod:`sysid.subspace.series_horizon`); experiments too short
            # for its window are left out (and said), not allowed to set it
            if data.n_inputs == 0:
                selection = series_horizons(data)
                horizon = selection["past"]
            else:
                horizon = available_horizon(data.lengths, data.n_inputs, data.n_outputs)
            short = [f"{k} ({n} samples)" for k, n in enumerate(data.lengths)
                     if n < 2 * horizon]
            if short and len(short) < data.n_experiments:
                note = (
                    f" (experiment(s) {', '.join(short)} shorter than the window of the "
                    f"default horizon {horizon} were left out; pass horizon=... to keep them)")
                warnings.warn(f"SubspaceEstimator:{note[1:-1]}", SysidWarning,
                              stacklevel=user_stacklevel())
                data = long_enough(data, 2 * horizon) or data
        elif horizon is None:
            horizon = default_horizon(min(data.lengths), data.n_inputs, data.n_outputs)
        horizon = as_int(horizon, "horizon", 1)
        past = as_int(past if past is not None else horizon, "past", 1)
        future = as_int(future if future is not None else horizon, "future", 1)
        if chunk_rows is not None:
            chunk_rows = as_int(chunk_rows, "chunk_rows", 1)
        _check_signals(data)
        try:  # the window against the record, then the data-matrix size: both in the core
            factor = _sysid.compress(data.experiments, past, future, chunk_rows, compressor)
        except ExcitationError as e:
            refuse_step_test(e, data.experiments, past)
        warn_if_fallback(factor, requested=compressor)
        self._init_state(data, factor, method=method, matrices=matrices, compressor=compressor,
                         scale=scale, from_factor=False, horizon_note=note,
                         horizon_selection=selection)
        try:
            self._subspace(None)  # checks the record (length, excitation) right away
        except ExcitationError as e:
            refuse_step_test(e, data.experiments, self.past)

    @classmethod
    def from_factor(
        cls,
        factor: Any,
        *,
        dt: float = 1.0,
        method: str = "moesp",
        input_names: list[str] | None = None,
        output_names: list[str] | None = None,
        scale: bool | None = None,
        matrices: str | None = None,
    ) -> SubspaceEstimator:
        """An estimator on an already computed :class:`~sysid._sysid.HankelFactor`.

        For factors computed out of core, merged across experiments or machines, or loaded
        from disk. Fits with ``x0=True`` need the data and are not available. ``scale``: as
        the constructor's (the channels' root mean squares are read from the factor, so an
        estimator rebuilt from ``est.factor`` fits what ``est`` fits); ``matrices``: as the
        constructor's.
        """
        if not isinstance(factor, _sysid.HankelFactor):
            raise DataError(
                f"factor must be a HankelFactor (from sysid.compress_stream or "
                f"SubspaceEstimator(...).factor), got {type(factor).__name__}"
            )
        m, l = factor.n_inputs, factor.n_outputs
        # a placeholder record that carries only channel counts, names and dt
        rows = max(m, l, 1)  # time-first: at least as many samples as channels
        data = IOData(
            u=np.zeros((rows, m)),
            y=np.zeros((rows, l)),
            dt=dt,
            input_names=input_names,
            output_names=output_names,
        )
        self = cls.__new__(cls)
        self._init_state(data, factor, method=_method(method),
                         matrices="shift" if matrices is None else as_option(matrices,
                                                                             "matrices"),
                         compressor="given", scale=scale, from_factor=True)
        return self

    def with_matrices(self, matrices: str) -> SubspaceEstimator:
        """This estimator taking ``A, B, C, D`` as ``matrices`` says (the constructor's
        option), sharing its record, factor, channel scaling and weighted SVDs (none depends
        on ``matrices``): another way to fit, with no pass over the data.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> u = np.random.default_rng(0).standard_normal((300, 1))
        >>> y = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]]).simulate(u)
        >>> est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=4)
        >>> est.with_matrices("states").fit(1).info["settings"]["matrices"], est.matrices
        ('states', 'shift')
        """
        new = type(self).__new__(type(self))
        new._init_state(self.data, self.factor, method=self.method,
                        matrices=as_option(matrices, "matrices"), compressor=self.compressor,
                        scale=self.scale, from_factor=self._from_factor,
                        horizon_note=self._horizon_note,
                        horizon_selection=self.horizon_selection, shared=self)
        return new

    def _init_state(self, data: IOData, factor: Any, *, method: str, matrices: str,
                    compressor: str, scale: bool | None, from_factor: bool,
                    horizon_note: str = "", horizon_selection: dict[str, Any] | None = None,
                    shared: SubspaceEstimator | None = None) -> None:
        """Every attribute of an estimator, set here alone (the constructor,
        :meth:`from_factor` and :meth:`with_matrices` all come through it, so that new state
        is added once). ``method``, ``matrices``: checked by the caller. ``shared``: an
        estimator on the same factor whose channel scaling, weighted SVDs and caches this
        one shares (none depends on ``matrices``: filled once for both); without it they
        are computed (``scale``) or start empty."""
        self.data, self.factor = data, factor
        self.past, self.future = factor.past, factor.future
        self.method, self.matrices, self.compressor = method, matrices, compressor
        #: built from a factor alone: no record (fits with x0=True are not available)
        self._from_factor = from_factor
        #: said in an order error: experiments the default horizon left out
        self._horizon_note = horizon_note
        #: how the default horizons were chosen for a time series (None otherwise)
        self.horizon_selection = horizon_selection
        if shared is None:
            self._set_scaling(scale)
            self._svd: dict[Any, Any] = {}
            self._pe_cache: dict[int | str, int] = {}
            self._feedback_p: float | None = None
            self._feedback_share = 0.0
            self._feedback_new = 0.0
            self._feedback_warned = False
        else:
            self.scale, self._su, self._sy = shared.scale, shared._su, shared._sy
            self.scaled_factor = shared.scaled_factor
            self._svd, self._pe_cache = shared._svd, shared._pe_cache  # filled for both
            self._feedback_p, self._feedback_warned = shared._feedback_p, shared._feedback_warned
            self._feedback_share = shared._feedback_share
            self._feedback_new = shared._feedback_new

    def _set_scaling(self, scale: bool | None) -> None:
        """The channel scaling of the fits (:mod:`sysid.subspace.scaling`): the record's
        factor with every channel at unit root mean square, :attr:`scaled_factor`."""
        self.scale = check_scale(scale)
        if self.scale:
            su, sy = self.factor.channel_rms()
            self._su, self._sy = np.asarray(su, float), np.asarray(sy, float)
            #: the factor the fits use: :attr:`factor` with the channel scaling applied
            self.scaled_factor = self.factor.scaled(su, sy)
        else:
            self._su = np.ones(self.factor.n_inputs)
            self._sy = np.ones(self.factor.n_outputs)
            self.scaled_factor = self.factor

    @property
    def channel_scales(self) -> tuple[np.ndarray, np.ndarray]:
        """The inputs' and outputs' scales of the fits (their root mean squares with
        ``scale=True``, ones without)."""
        return self._su, self._sy

    def _subspace(self, method: str | None) -> Any:
        key = self.method if method is None else _method(method)
        if key not in self._svd:
            if key in CLOSED_LOOP:
                self._svd[key] = _sysid.ClosedLoopSubspace(self.scaled_factor, key)
            else:
                self._svd[key] = _sysid.Subspace(self.scaled_factor, key)
        return self._svd[key]

    def feedback_pvalue(self) -> float:
        """Combined p-value of the feedback test (:func:`sysid.check_feedback`) computed on
        this estimator's factor (no pass over the data); 1.0 without inputs. A past window
        shorter than the test's default lags cannot tell an input with a long memory (a
        sweep, a narrow band) from one fed back: past outputs, which carry the input's older
        history, predict it (a robot arm's sweep at ``horizon=8``: p = 2e-42, at the 17
        default lags 0.21). The factor's rows are not centred either: on a record with an
        offset left in, past outputs predict the input's constant, and the test found
        "feedback" in open-loop data (p = 6e-12 where the mean-removed record gives 0.72,
        ``benches/results/warning_audit.md``). A detection is therefore checked on the record
        by :func:`sysid.check_feedback`, which removes the means, at the larger of its default
        lags and the past window (one more pass), and the larger p-value kept."""
        if self._feedback_p is None:
            p, share, new = 1.0, 0.0, 0.0
            if self.factor.n_inputs:
                _, pv, shares, _, _, news = feedback_statistics(self.scaled_factor)
                p = float(min(1.0, len(pv) * float(np.min(pv))))
                share, new = float(np.max(shares)), float(np.max(news))
                if p < FEEDBACK_WARNING_LEVEL and isinstance(self.data, IOData):
                    p_default, share_default, new_default = self._default_lags_test()
                    if p_default > p:
                        p, share, new = p_default, share_default, new_default
            self._feedback_p, self._feedback_share, self._feedback_new = p, share, new
        return self._feedback_p

    def _default_lags_test(self) -> tuple[float, float, float]:
        """:func:`sysid.check_feedback`'s combined p-value and largest explained shares (of
        the input's variance, and of the part its own past does not predict) on the
        mean-removed record, at the larger of its default lags and this estimator's past
        window (zeros when the record is too short for them: the window's test stands)."""
        data = self.data
        lags = max(default_lags(data), self.past)
        try:
            fb = check_feedback(data, lags)
        except SysidError:  # too short for those lags: the window's test stands
            return 0.0, 0.0, 0.0
        pv = np.asarray(fb.p_values, float)
        return (float(min(1.0, pv.size * float(np.min(pv)))), fb.explained_share,
                fb.explained_new_share)

    def _quiet_fit(self, *args: Any, **kwargs: Any) -> StateSpaceModel:
        """:meth:`fit` with every warning suppressed, for the package's own checks (order
        choice, feedthrough test): the once-per-estimator feedback warning is left for the
        user's own fit (an internal fit used to consume it, so ``n4sid(data)`` never warned)."""
        said = self._feedback_warned
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return self.fit(*args, **kwargs)
        finally:
            self._feedback_warned = said

    def _warn_feedback(self, key: str) -> None:
        if key in CLOSED_LOOP or self._feedback_warned:
            return
        p = self.feedback_pvalue()
        self._feedback_warned = True
        if p < FEEDBACK_WARNING_LEVEL:
            warnings.warn(
                f"the record shows feedback (past outputs predict the input, {pvalue(p)}; beyond "
                f"its own past they explain {100 * self._feedback_share:.2g} % of its variance, "
                f"{100 * self._feedback_new:.2g} % of the part its own past does not predict, "
                f"and the bias of open-loop fits grows with them): "
                f"the open-loop method {key!r} is biased under feedback; use method='pbsid' "
                "or 'ssarx' (see sysid.check_feedback). A nonlinear plant in open loop can "
                "show the same (its distortions, functions of past inputs, stay in a linear "
                "model's outputs): sysid.advice(data) weighs both",
                FeedbackWarning,
                stacklevel=user_stacklevel(),
            )

    @property
    def singular_values(self) -> np.ndarray:
        """Singular values of the weighted projection for :attr:`method` (order choice)."""
        return self._subspace(None).singular_values

    def singular_values_for(self, method: str) -> np.ndarray:
        """Singular values under another weighting, reusing the compression."""
        return self._subspace(method).singular_values

    @property
    def auto_order(self) -> int:
        """Order at the largest gap of the log singular values (SLICOT's rule).

        A fast first look; on real records it often stops at 1-2 where the data support
        more, so ``fit(order="auto")`` uses :meth:`order_selection` instead."""
        return self._subspace(None).auto_order()

    def order_selection(self, method: str | None = None,
                        feedthrough: bool = FEEDTHROUGH_DEFAULT,
                        orders: Sequence[int] | None = None) -> dict[str, Any]:
        """The order ``fit(order="auto")`` takes, with the table and the reason.

        With the data at hand: the order whose models, fitted on part of the record, best
        simulate the part held out (five contiguous blocks, or the experiments;
        :func:`sysid.validation.crossval.cross_validated_order`; for a time series, best
        predict it one step ahead with their Kalman predictor), the smallest within 0.5 fit
        points of the best, among the orders whose model on the whole record is stable unless
        an unstable one beats the best stable order on every block
        (:func:`sysid.validation.stable_orders.stable_first`). Otherwise (an estimator built from
        a factor, a record too short to split): the largest gap of the log singular values
        (:attr:`auto_order`). The result is recorded in
        ``model.info["order_selection"]``. ``orders``: only these are tried (default: every
        order up to :attr:`max_order`, at most 20).
        """
        from .order_choice import order_selection

        return order_selection(self, self.method if method is None else _method(method),
                               bool(feedthrough), _orders(orders, self.max_order))

    def feedthrough_selection(self, method: str | None = None, order: Order = "auto"
                              ) -> tuple[bool, dict[str, Any]]:
        """Whether ``fit(feedthrough="auto")`` estimates ``D``: the held-out simulation fits
        (as :meth:`order_selection`) with and without it; ``D`` only when it gains more than
        0.5 fit points (no feedthrough, MATLAB's default, otherwise). Closed-loop methods and
        data that cannot be split: no ``D``. The one rule of every estimator
        (:func:`sysid.subspace.feedthrough.choose_feedthrough`)."""
        return choose_feedthrough(self, order, method=method)

    @property
    def max_order(self) -> int:
        """Largest order the horizon allows."""
        return self._subspace(None).max_order

    def fit(
        self,
        order: Order = "auto",
        *,
        method: str | None = None,
        feedthrough: bool | str | None = None,
        kalman: bool = True,
        stable: bool = False,
        x0: bool = False,
        uncertainty: str | None = None,
        n_boot: int = 100,
        rng: Any = None,
        regularization: str = "none",
    ) -> StateSpaceModel:
        """Estimate ``A, B, C, D, K`` and the noise covariances for one order.

        Parameters
        ----------
        order : int, "auto" or sequence of int
            Model order; ``"auto"``: chosen by simulation error cross-validated inside the
            record (:meth:`order_selection`; table and reason in
            ``info["order_selection"]``); a sequence (``range(1, 11)``, MATLAB's
            ``n4sid(data, 1:10)``): chosen the same way among those orders.
        method : str, optional
            Weighting for this fit (default: the estimator's).
        feedthrough : bool or "auto", optional
            Estimate ``D``. Default: ``D = 0`` at a given order (MATLAB's default, the same
            for every sysid state-space estimator), and with ``order="auto"`` chosen with the
            order, as ``"auto"`` (:mod:`sysid.subspace.feedthrough`). ``True`` estimates
            ``D`` (with ``"pbsid"``/``"ssarx"`` consistent only when the controller has no
            direct feedthrough); ``False``: ``D = 0``; ``"auto"``: decided by held-out
            simulation fit (:meth:`feedthrough_selection`, recorded in
            ``info["feedthrough_selection"]``).
        kalman : bool
            Estimate the noise model (``K`` from the Riccati equation of the residuals'
            covariances, innovation covariance; solved again in a scaled basis with Newton's
            refinement where the doubling fails, a shift of the covariances that had to be
            kept in ``info["kalman_regularization"]``, the equation's residual at ``K`` in
            ``info["kalman_residual"]``; where the core's solvers refuse, SciPy's Schur
            solver, ``info["kalman_solver"]``, :mod:`sysid.subspace.kalman`).
        stable : bool
            Enforce a stable ``A`` (Maciejowski's zero-padded shift); recorded in ``info``.
        x0 : bool
            Also estimate ``B, D`` jointly with the initial state by least squares on the
            simulation error of the data (one more pass over the record; SLICOT's IB01CD).
            Several experiments: one ``B, D`` for all and an initial state per experiment,
            in ``info["x0_experiments"]`` (the model's ``x0`` is then None).
        uncertainty : {None, "bootstrap"}
            ``"bootstrap"``: attach the parameter uncertainty from a residual bootstrap of
            ``n_boot`` records (see :mod:`sysid.subspace.bootstrap`), so that
            ``poles(std=True)``, ``freqresp(w, std=True)`` and Bode bands work.
        n_boot : int
            Bootstrap records (``uncertainty="bootstrap"``).
        rng : seed or numpy Generator, optional
            Random numbers of the bootstrap.
        regularization : {"none", "ridge", "tc"}
            Closed-loop methods only: regularisation of their VARX.

        Returns
        -------
        StateSpaceModel
        """
        key = self.method if method is None else _method(method)
        ft_selection = None
        feedthrough = default_feedthrough(feedthrough, order)
        if check_feedthrough(feedthrough) == "auto":
            feedthrough, ft_selection = self.feedthrough_selection(key, order)
        orders = _orders(order)
        if key in CLOSED_LOOP:
            from .closed_loop import closed_loop_fit

            if orders is not None:
                raise DataError(f"a sequence of orders is for the open-loop methods; with "
                                f"method={key!r} pass order='auto' or one order")

            if x0 or stable or uncertainty is not None:
                raise DataError(f"x0, stable and uncertainty are not available with "
                                f"method={key!r} (an open-loop re-fit or simulation would "
                                "ignore the feedback); refine with sysid.pem for both")

            cl = closed_loop_fit(self, key, order, feedthrough=feedthrough, kalman=kalman,
                                 regularization=regularization)
            if ft_selection is not None:
                cl.info["feedthrough_selection"] = ft_selection
            return cl
        sub = self._subspace(method)
        self._warn_feedback(key)
        if isinstance(order, str) or orders is not None:
            if isinstance(order, str) and order != "auto":
                raise DataError(f"order must be an integer, a sequence of integers or 'auto', "
                                f"got {order!r}")
            if self.factor.n_inputs == 0 and not self._from_factor:
                refuse_white_noise(self.data)
            selection = self.order_selection(method=key, feedthrough=bool(feedthrough),
                                             orders=orders)
            n = selection["order"]
        else:
            selection = None
            n = as_int(order, "order", 1)
        for name, flag in (
            ("feedthrough", feedthrough),
            ("kalman", kalman),
            ("stable", stable),
            ("x0", x0),
        ):
            if not isinstance(flag, (bool, np.bool_)):
                raise DataError(f"{name} must be True or False, got {flag!r}")
        try:
            res = sub.fit(n, bool(feedthrough), bool(kalman), bool(stable), self.matrices)
        except OrderError as e:
            if not self._horizon_note:
                raise
            raise OrderError(f"{e}{self._horizon_note}") from None
        except RiccatiError:  # SciPy's Schur solver may still find the stabilising gain
            res = schur_gain(sub.fit(n, bool(feedthrough), False, bool(stable), self.matrices))
            if res is None:
                raise
        if self.factor.n_inputs:
            # warn (ExcitationWarning) when the input cannot support order n
            warn_excitation(self._excitation_order(2 * n), n, stacklevel=user_stacklevel())
        x0_est = None
        B, D = res["B"], res["D"]
        x0_all = None
        if x0:
            if self._from_factor:
                raise DataError("x0=True needs the data; this estimator was built from a factor")
            exps = scaled_experiments(self.data, self._su, self._sy)
            B, D, x0_all = _sysid.estimate_bd_x0_records(
                res["A"], res["C"], [u for u, _ in exps], [y for _, y in exps],
                bool(feedthrough))
            x0_all = [np.asarray(v, float) for v in x0_all]
            # one initial state is the model's; several (one per experiment) are reported
            x0_est = x0_all[0] if len(x0_all) == 1 else None
        info = {
            "method": method and _method(method) or self.method,
            "order": n,
            "past": self.past,
            "future": self.future,
            "singular_values": sub.singular_values,
            "n_columns": self.factor.n_columns,
            "compression": compression_info(self.factor, self.compressor),
            "stable_enforced": bool(stable),
            # the relative shift of Q and R whose Riccati equation K solves (0: the
            # covariances as estimated; the core's riccati::kalman_gain)
            "kalman_regularization": float(res.get("kalman_regularization", 0.0)),
            # its relative residual at K: at most 1e-9, up to 1e-6 where the solvers stall
            # on modes near the unit circle
            "kalman_residual": float(res.get("kalman_residual", 0.0)),
            "kalman_solver": res.get("kalman_solver", "doubling and Newton (sysid core)")
            if kalman else None,
            "Q": res["Q"],
            "R": res["R"],
            "S": res["S"],
            "settings": {"method": method and _method(method) or self.method, "order": n,
                         "order_rule": "auto" if isinstance(order, str) else "given",
                         "past": self.past, "future": self.future,
                         "feedthrough": bool(feedthrough), "kalman": bool(kalman),
                         "stable": bool(stable), "x0": bool(x0), "scale": bool(self.scale),
                         "matrices": self.matrices},
            "preprocessing": _preprocessing(self.data, self._from_factor),
        }
        if x0_all is not None and len(x0_all) > 1:
            info["x0_experiments"] = [v.tolist() for v in x0_all]
        if selection is not None:
            info["order_selection"] = selection
        if self.horizon_selection is not None:
            info["horizon_selection"] = dict(self.horizon_selection)
        if ft_selection is not None:
            info["feedthrough_selection"] = ft_selection
        model = StateSpaceModel(
            res["A"],
            B,
            res["C"],
            D,
            res["K"],
            dt=self.data.dt,
            noise_cov=res["noise_cov"],
            x0=x0_est,
            input_names=self.data.input_names,
            output_names=self.data.output_names,
            info=info,
        )
        model = in_record_units(model, self._su, self._sy)
        if uncertainty is not None:
            if uncertainty != "bootstrap":
                raise DataError(f"uncertainty must be None or 'bootstrap', got {uncertainty!r}")
            from .bootstrap import bootstrap_uncertainty

            def refit(rec: IOData) -> StateSpaceModel:
                # the fast compressor: exact up to rounding (it falls back to QR itself when
                # its Gram matrix is ill-conditioned), 2-3x faster on short records
                est = SubspaceEstimator(rec, past=self.past, future=self.future,
                                        method=self.method, compressor="correlation",
                                        scale=self.scale, matrices=self.matrices)
                return est.fit(n, method=method, feedthrough=feedthrough, stable=stable, x0=x0)

            model.uncertainty = bootstrap_uncertainty(self, model, refit, n_boot, rng)
            model.info["uncertainty"] = {"method": "bootstrap",
                                         "n_boot": model.uncertainty.n_boot,  # type: ignore
                                         "n_failed": model.uncertainty.n_failed}  # type: ignore
        warn_unstable(model, info["method"])
        return model

    def _excitation_order(self, needed: int) -> int:
        """Persistent-excitation order of the input, up to ``needed``: the count of excited
        lines of its spectrum (:mod:`sysid.data.excitation`, once per estimator), as
        :func:`sysid.persistent_excitation_order` gives it: the warning and the user's check
        agree. The spectrum is read only when the input is not plainly rich: first the rank
        of the input rows of the factor, no pass over the data (the largest ``d <= min(needed,
        past + future)`` for which the input's block Hankel matrix with ``d`` block rows has
        the eigenvalues of its Gram matrix within ``FLAT_LAGS`` of the largest). A rank test
        at a rounding tolerance counts sensor noise 40 dB below a few tones as excitation (a
        shaker's three-tone drive read 22, its spectrum 6). From a factor alone, the rank at
        ``RANK_LAGS`` decides."""
        if needed not in self._pe_cache:
            # in the Rust core on the calling thread: one Cholesky of G - tol top I answers
            # every d (the first non-positive pivot), no threaded LAPACK call
            tol = RANK_LAGS if self._from_factor else FLAT_LAGS
            got = int(_sysid.excitation_order(self.scaled_factor, needed, tol))
            if got < needed and not self._from_factor:
                if "spectrum" not in self._pe_cache:
                    us = [np.ascontiguousarray(u) for u, _ in self.data.experiments]
                    self._pe_cache["spectrum"] = spectral_excitation_order(us)
                got = min(needed, self._pe_cache["spectrum"])
            self._pe_cache[needed] = got
        return self._pe_cache[needed]

    def __repr__(self) -> str:
        return (
            f"SubspaceEstimator(method={self.method!r}, past={self.past}, future={self.future}, "
            f"{self.factor.n_columns} Hankel columns, {self.data.n_experiments} experiment(s))"
        )


def _orders(order: Any, top: int | None = None) -> list[int] | None:
    """A sequence of orders as a sorted list of distinct positive integers (None for one
    order or ``"auto"``), checked against the largest order ``top`` the horizon allows."""
    if order is None or isinstance(order, str) or np.ndim(order) == 0:
        return None
    orders = as_orders(order)
    if top is not None and orders[0] > top:
        raise OrderError(f"every order in {orders} is too large: the horizon allows at most "
                         f"{top} states; choose orders <= {top} or a longer horizon")
    return [o for o in orders if top is None or o <= top]
