"""The parameter covariance of a simulation-error fit whose errors are coloured.

The Gauss-Newton covariance ``sigma^2 (J^T W J)^-1`` of :func:`sysid.pem` holds when the
errors it minimises are white. With ``focus="simulation"`` they are the output disturbance
itself, coloured on nearly every real record (and whenever the plant has a noise model):
then the covariance of the estimate is the sandwich (Ljung, *System Identification*, 1999,
eq. 9.42)

    P = (J^T W J)^-1 (J^T W Sigma W J) (J^T W J)^-1,

``Sigma`` the errors' covariance over time. It is estimated here from the fit's own errors:
per output, the spectrum of an autoregressive model of them (order by AIC; white errors get
order 0 and keep the Gauss-Newton covariance), applied to the Jacobian in the frequency
domain (zero-padded FFTs: no ``N x N`` matrix). ``J`` comes from the
model's own uncertainty object (central differences along its identifiable directions, the
coordinates in which the Gauss-Newton covariance is the identity), so only the correction
``Delta`` of ``P_z = I + Delta`` is formed: the directions ``J`` does not see (the initial
state's, held fixed here) keep their Gauss-Newton value.

On a second-order plant with a coloured disturbance (200 Monte Carlo runs) the Gauss-Newton
standard deviation of the static gain was a third of the sample one (0.073 against 0.215);
this covariance gives 0.188, its 95 % intervals covering 89.5 % (``tests/test_pem_coloured.py``).

The same holds for every output-error fit: :func:`sysid.oe` and the discrete
:func:`sysid.tfest` (which is ``oe``) carry it too (:func:`sandwich_covariance`, one block
per output, as they search one output at a time; ``info["covariance"]`` says which). On a
first-order OE plant with an AR(1) disturbance (400 runs) the Gauss-Newton std of the static
gain was 0.044 against a sample 0.140 (intervals covering 43 %); the sandwich gives 0.133,
covering 93.5 % (``tests/test_oe_coloured.py``). ``bj`` and ``armax`` model the disturbance:
their errors are the whitened innovations, and their Gauss-Newton covariance stands.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..models.paramtable import Z95, ParameterTable
from ..models.uncertainty import ParameterUncertainty, UncertaintyWarning

__all__ = ["DeferredSandwich", "DeferredTable", "coloured_error_covariance", "defer_sandwich",
           "defer_state_space", "free_response", "gauss_newton", "sandwich_covariance",
           "with_fitted_state"]

#: the Jacobian over the record holds samples x outputs x directions numbers: beyond this the
#: correction is not formed (``info["pem"]["covariance"]`` says so)
MAX_ENTRIES = 10_000_000


def _ar_fit(series: Sequence[np.ndarray], max_order: int,
            penalty: float = 2.0) -> tuple[np.ndarray, float, int]:
    """An autoregressive model of one process seen on several independent ``series``
    (their autocorrelations pooled, each series about its own mean): Yule-Walker by
    Levinson-Durbin, the order by AIC (``N log v + penalty * order``; ``penalty=log N``
    is BIC) up to ``max_order`` and a tenth of the samples (and below the shortest series).
    Returns its coefficients, its variance and its order."""
    es = [np.asarray(e, float) - np.mean(e) for e in series]
    N = sum(e.size for e in es)
    top = int(min(max_order, N // 10, min(e.size for e in es) - 1))
    r = np.zeros(max(top, 0) + 1)
    for e in es:
        E = np.fft.rfft(e, 1 << int(np.ceil(np.log2(2 * e.size))))
        r += np.fft.irfft(E * np.conj(E))[:top + 1]
    r /= N
    if r[0] <= 0:
        return np.zeros(0), 0.0, 0
    # Levinson-Durbin: the prediction-error variance of every order, AIC over them
    a, v = np.zeros(0), float(r[0])
    best = (N * np.log(v), 0, a.copy(), v)
    for k in range(1, top + 1):
        kap = (r[k] - (a @ r[k - 1:0:-1] if a.size else 0.0)) / v
        a = np.r_[a - kap * a[::-1], kap]
        v *= 1.0 - kap * kap
        if v <= 0:
            break
        aic = N * np.log(v) + penalty * k
        if aic < best[0]:
            best = (aic, k, a.copy(), v)
    _, p, a, v = best
    return a, v, p


def error_spectrum(e: Any, nfft: int, max_order: int = 30) -> tuple[np.ndarray, int]:
    """The spectral density of a series ``e`` on the ``rfft`` grid of ``nfft`` points, from an
    autoregressive model of it (Yule-Walker by Levinson-Durbin, the order by AIC up to
    ``max_order`` and a tenth of the record): a slowly decaying autocorrelation (errors
    through a pole near 1) is caught in full, as a lag window cut short would not. Returns
    the density (its mean over the full grid is the AR model's variance) and the order.
    ``e`` may be a list of series, independent records of one process (the model is fitted
    to their pooled autocorrelations).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> from sysid.pem.sandwich import error_spectrum
    >>> e = np.random.default_rng(0).standard_normal(4000)
    >>> S, p = error_spectrum(e, 8192)
    >>> p, bool(np.allclose(S, 1.0, atol=0.1))      # white: flat at the variance
    (0, True)
    >>> S, p = error_spectrum(lfilter([1.0], [1.0, -0.9], e), 8192)
    >>> p >= 1, bool(abs(S[0] / 100.0 - 1.0) < 0.3)  # 1 / (1 - 0.9)^2 at zero frequency
    (True, True)
    """
    series = list(e) if isinstance(e, (list, tuple)) else [e]
    a, v, p = _ar_fit(series, max_order)
    if v <= 0:
        return np.zeros(nfft // 2 + 1), 0
    A = np.fft.rfft(np.r_[1.0, -a], nfft)
    return v / np.abs(A) ** 2, p


def free_response(A: np.ndarray, C: np.ndarray, N: int) -> np.ndarray:
    """``O[t] = C A^t``, ``(N, l, n)``: the outputs of ``x(t+1) = A x(t), y = C x`` from each
    unit initial state, by doubling: ``O[k:2k] = O[0:k] A^k`` (one matrix product per
    doubling, ``A^k`` squared; ``N l n^2`` flops in all, where the run per state of the
    Rust core's recursion took 2.2 ms a state on 8 000 samples of a 21-state model: 46 ms a
    model, the largest cost of a sandwich covariance). An unstable ``A`` whose powers
    overflow gives ``inf`` or ``nan`` there, caught by the callers as not finite. A stable
    response is zero once a whole doubling block has decayed far below round-off of its
    largest value (``DECAYED``): run on, it would sink into subnormal numbers, whose
    arithmetic is some 40 times slower.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.pem.sandwich import free_response
    >>> free_response(np.array([[0.5]]), np.array([[2.0]]), 3)[:, 0, 0].tolist()
    [2.0, 1.0, 0.5]
    """
    A, C = np.ascontiguousarray(A, float), np.ascontiguousarray(C, float)
    n, l = A.shape[0], C.shape[0]
    out = np.zeros((N, l, n))
    if n == 0 or N == 0:
        return out
    out[0] = C
    power, k = A.copy(), 1  # power = A^k
    top = float(np.max(np.abs(C))) if C.size else 0.0
    with np.errstate(all="ignore"):
        while k < N:
            m = min(k, N - k)
            block = (out[:m].reshape(m * l, n) @ power).reshape(m, l, n)
            out[k:k + m] = block
            k += m
            largest = float(np.max(np.abs(block))) if block.size else 0.0
            if not np.isfinite(largest):  # overflowed: not finite from here on
                out[k:] = np.inf
                break
            top = max(top, largest)
            if largest <= DECAYED * top:  # decayed: zero after (already)
                break
            if k < N:
                power = power @ power
    return out


#: a free response this far below its largest value is zero (:func:`free_response`)
DECAYED = 1e-25


def with_fitted_state(y_sim: np.ndarray, y: np.ndarray, O: np.ndarray,
                      weights: Any = None) -> np.ndarray:
    """``y_sim + O x0`` with ``x0`` fitted to ``y`` by least squares (``O`` from
    :func:`free_response`; ``weights`` the criterion's, a vector per output or a matrix
    applied to the errors): the simulation of a fit that estimated its initial state,
    as a function of the model alone. Its Jacobian is the one of the model's parameters
    with the initial state profiled out, so the sandwich formed on it holds for the
    model's parameters whatever the (nuisance) initial state's estimate."""
    y_sim, y = np.asarray(y_sim, float), np.asarray(y, float)
    N, l, n = O.shape
    if n == 0:
        return y_sim
    # the samples after the free response has decayed to zero do not move x0: left out
    moving = np.flatnonzero(np.any(O != 0.0, axis=(1, 2)))
    k = int(moving[-1]) + 1 if moving.size else 0
    T = _weight_matrix(weights, l)
    M = np.einsum("kj,tjn->tkn", T, O[:k]).reshape(k * l, n)
    r = ((y[:k] - y_sim[:k]) @ T.T).ravel()
    with np.errstate(all="ignore"):
        x0 = np.linalg.lstsq(M, r, rcond=None)[0] if np.all(np.isfinite(M)) else \
            np.full(n, np.nan)
    out = np.array(y_sim, float)
    out[:k] += O[:k] @ x0
    return out


def _weight_matrix(weights: Any, l: int) -> np.ndarray:
    """The criterion's weighting as a matrix ``T`` applied to the errors (``e -> T e``):
    ``None`` the identity, a vector per output its diagonal, a matrix itself."""
    if weights is None:
        return np.eye(l)
    w = np.asarray(weights, float)
    return np.diag(w) if w.ndim == 1 else w


def coloured_error_covariance(model: Any, records: Sequence[tuple[np.ndarray, np.ndarray]],
                              weights: Any, x0s: Sequence[Any] | None = None
                              ) -> tuple[ParameterUncertainty | None, str]:
    """The sandwich covariance of a state-space simulation-error fit of ``model`` (its
    Gauss-Newton :class:`ParameterUncertainty`) on the records ``(u, y)`` whose errors
    weighed ``weights`` (per output, or a matrix applied to them) in its criterion; and a
    sentence for ``info["pem"]``. ``None`` when the correction is not formed (the records
    too long, the errors not finite). ``x0s``: per record, the initial state the simulation
    starts from, or ``None`` where the fit estimated it (fitted again for every model,
    :func:`with_fitted_state`); default the model's ``x0`` (zero without one).

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(0)
    >>> plant = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(400)
    >>> v = lfilter([1.0], [1.0, -0.9], 0.3 * rng.standard_normal(400))
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     m = sysid.ssest(sysid.IOData(u=u, y=plant.simulate(u)[:, 0] + v), 1,
    ...                     focus="simulation")
    >>> s = m.dcgain(std=True)[1]  # the first use forms it
    >>> m.info["pem"]["covariance"].startswith("sandwich for coloured simulation errors")
    True
    """
    records = [(np.asarray(u, float), np.asarray(y, float)) for u, y in records]
    if x0s is None:
        x0 = getattr(model, "x0", None)
        x0s = [np.zeros(model.nstates) if x0 is None else np.asarray(x0, float)] * len(records)

    # the free responses of the last (A, C): a perturbed B or D leaves them as they are
    last: list[Any] = [None, None]

    def sim(m: Any) -> list[np.ndarray]:
        key = (np.asarray(m.A, float).tobytes(), np.asarray(m.C, float).tobytes())
        if last[0] != key:
            last[:] = [key, [None if x0 is not None else free_response(m.A, m.C, u.shape[0])
                             for (u, _), x0 in zip(records, x0s)]]
        out = []
        for (u, y), x0, O in zip(records, x0s, last[1]):
            if x0 is not None:
                out.append(np.asarray(m.simulate(u, x0=x0), float))
            else:
                out.append(with_fitted_state(m.simulate(u), y, O, weights))
        return out

    return sandwich_covariance(model.uncertainty, sim, [y for _, y in records], weights)


def sandwich_covariance(unc: ParameterUncertainty, sim: Callable[[Any], Any],
                        y: Any, weights: Any = None,
                        blocks: Sequence[tuple[Sequence[int], Sequence[int]]] | None = None,
                        ) -> tuple[ParameterUncertainty | None, str]:
    """The sandwich covariance of any simulation-error fit: ``unc`` its Gauss-Newton
    uncertainty, ``y`` the record's outputs ``(N, l)`` or a list of independent records',
    ``sim(model)`` the simulated outputs (an array, or a list of one per record) exactly as
    the fit's errors ``y - sim(model)`` were formed (its initial conditions included; an
    estimated initial state fitted again, :func:`with_fitted_state`), ``weights`` the
    outputs' weights in the criterion (default 1; a matrix ``T`` weighs the errors ``T e``,
    its rows' sum of squares the criterion). The records' terms of the "meat" add (they are
    independent); one autoregressive model per output serves them all (their
    autocorrelations pooled). ``blocks`` lists ``(parameters,
    outputs)`` index pairs fitted separately (a polynomial or transfer-function model's one
    search per output, each with its own noise variance): each block's correction is formed
    on its own outputs' errors, and between blocks (zero for separate searches) and outside
    them the covariance stays the Gauss-Newton one. Default: one block, every parameter and
    output. Returns the uncertainty (``None`` when no block's
    correction is formed) and the sentence saying which covariance it is.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy.signal import lfilter
    >>> from sysid.pem.sandwich import gauss_newton, sandwich_covariance
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(1000)
    >>> v = lfilter([1.0], [1.0, -0.9], 0.1 * rng.standard_normal(1000))
    >>> data = sysid.IOData(u, lfilter([0.0, 0.5], [1.0, -0.8], u) + v, 1.0)
    >>> m = sysid.oe(data, 1, 1, 1)
    >>> gn = gauss_newton(m.uncertainty)           # before oe's own sandwich is formed
    >>> unc, note = sandwich_covariance(gn, lambda g: g.simulate(u), data.y)
    >>> note.startswith("sandwich"), bool(np.all(unc.std > 1.2 * gn.std))
    (True, True)
    >>> bool(np.allclose(unc.covariance, m.uncertainty.covariance))   # what oe carries
    True
    """
    several = isinstance(y, (list, tuple))
    ys = [np.asarray(r, float) for r in (y if several else [y])]
    ys = [r[:, None] if r.ndim == 1 else r for r in ys]
    lens = [r.shape[0] for r in ys]
    l = ys[0].shape[1]

    def records(m: Any) -> np.ndarray:  # every record's simulation, stacked
        out = sim(m)
        parts = list(out) if several else [out]
        return np.concatenate([np.asarray(p, float).reshape(n, -1) for p, n in zip(parts, lens)])

    stacked = np.concatenate(ys)
    if blocks is None:
        return _block(unc, records, stacked, lens, weights)[:2]
    w_out = np.ones(l) if weights is None else np.asarray(weights, float)
    P = np.array(unc.covariance, float)
    orders: list[int] = []
    ratios: list[float] = []
    notes: list[str] = []
    formed = False
    for params, outs in blocks:
        ix, ox = np.asarray(params, int), np.asarray(outs, int)
        sub = _sub_uncertainty(unc, ix)

        def sim_block(m: Any, ox: np.ndarray = ox) -> np.ndarray:
            return records(m)[:, ox]

        got, note, ords, ratio = _block(sub, sim_block, stacked[:, ox], lens, w_out[ox])
        formed |= got is not None
        res = sub if got is None else got
        P[np.ix_(ix, ix)] = res.covariance
        notes.append(note)
        if got is not None:
            orders += ords
            ratios.append(ratio)
    if not formed:
        return None, notes[0]
    out = ParameterUncertainty(unc.theta, P, unc.build, names=unc.names, method=_METHOD,
                               undetermined=unc.undetermined)  # its rank from P
    kept = [n for n in notes if not n.startswith("sandwich")]
    return out, (f"{_NOTE}{_on(lens)} (their autoregressive order "
                 f"{', '.join(map(str, orders))}; the "
                 f"variances {np.mean(ratios):.2g} times the Gauss-Newton ones on average"
                 + ("; gauss-newton for the others: " + "; ".join(kept) if kept else "")
                 + ")")


_METHOD = "gauss-newton with coloured simulation errors (sandwich)"
_NOTE = "sandwich for coloured simulation errors"


def _on(lens: Sequence[int]) -> str:
    return f" on {len(lens)} records" if len(lens) > 1 else ""


def _sub_uncertainty(unc: ParameterUncertainty, ix: np.ndarray) -> ParameterUncertainty:
    """``unc`` on the parameters ``ix`` alone, the others held at the estimate."""
    theta = unc.theta

    def build(t: np.ndarray) -> Any:
        full = theta.copy()
        full[ix] = t
        return unc.build(full)

    return ParameterUncertainty(theta[ix], unc.covariance[np.ix_(ix, ix)], build,
                                names=[unc.names[i] for i in ix], method=unc.method)


def _block(unc: ParameterUncertainty, sim: Callable[[Any], np.ndarray], y: np.ndarray,
           lens: Sequence[int], weights: Any
           ) -> tuple[ParameterUncertainty | None, str, list[int], float]:
    """:func:`sandwich_covariance` of one block: every parameter of ``unc``, every output
    of ``y`` (the records of lengths ``lens`` stacked; one noise variance: the Gauss-Newton
    covariance in the coordinates ``z`` is ``sigma^2`` times the identity, on the directions
    the simulation sees); also the errors' AR orders and the mean variance ratio."""
    w, V = unc._eigen()
    N, l = y.shape
    r = w.size
    if r == 0:
        return None, "gauss-newton: no identifiable direction", [], 1.0
    if N * l * r > MAX_ENTRIES:
        return None, (f"gauss-newton, as for white errors: the coloured-error correction "
                      f"would hold {N * l * r:.2g} numbers (at most {MAX_ENTRIES:.0e})"), [], 1.0
    with np.errstate(all="ignore"), warnings.catch_warnings():
        # a direction whose perturbed models cannot be simulated (an estimate next to an
        # unstable model: a time constant run to its bound) gives an infinite column: the
        # correction then falls back to the Gauss-Newton covariance and its note says why
        # (the Jacobian's own warning would be raised by printing the summary)
        warnings.simplefilter("ignore", UncertaintyWarning)
        value, G = unc.scaled_jacobian(sim)
        e = y - np.asarray(value, float).reshape(N, l)
    if not (np.all(np.isfinite(e)) and np.all(np.isfinite(G))):
        return None, ("gauss-newton, as for white errors: the errors or their Jacobian "
                      "overflow"), [], 1.0
    T = _weight_matrix(weights, l)
    # a Jacobian finite but beyond squaring overflows here: checked below, not warned
    with np.errstate(over="ignore", invalid="ignore"):
        J = np.einsum("kj,tjr->tkr", T, G.reshape(N, l, r))
        E = e @ T.T
        A = np.einsum("tkr,tks->rs", J, J)
        if not np.all(np.isfinite(A)):
            return None, ("gauss-newton, as for white errors: the coloured-error correction "
                          "overflows"), [], 1.0
        ev = np.linalg.eigvalsh(0.5 * (A + A.T))
        # sigma^2 on every direction the simulation sees (an estimated initial state's, fitted
        # again in it, it does not)
        sigma2 = float(np.median(ev[ev > 0.1 * ev.max()])) if ev.max() > 0 else 0.0
        if not sigma2 > 0:
            return None, ("gauss-newton, as for white errors: the fit does not move its "
                          "outputs"), [], 1.0
        delta = np.zeros((r, r))
        orders = []
        cuts = np.concatenate([[0], np.cumsum(lens)]).astype(int)
        for k in range(l):
            a, v, p = _ar_fit([E[s:t, k] for s, t in zip(cuts[:-1], cuts[1:])], 30)
            orders.append(p)
            if p == 0 or v <= 0:  # white: nothing to correct
                continue
            for s, t in zip(cuts[:-1], cuts[1:]):
                nfft = 1 << int(np.ceil(np.log2(2 * (t - s))))
                wts = np.full(nfft // 2 + 1, 2.0)  # the rfft grid's weights on the full one
                wts[0] = 1.0
                wts[-1] = 1.0
                S = v / np.abs(np.fft.rfft(np.r_[1.0, -a], nfft)) ** 2
                # J / sqrt(sigma2) and the spectrum / sigma2: M / sigma2^2 formed in units
                # near one (sigma2 ** 2 of a Python float raised OverflowError past 1e154:
                # a process model's Jacobian along a time constant at its bound)
                F = np.fft.rfft(J[s:t, k, :] / np.sqrt(sigma2), nfft, axis=0)
                dev = (S - np.sum(wts * S) / nfft) * wts / sigma2
                M = ((np.conj(F) * dev[:, None]).T @ F).real / nfft
                delta += 0.5 * (M + M.T)
        Pz = np.eye(r) + delta
    if not np.all(np.isfinite(Pz)):
        return None, ("gauss-newton, as for white errors: the coloured-error correction "
                      "overflows"), [], 1.0
    ev, Q = np.linalg.eigh(0.5 * (Pz + Pz.T))
    Pz = (Q * np.clip(ev, 0.0, None)) @ Q.T
    Gd = V * np.sqrt(w)  # parameters = theta + Gd z, z of unit Gauss-Newton covariance
    P = Gd @ Pz @ Gd.T
    ratio = float(np.trace(Pz) / r)
    out = ParameterUncertainty(unc.theta, 0.5 * (P + P.T), unc.build, names=unc.names,
                               dof=int(np.sum(ev > 1e-12 * max(float(ev.max()), 1e-300))),
                               method=_METHOD, undetermined=unc.undetermined)
    return out, (f"{_NOTE}{_on(lens)} (their autoregressive order "
                 f"{', '.join(map(str, orders))}; the "
                 f"variances {ratio:.2g} times the Gauss-Newton ones on average)"), orders, ratio


class DeferredSandwich(ParameterUncertainty):
    """A fit's Gauss-Newton uncertainty whose covariance becomes the sandwich when first
    used (a standard deviation, a band, a sample, saving): the many fits that never report
    one (``identify``'s held-out fits) do not pay for the Jacobian over the record.
    ``form()`` returns what :func:`sandwich_covariance` does; ``then(note)`` is called with
    its sentence (for the fit's ``info``) once it is formed. :func:`gauss_newton` gives the
    Gauss-Newton uncertainty while it is pending."""

    def __init__(self, base: ParameterUncertainty,
                 form: Callable[[], tuple[ParameterUncertainty | None, str]],
                 then: Callable[[str], None]) -> None:
        self.__dict__.update(base.__dict__)
        self._pending: tuple[Any, ...] | None = (base, form, then)

    def _form(self) -> None:
        pending, self._pending = self._pending, None
        if pending is None:
            return
        _, form, then = pending
        unc, note = form()
        if unc is not None:
            self.__dict__.update(unc.__dict__)
        self.__dict__.pop("_pending", None)
        self.__class__ = ParameterUncertainty  # type: ignore[assignment]  # formed: plain
        then(note)

    def __getattribute__(self, name: str) -> Any:
        if name in ("covariance", "dof", "method", "_eig", "_eigen", "_cache", "__reduce__",
                    "__deepcopy__", "std", "correlation", "summary", "to_pandas", "__repr__"):
            pending = object.__getattribute__(self, "__dict__").get("_pending")
            if pending is not None:
                object.__getattribute__(self, "_form")()
        return object.__getattribute__(self, name)


def through_deferred(unc: Any, fn: Callable[[Any], Any]) -> Any:
    """``unc.through(fn)`` that keeps a :class:`DeferredSandwich` deferred (``through`` reads
    the covariance, which forms it).

    Examples
    --------
    >>> import sysid
    >>> from sysid.pem.sandwich import DeferredSandwich, through_deferred
    >>> base = sysid.ParameterUncertainty([0.5], [[0.01]], lambda t: float(t[0]))
    >>> d = through_deferred(DeferredSandwich(base, lambda: (None, "gn"), print),
    ...                      lambda a: 2 * a)
    >>> d.__dict__["_pending"] is not None, d.build([0.25])
    (True, 0.5)
    """
    pending = unc.__dict__.get("_pending") if hasattr(unc, "__dict__") else None
    if pending is None:
        return unc.through(fn)
    base, form, then = pending

    def formed() -> tuple[ParameterUncertainty | None, str]:
        new, note = form()
        return (None if new is None else new.through(fn)), note

    return DeferredSandwich(base.through(fn), formed, then)


def gauss_newton(unc: Any) -> Any:
    """The Gauss-Newton uncertainty of a :class:`DeferredSandwich` not formed yet, without
    forming it; any other uncertainty itself.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.pem.sandwich import DeferredSandwich, gauss_newton
    >>> base = sysid.ParameterUncertainty([0.5], [[0.01]],
    ...     lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))
    >>> d = DeferredSandwich(base, lambda: (None, "gauss-newton"), print)
    >>> gauss_newton(d) is base
    True
    """
    pending = unc.__dict__.get("_pending") if hasattr(unc, "__dict__") else None
    return pending[0] if pending is not None else unc


class DeferredTable(ParameterTable):
    """A :class:`~sysid.models.paramtable.ParameterTable` whose standard deviations (and
    95 % intervals) are those of a :class:`DeferredSandwich`: reading them forms it, and the
    table becomes a plain one (an estimator that reports a table next to its uncertainty
    keeps the deferral; the discrete :func:`sysid.tfest`). ``rows``: the table's rows of the
    uncertainty's parameters, when it lists others too (a grey box's fixed parameters).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.models.paramtable import ParameterTable
    >>> from sysid.pem.sandwich import DeferredSandwich, DeferredTable
    >>> build = lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]])
    >>> base = sysid.ParameterUncertainty([0.5], [[0.01]], build)
    >>> wider = sysid.ParameterUncertainty([0.5], [[0.04]], build)
    >>> unc = DeferredSandwich(base, lambda: (wider, "sandwich"), lambda note: None)
    >>> t = DeferredTable(ParameterTable(["a"], [0.5], [0.1], [False]), unc)
    >>> t["a"]["std"]                                 # formed when first read
    0.2
    """

    def __init__(self, table: ParameterTable, unc: ParameterUncertainty,
                 limits: tuple[Any, Any] | None = None,
                 rows: Sequence[int] | None = None) -> None:
        self.__dict__.update(table.__dict__)
        self._source: ParameterUncertainty | None = unc
        # the parameters' bounds: the intervals stay cut there (ParameterTable.cut_at_bounds)
        self._limits = limits
        # the table's rows of the uncertainty's parameters (a grey box's table lists its
        # fixed parameters too); default every row, in order
        self._rows = None if rows is None else np.asarray(rows, int)

    def __getattribute__(self, name: str) -> Any:
        if name in ("std", "lower", "upper", "__reduce_ex__", "__reduce__", "__deepcopy__",
                    "__copy__", "__getstate__"):
            d = object.__getattribute__(self, "__dict__")
            if d.get("_source") is not None:
                # formed first: its note's writer may read this table (then turned plain)
                _ = d["_source"].covariance
            src = d.pop("_source", None)
            if src is not None:
                rows = d.pop("_rows", None)
                sd = np.array(d["std"], float)
                sd[slice(None) if rows is None else rows] = np.sqrt(
                    np.clip(np.diag(src.covariance), 0.0, None))
                sd[np.isinf(d["std"])] = np.inf  # the undetermined stay so
                sd[d["fixed"]] = d["std"][d["fixed"]]
                d["std"], d["lower"], d["upper"] = sd, d["value"] - Z95 * sd, d["value"] + Z95 * sd
                limits = d.pop("_limits", None)
                self.__class__ = ParameterTable  # type: ignore[assignment]
                if limits is not None:
                    self.cut_at_bounds(*limits)
        return object.__getattribute__(self, name)


def defer_sandwich(model: Any, sim: Callable[[Any], Any], y: Any,
                   blocks: Sequence[tuple[Sequence[int], Sequence[int]]] | None,
                   limits: tuple[Any, Any] | None = None, key: str = "covariance") -> None:
    """A simulation-error fit's Gauss-Newton uncertainty (and parameter table) becoming the
    sandwich for coloured errors when first used, as :func:`sysid.oe`'s: for the fits of
    continuous-time models (:func:`sysid.tfest`, :func:`sysid.procest`), ``sim(model)``
    simulating the record's input exactly as the search formed its errors ``y - sim``;
    ``blocks`` as in :func:`sandwich_covariance`, ``limits`` the parameters' bounds (the
    table's intervals stay cut there). ``model.info[key]`` (default ``"covariance"``) says
    which covariance the model carries (the Hammerstein-Wiener fits keep their Gauss-Newton
    array under ``"covariance"`` and say it under ``"covariance_method"``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy.signal import lfilter
    >>> from sysid.pem.sandwich import defer_sandwich
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(600)
    >>> y = lfilter([0.0, 0.5], [1.0, -0.8], u)
    >>> y = y + lfilter([1.0], [1.0, -0.9], 0.1 * rng.standard_normal(600))
    >>> m = sysid.arx(sysid.IOData(u, y, 1.0), 1, 1, 1)   # any fit with an uncertainty
    >>> defer_sandwich(m, lambda g: g.simulate(u), y[:, None], [([0, 1], [0])])
    >>> m.info["covariance"].startswith("gauss-newton until first used")
    True
    >>> sd = m.std                                  # the first use forms it
    >>> m.info["covariance"].startswith("sandwich for coloured simulation errors")
    True
    """
    base = model.uncertainty
    info = model.info
    info[key] = ("gauss-newton until first used, then the sandwich for coloured "
                 "simulation errors")

    def form() -> tuple[ParameterUncertainty | None, str]:
        return sandwich_covariance(base, sim, y, blocks=blocks)

    def then(note: str) -> None:
        info[key] = note
    model.uncertainty = DeferredSandwich(base, form, then)
    table = getattr(model, "parameters", None)
    if isinstance(table, ParameterTable):
        model.parameters = DeferredTable(table, model.uncertainty, limits)


def defer_state_space(out: Any, records: Sequence[tuple[np.ndarray, np.ndarray]],
                      weighting: str, scale: np.ndarray, x0s: Sequence[Any]) -> None:
    """A state-space simulation-error fit's (:func:`sysid.pem`'s) uncertainty for coloured
    errors: its Gauss-Newton one becoming :func:`coloured_error_covariance`'s when first
    used, on every record (in its own units) with its initial state (``x0s``: ``None``
    where estimated). ``weighting`` the criterion's: ``"identity"``, ``"output"`` (each
    output by ``1 / scale``), ``"noise"`` (the inverse of the errors' covariance, the
    model's ``noise_cov``). ``info["pem"]["covariance"]`` says which covariance the model
    carries."""
    if weighting == "noise":
        lam = np.atleast_2d(np.asarray(out.noise_cov, float))
        try:
            weights: Any = np.linalg.inv(np.linalg.cholesky(lam))
        except np.linalg.LinAlgError:
            out.info["pem"]["covariance"] = ("gauss-newton, as for white errors (the errors' "
                                             "covariance is singular)")
            return
    else:
        weights = 1.0 / np.asarray(scale, float) if weighting == "output" else None
    info = out.info["pem"]
    info["covariance"] = ("gauss-newton until first used, then the sandwich for coloured "
                          "simulation errors")

    def form() -> tuple[ParameterUncertainty | None, str]:
        out.uncertainty = base  # the Jacobian is the Gauss-Newton uncertainty's
        try:
            return coloured_error_covariance(out, records, weights, x0s)
        finally:
            out.uncertainty = deferred

    def then(note: str) -> None:
        info["covariance"] = note
    base = out.uncertainty
    deferred = DeferredSandwich(base, form, then)
    out.uncertainty = deferred
