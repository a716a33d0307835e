"""Nonlinear ARX / ARMAX models (NARX, NARMAX) and their candidate bases.

For output ``i``: ``y_i(t) = sum_k theta_ik phi_k(x(t)) + e_i(t)`` where ``x(t)`` holds the
lagged outputs ``y_k(t-1..t-na_k)``, inputs ``u_j(t-nk_j..t-nk_j-nb_j+1)`` and, for NARMAX,
residuals ``e_k(t-1..t-ne_k)``; the terms ``phi_k`` are monomials of ``x`` (a
:class:`PolynomialBasis`) or Gaussian radial basis functions plus the linear terms (an
:class:`RBFBasis`). Simulation and prediction loops run in Rust (``sysid-core``,
``narx/simulate.rs``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_2d
from .._measured import as_horizon, as_measured, predict_args
from ..errors import DataError, ShapeError
from ..models.protocol import ModelMixin, no_pole_std
from .customreg import CustomRegressor

__all__ = ["NARXModel", "PolynomialBasis", "RBFBasis", "CustomRegressor"]


class PolynomialBasis:
    """All monomials of the lagged variables up to total degree ``degree``.

    Examples
    --------
    >>> import sysid
    >>> sysid.PolynomialBasis(3)
    PolynomialBasis(degree=3)
    """

    def __init__(self, degree: int = 2) -> None:
        if int(degree) != degree or degree < 1:
            raise DataError(f"degree must be a positive integer, got {degree!r}")
        self.degree = int(degree)

    def rust_args(self) -> tuple[int | None, Any]:
        """``(degree, rbf)`` arguments of the Rust functions."""
        return self.degree, None

    def fitted(self, lags: np.ndarray) -> PolynomialBasis:
        """Nothing to fit: the basis itself."""
        return self

    def to_dict(self) -> dict[str, Any]:
        """For saving."""
        return {"kind": "polynomial", "degree": self.degree}

    def __repr__(self) -> str:
        return f"PolynomialBasis(degree={self.degree})"


class RBFBasis:
    """Gaussian radial basis functions ``exp(-|z - c_k|^2 / (2 w_k^2))`` plus the constant and
    linear terms, on the lagged variables ``z`` standardised by their means and standard
    deviations over the estimation data.

    Parameters
    ----------
    n_centres : int
        Number of centres found by k-means clustering of the standardised lag vectors
        (ignored when ``centres`` is given).
    centres : array_like (n_centres, n_lagged_variables), optional
        Centres in the units of the data (lagged variables in the model's order).
    widths : float or array_like, optional
        Width(s) in standardised units; default: for each centre, the distance to its
        nearest other centre (at least 0.5).
    seed : int
        Seed of the clustering.

    Examples
    --------
    >>> import sysid
    >>> sysid.RBFBasis(n_centres=8)
    RBFBasis(n_centres=8)
    """

    def __init__(self, n_centres: int = 10, *, centres: Any = None, widths: Any = None,
                 seed: int = 0) -> None:
        self.n_centres = int(n_centres) if centres is None else int(np.shape(centres)[0])
        if self.n_centres < 1:
            raise DataError(f"n_centres must be at least 1, got {n_centres!r}")
        self.centres_data = None if centres is None else np.atleast_2d(np.asarray(centres,
                                                                                   float))
        self.widths_arg = widths
        self.seed = int(seed)
        self.centres: np.ndarray | None = None  # standardised, after fitting
        self.widths: np.ndarray | None = None
        self.shift: np.ndarray | None = None
        self.scale: np.ndarray | None = None

    def fitted(self, lags: np.ndarray | list[np.ndarray]) -> RBFBasis:
        """A copy with shift, scale, centres and widths fitted to lag vectors ``(n, nv)``, or
        to a list of them, one per experiment: stacked in an order of their own (by their
        contents), so that the seeded clustering does not depend on the order in which the
        experiments are given (one experiment is taken as it is)."""
        from scipy.cluster.vq import kmeans2

        if isinstance(lags, (list, tuple)):
            lags = np.vstack(sorted(lags, key=lambda a: (a.shape[0], a.tobytes())))
        out = RBFBasis(self.n_centres, centres=self.centres_data, widths=self.widths_arg,
                       seed=self.seed)
        shift = lags.mean(axis=0)
        scale = lags.std(axis=0)
        scale[scale <= 0] = 1.0
        z = (lags - shift) / scale
        if self.centres_data is not None:
            if self.centres_data.shape[1] != lags.shape[1]:
                raise DataError(f"centres have {self.centres_data.shape[1]} columns but the "
                                f"model has {lags.shape[1]} lagged variables")
            c = (self.centres_data - shift) / scale
        else:
            if z.shape[0] < self.n_centres:
                raise DataError(f"{self.n_centres} centres need at least as many samples")
            rng = np.random.default_rng(self.seed)
            pick = z[rng.choice(z.shape[0], min(z.shape[0], 20000), replace=False)]
            c, _ = kmeans2(pick, self.n_centres, minit="++", seed=self.seed)
        if self.widths_arg is None:
            if c.shape[0] > 1:
                d = np.sqrt(((c[:, None, :] - c[None, :, :]) ** 2).sum(-1))
                np.fill_diagonal(d, np.inf)
                w = np.maximum(d.min(axis=1), 0.5)
            else:
                w = np.ones(1)
        else:
            w = np.broadcast_to(np.asarray(self.widths_arg, float), (c.shape[0],)).copy()
        out.centres, out.widths, out.shift, out.scale = c, w, shift, scale
        return out

    def rust_args(self) -> tuple[int | None, Any]:
        """``(degree, rbf)`` arguments of the Rust functions."""
        if self.centres is None:
            raise DataError("this RBFBasis is not fitted to data; use the model's basis")
        return None, (np.ascontiguousarray(self.centres), np.ascontiguousarray(self.widths),
                      np.ascontiguousarray(self.shift), np.ascontiguousarray(self.scale))

    def to_dict(self) -> dict[str, Any]:
        """For saving (the fitted parameters)."""
        return {"kind": "rbf", "n_centres": self.n_centres, "centres": self.centres,
                "widths": self.widths, "shift": self.shift, "scale": self.scale,
                "seed": self.seed}

    def __repr__(self) -> str:
        return f"RBFBasis(n_centres={self.n_centres})"


def basis_from_dict(d: dict[str, Any]) -> PolynomialBasis | RBFBasis:
    """Inverse of ``basis.to_dict()``."""
    if d["kind"] == "polynomial":
        return PolynomialBasis(int(d["degree"]))
    b = RBFBasis(int(d["n_centres"]), seed=int(d.get("seed", 0)))
    b.centres, b.widths = np.asarray(d["centres"], float), np.asarray(d["widths"], float)
    b.shift, b.scale = np.asarray(d["shift"], float), np.asarray(d["scale"], float)
    return b


def lag_names(na: list[int], nb: list[int], nk: list[int], ne: list[int],
              input_names: list[str], output_names: list[str]) -> list[str]:
    """Names of the lagged variables in the model's order."""
    out = [f"{output_names[k]}(t-{lag})" for k in range(len(na)) for lag in range(1, na[k] + 1)]
    for j in range(len(nb)):
        out += [f"{input_names[j]}(t-{lag})" if lag else f"{input_names[j]}(t)"
                for lag in range(nk[j], nk[j] + nb[j])]
    out += [f"e_{output_names[k]}(t-{lag})" for k in range(len(ne)) for lag in range(1, ne[k] + 1)]
    return out


def channel_names(names: Any, prefix: str, count: int) -> list[str]:
    """``names`` as strings, or ``prefix0, prefix1, ...`` when ``None``."""
    return [f"{prefix}{j}" for j in range(count)] if names is None else [str(n) for n in names]


def term_name(term: list[int], names: list[str], custom: list[str] | None = None) -> str:
    """``1``, ``y0(t-1)^2 u0(t-1)``, ``rbf3`` or the name of custom regressor ``c`` (term
    ``[-1, c]``)."""
    if len(term) == 2 and term[0] == -1:
        return (custom or [])[term[1]]
    if len(term) == 1 and term[0] < 0:
        return f"rbf{-1 - term[0]}"
    if not term:
        return "1"
    parts, i = [], 0
    while i < len(term):
        j = i
        while j < len(term) and term[j] == term[i]:
            j += 1
        parts.append(names[term[i]] + (f"^{j - i}" if j - i > 1 else ""))
        i = j
    return " ".join(parts)


class LaggedIO:
    """The argument checks of a NARX model's ``simulate`` and ``predict`` (the host has
    ``ninputs``, ``noutputs`` and ``max_lag``)."""

    ninputs: int
    noutputs: int
    max_lag: int

    def _u(self, u: Any) -> np.ndarray:
        """``u`` as a contiguous real, finite ``(n_samples, ninputs)`` array."""
        if self.ninputs == 0 and np.ndim(u) == 1:
            return np.zeros((np.size(u), 0))
        return np.ascontiguousarray(as_2d(u, "u", ncols=self.ninputs,
                                          allow_empty=self.ninputs == 0))

    def _y0(self, x0: Any) -> np.ndarray:
        """The first ``max_lag`` outputs a simulation starts from: ``x0`` (``None`` or
        ``"zero"``: zeros)."""
        lag, ny = self.max_lag, self.noutputs
        if x0 is None or (isinstance(x0, str) and x0 == "zero"):
            return np.zeros((lag, ny))
        want = f"the first {lag} outputs, shape ({lag}, {ny})"
        if isinstance(x0, (str, bytes)):
            raise DataError(f"x0 must be None, 'zero' or {want}; got {x0!r}")
        y0 = as_2d(x0, "x0")  # complex, NaN, not numeric: an error naming x0
        if y0.size % ny:
            raise ShapeError(f"x0 has shape {y0.shape} but should hold {want}")
        y0 = y0.reshape(-1, ny)[:lag]
        if y0.shape[0] < lag:
            raise ShapeError(f"x0 must hold {want}")
        return np.ascontiguousarray(y0)

    def _measured(self, u: Any, y: Any, horizon: Any
                  ) -> tuple[np.ndarray, np.ndarray, int | None]:
        """``predict``'s arguments checked: ``u``, ``y`` of one length and the horizon
        (``None`` for ``np.inf``, the simulation)."""
        if self.ninputs == 0 and np.ndim(u) == 1:
            u = np.zeros((np.size(u), 0))
        u, y = as_measured(*predict_args(u, y), self.ninputs, self.noutputs)
        return np.ascontiguousarray(u), np.ascontiguousarray(y), as_horizon(horizon)

    def _measured_start(self, y: np.ndarray) -> np.ndarray:
        """The first ``max_lag`` measured outputs, from which ``predict(..., np.inf)``
        simulates (MATLAB's ``predict(sys, data, Inf)``; any ``k``-step prediction with ``k``
        beyond the record equals it); zeros past a record shorter than that, whose outputs
        are then all copied."""
        lag = self.max_lag
        start = np.zeros((lag, self.noutputs))
        start[:min(lag, y.shape[0])] = y[:lag]
        return start


class NARXModel(LaggedIO, ModelMixin):
    """A (MIMO) NARX / NARMAX model: one equation of selected terms per output.

    Parameters
    ----------
    na : list of int (n_outputs)
        Output lags ``1..na[k]`` of each output (shared by every equation).
    nb, nk : list of int (n_inputs)
        Input lags ``nk[j]..nk[j] + nb[j] - 1``.
    basis : PolynomialBasis or RBFBasis
        The basis the terms come from (fitted, for RBF).
    terms : list (n_outputs) of lists of terms
        A term is a list of lagged-variable indices (a monomial; ``[]`` is the constant) or
        ``[-1 - c]`` for radial basis function ``c``.
    coefs : list (n_outputs) of arrays
        Coefficients of the terms.
    dt : float
        Sample time.
    ne : list of int (n_outputs), optional
        Residual lags of the NARMAX noise terms (zero in simulation).
    err : list of arrays, optional
        Error reduction ratio of each term (from FROLS).
    noise_variance : array_like, optional
        Residual variance per output.
    custom : list of CustomRegressor, optional
        User-supplied regressors; term ``[-1, c]`` is ``custom[c]``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> # y(t) = 0.5 y(t-1) + u(t-1) - 0.2 u(t-1)^2
    >>> m = sysid.NARXModel([1], [1], [1], sysid.PolynomialBasis(2), [[[0], [1], [1, 1]]],
    ...                     [[0.5, 1.0, -0.2]], dt=1.0)
    >>> np.round(m.simulate(np.ones(4)).ravel(), 12).tolist()
    [0.0, 0.8, 1.2, 1.4]
    >>> print(m.terms_table())
    y0 = 0.5 y0(t-1) + 1 u0(t-1) - 0.2 u0(t-1)^2
    """

    def __init__(self, na: Any, nb: Any, nk: Any, basis: PolynomialBasis | RBFBasis,
                 terms: Any, coefs: Any, dt: float, *, ne: Any = None, err: Any = None,
                 noise_variance: Any = None, input_names: Any = None,
                 output_names: Any = None, info: dict[str, Any] | None = None,
                 custom: Any = None) -> None:
        self.na = [int(v) for v in np.atleast_1d(na)]
        self.nb = [int(v) for v in np.atleast_1d(nb)] if np.size(nb) else []
        self.nk = [int(v) for v in np.atleast_1d(nk)] if np.size(nk) else []
        ny, nu = len(self.na), len(self.nb)
        self.ne = [0] * ny if ne is None else [int(v) for v in np.atleast_1d(ne)]
        if len(self.nk) != nu or len(self.ne) != ny:
            raise DataError(f"nk needs {nu} entries (one per input) and ne {ny} (per output)")
        self.basis = basis
        self.terms = [[[int(v) for v in t] for t in ts] for ts in terms]
        self.coefs = [np.asarray(c, float).ravel() for c in coefs]
        if len(self.terms) != ny or len(self.coefs) != ny or any(
                len(t) != c.size for t, c in zip(self.terms, self.coefs)):
            raise DataError(f"terms and coefs need one list per output ({ny}), one "
                            "coefficient per term")
        self.err = ([np.asarray(e, float).ravel() for e in err] if err is not None
                    else [np.full(c.size, np.nan) for c in self.coefs])
        self.dt = float(dt)
        self.noise_variance = (np.ones(ny) if noise_variance is None
                               else np.asarray(noise_variance, float).ravel())
        self.input_names = channel_names(input_names, "u", nu)
        self.output_names = channel_names(output_names, "y", ny)
        self.info: dict[str, Any] = dict(info or {})
        self.custom: list[CustomRegressor] = list(custom or [])
        if not all(isinstance(c, CustomRegressor) for c in self.custom):
            raise DataError("custom must be a list of sysid.CustomRegressor")
        self._custom_args = [c.resolve(self.output_names, self.input_names)
                             for c in self.custom]
        # checks terms against the lags and basis (raises a DataError naming the problem)
        self._rust("simulate", np.zeros((self.max_lag + 1, nu)),
                   np.zeros((self.max_lag, ny)), fns=[lambda *a: 0.0] * len(self.custom))

    # -- protocol ----------------------------------------------------------------------
    ninputs = property(lambda self: len(self.nb), doc="Number of inputs.")
    noutputs = property(lambda self: len(self.na), doc="Number of outputs.")

    @property
    def n_parameters(self) -> int:
        """Number of selected terms (coefficients) over all outputs."""
        return int(sum(c.size for c in self.coefs))

    @property
    def max_lag(self) -> int:
        """Largest lag: the number of initial outputs a simulation needs."""
        lags = [*self.na, *[b + k - 1 for b, k in zip(self.nb, self.nk) if b], *self.ne, 1]
        lags += [lag for a in getattr(self, "_custom_args", []) for _, _, lag in a]
        return int(max(lags))

    @property
    def regressor_names(self) -> list[str]:
        """Names of the lagged variables (indices of the monomial terms)."""
        return lag_names(self.na, self.nb, self.nk, self.ne, self.input_names,
                         self.output_names)

    def term_names(self, output: int = 0) -> list[str]:
        """Readable names of the terms of one output's equation."""
        names, custom = self.regressor_names, [c.name for c in self.custom]
        return [term_name(t, names, custom) for t in self.terms[output]]

    def _rust(self, fn: str, *arrays: Any, fns: Any = None) -> np.ndarray:
        degree, rbf = self.basis.rust_args()
        structure = {"orders": (self.na, self.nb, self.nk, self.ne), "degree": degree,
                     "rbf": rbf, "custom_args": self._custom_args if self.custom else []}
        eqs = [(t, c.tolist()) for t, c in zip(self.terms, self.coefs)]
        if not self.custom:
            return np.asarray(getattr(_sysid, f"narx_{fn}")(structure, eqs, *arrays))
        fns = [c.scalar() for c in self.custom] if fns is None else fns
        return np.asarray(getattr(_sysid, f"narx_{fn}")(structure, eqs, *arrays, custom_fns=fns))

    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Free-run simulation (noise terms zero).

        ``x0``: the first ``max_lag`` outputs, array ``(max_lag, noutputs)`` (for example the
        measured ones); ``None`` or ``"zero"`` starts from zero outputs. Raises a
        :class:`~sysid.NumericalError` naming the sample when the simulation diverges.
        """
        return self._rust("simulate", self._u(u), self._y0(x0))

    def predict(self, u: Any, y: Any = None, horizon: int = 1) -> np.ndarray:
        """``horizon``-step prediction ``yhat(t | t - horizon)`` from measured ``u``, ``y``
        (NARMAX: residual terms from the one-step residuals up to ``t - horizon``);
        ``np.inf``: the simulation from the measured first ``max_lag`` outputs. The first
        ``max_lag`` rows repeat the measured outputs."""
        u, y, h = self._measured(u, y, horizon)
        if h is None:
            return self.simulate(u, x0=self._measured_start(y))
        return self._rust("predict", u, y, h)

    def linearize(self) -> Any:
        """The linear ARX model of the first-order terms around zero (a
        :class:`~sysid.PolynomialModel`; constant, higher-degree and RBF terms dropped). The
        linearisation at a steady operating point is :func:`sysid.linearize`."""
        from ..polynomial.model import PolynomialModel

        ny, nu = self.noutputs, self.ninputs
        a = [[np.zeros(self.na[k]) for k in range(ny)] for _ in range(ny)]
        b = [[np.zeros(self.nb[j]) for j in range(nu)] for _ in range(ny)]
        offs = np.cumsum([0, *self.na, *self.nb])
        for i in range(ny):
            for t, c in zip(self.terms[i], self.coefs[i]):
                if len(t) != 1 or t[0] < 0 or t[0] >= offs[-1]:
                    continue
                v = t[0]
                blk = int(np.searchsorted(offs, v, side="right") - 1)
                if blk < ny:
                    a[i][blk][v - offs[blk]] = -c
                else:
                    b[i][blk - ny][v - offs[blk]] = c
        return PolynomialModel(a, b, [list(self.nk)] * ny, self.dt)

    def to_nlss(self) -> Any:
        """The nonlinear state-space form (:class:`~sysid.NARXStateSpace`): the state is the
        shift register of the last ``max_lag`` outputs and inputs; its simulation is this
        model's free run."""
        from .narx_ss import NARXStateSpace

        return NARXStateSpace(self)

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response of :meth:`linearize` (the small-signal response at zero)."""
        return np.asarray(self.linearize().freqresp(omega))

    def poles(self, std: bool = False) -> np.ndarray:
        """Poles of :meth:`linearize`."""
        no_pole_std(self, std)
        return np.asarray(self.linearize().poles())

    # -- presentation ------------------------------------------------------------------
    def to_pandas(self) -> Any:
        """One row per (output, term): name, coefficient, ERR."""
        import pandas as pd

        rows = [{"output": self.output_names[i], "term": n, "coefficient": c, "err": e}
                for i in range(self.noutputs)
                for n, c, e in zip(self.term_names(i), self.coefs[i], self.err[i])]
        return pd.DataFrame(rows, columns=["output", "term", "coefficient", "err"])

    def terms_table(self) -> str:
        """The equations, one line per output."""
        lines = []
        for i in range(self.noutputs):
            parts = []
            for n, c in zip(self.term_names(i), self.coefs[i]):
                sign = "-" if c < 0 else "+"
                parts.append(f"{sign} {abs(c):.4g}" + ("" if n == "1" else f" {n}"))
            body = " ".join(parts).lstrip("+ ") if parts else "0"
            if body.startswith("- "):
                body = "-" + body[2:]
            lines.append(f"{self.output_names[i]} = {body}")
        return "\n".join(lines)

    def summary(self) -> str:
        """Terms with coefficients and error reduction ratios."""
        out = [repr(self)]
        for i in range(self.noutputs):
            out.append(f"output {self.output_names[i]} (residual variance "
                       f"{self.noise_variance[i]:.4g}):")
            out.append(f"  {'term':<32} {'coefficient':>14} {'ERR':>10}")
            for n, c, e in zip(self.term_names(i), self.coefs[i], self.err[i]):
                out.append(f"  {n:<32} {c:>14.6g} {e:>10.4g}")
        return "\n".join(out)

    def __repr__(self) -> str:
        kind = "NARMAX" if any(self.ne) else "NARX"
        return (f"NARXModel({kind}, {self.noutputs} output(s), {self.ninputs} input(s), "
                f"{self.n_parameters} terms, {self.basis!r}, dt={self.dt:g})")

    def plot(self, fig: Any = None) -> Any:
        """Bar chart of the ERR of each output's terms; returns the figure."""
        import matplotlib.pyplot as plt

        fig = fig or plt.figure(figsize=(7, 2.5 * self.noutputs))
        for i in range(self.noutputs):
            ax = fig.add_subplot(self.noutputs, 1, i + 1)
            ax.barh(self.term_names(i)[::-1], self.err[i][::-1])
            ax.set_xlabel(f"ERR ({self.output_names[i]})")
        fig.tight_layout()
        return fig

    # -- saving ------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Everything needed to rebuild the model (see :func:`sysid.save_model`)."""
        if self.custom:
            raise DataError("a NARXModel with custom regressors holds Python functions and "
                            "cannot be saved; save the terms and coefficients (to_pandas()) "
                            "and rebuild it with NARXModel(..., custom=[...])")
        return {"na": self.na, "nb": self.nb, "nk": self.nk, "ne": self.ne,
                "basis": self.basis.to_dict(), "terms": self.terms,
                "coefs": [c for c in self.coefs], "err": [e for e in self.err],
                "dt": self.dt, "noise_variance": self.noise_variance,
                "input_names": self.input_names, "output_names": self.output_names,
                "info": self.info}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NARXModel:
        """Inverse of :meth:`to_dict`."""
        return cls(d["na"], d["nb"], d["nk"], basis_from_dict(dict(d["basis"])), d["terms"],
                   d["coefs"], float(d["dt"]), ne=d.get("ne"), err=d.get("err"),
                   noise_variance=d.get("noise_variance"), input_names=d.get("input_names"),
                   output_names=d.get("output_names"), info=d.get("info"))
