"""Parameter uncertainty of an estimated model and its propagation: written once, used by
every model family.

An estimator that knows the covariance ``P`` of its free parameters ``theta`` attaches

.. math::

    \\texttt{ParameterUncertainty}(\\theta, P, \\texttt{build})

where ``build(theta)`` rebuilds the model. Any real function ``f`` of the model then gets the
first-order (delta-method) covariance ``J P J^T`` with ``J = df/dtheta`` taken by central
differences along the eigenvectors of ``P`` (only the directions that ``P`` spans matter, so the
unidentifiable directions of an over-parameterised model are never stepped along), or a Monte
Carlo estimate from models drawn from ``N(theta, P)``. Poles use the analytic first-order
perturbation ``d lambda = w^H dA v / (w^H v)`` (left and right eigenvectors) where the model
has an ``A`` matrix (:mod:`sysid.models.pole_uncertainty`); a pole that coincides with
another (numerically, or within their uncertainty), where the first-order expansion does not
exist, gets the Monte Carlo value instead and an :class:`UncertaintyWarning` says so.

Examples
--------
>>> import numpy as np, sysid
>>> from sysid.models.uncertainty import ParameterUncertainty
>>> unc = ParameterUncertainty([0.5, 1.0], np.diag([1e-4, 4e-4]),
...                            lambda t: sysid.StateSpaceModel([[t[0]]], [[t[1]]], [[1.0]]),
...                            names=["a", "b"])
>>> np.round(unc.std, 6)
array([0.01, 0.02])
>>> g = unc.propagate(lambda m: m.dcgain().ravel())   # b / (1 - a)
>>> round(float(g.value[0]), 6), round(float(g.std[0]), 4)
(2.0, 0.0566)
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np

from .._checks import user_stacklevel
from .._display import HTMLResult
from ..errors import DataError, SysidWarning

__all__ = ["ParameterUncertainty", "Propagation", "UncertaintyWarning"]

_METHODS = ("linear", "monte-carlo")


class UncertaintyWarning(SysidWarning):
    """A standard deviation could not be computed reliably (reported as NaN)."""


class Propagation(NamedTuple):
    """Value of a function of the model and its covariance; unpacks as ``value, covariance``.

    Attributes
    ----------
    value : ndarray
        ``fn(model)`` at the estimate (its own shape).
    covariance : ndarray
        Covariance of ``value.ravel()``, shape ``(k, k)``.
    """

    value: np.ndarray
    covariance: np.ndarray

    @property
    def std(self) -> np.ndarray:
        """Standard deviations, shaped like :attr:`value`."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None)).reshape(
            np.shape(self.value))


def _real_vector(x: Any, what: str = "fn(model)") -> np.ndarray:
    a = np.asarray(x)
    if np.iscomplexobj(a):
        raise DataError(f"{what} must be real: propagate its real and imaginary parts (or "
                        "abs and angle) as separate entries")
    return a.astype(float)


#: times a central difference's step is shortened (by 10 each) where the two sides disagree
BENT_RETRIES = 4


def _bent(fp: np.ndarray, fm: np.ndarray, f0: np.ndarray) -> bool:
    """Whether values ``fp``, ``fm`` one step either side of ``f0`` are far from a straight
    line through it: the second difference over half the first difference's size (above
    1e-6 of the values, so that rounding of a flat function is not taken for a bend). In
    the linear range it is of the order of the step; it is about 1 when one side runs away
    (a perturbed model that turns unstable and whose simulation grows without bound)."""
    with np.errstate(all="ignore"):
        bend = float(np.linalg.norm(fp + fm - 2.0 * f0))
        slope = float(np.linalg.norm(fp - fm))
        size = float(np.linalg.norm(f0))
    if not (np.isfinite(bend) and np.isfinite(slope)):
        return True
    return bend > 0.5 * slope and bend > 1e-6 * size


class ParameterUncertainty(HTMLResult):
    """Covariance of the free parameters of an estimated model, and its propagation.

    Parameters
    ----------
    theta : array_like, shape (p,)
        Free parameters at the estimate.
    covariance : array_like, shape (p, p)
        Their covariance (symmetric positive semi-definite; it may be singular, as for an
        over-parameterised state-space model whose similarity directions are not identifiable).
    build : callable
        ``build(theta) -> model`` of the same family (``StateSpaceModel``, ``PolynomialModel``,
        ...).
    names : sequence of str, optional
        One name per parameter (default ``theta0, theta1, ...``).
    dof : int, optional
        Number of identifiable directions (default: the numerical rank of ``covariance``).
        When given, the eigendecomposition of ``covariance`` waits until sampling or
        propagation needs it (a Cholesky factor checks it is positive semi-definite now).
    method : str
        How the covariance was obtained (``"gauss-newton"``, ``"least-squares"``,
        ``"bootstrap"``, ``"instrumental-variable"``, ...); informational.
    undetermined : sequence of int, optional
        Parameters the data do not determine (they lie along a direction that does not
        change the fit: a grey-box or transfer-function parameterisation that is not
        identifiable). Their :attr:`std` is inf; the covariance itself (the minimum-norm one
        on the determined directions) still propagates to poles, responses and the other
        functions of the model, which the data do determine.
    blocks : sequence of int, optional
        ``covariance`` is block diagonal with blocks of these sizes (the outputs of a
        multi-output polynomial model are estimated separately): it is checked and
        decomposed block by block (a 60-output ARX model, 7320 parameters, took minutes as
        one dense matrix).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> unc = ParameterUncertainty([0.9], [[1e-4]],
    ...                            lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))
    >>> unc
    ParameterUncertainty(1 parameter, rank 1, gauss-newton)
    >>> p = unc.propagate(lambda m: m.poles().real)
    >>> round(float(p.std[0]), 6)
    0.01
    """

    def __init__(
        self,
        theta: Any,
        covariance: Any,
        build: Callable[[np.ndarray], Any],
        *,
        names: Sequence[str] | None = None,
        dof: int | None = None,
        method: str = "gauss-newton",
        undetermined: Sequence[int] = (),
        blocks: Sequence[int] | None = None,
    ) -> None:
        th = np.asarray(theta, dtype=float).ravel()
        P = np.asarray(covariance, dtype=float)
        p = th.size
        if P.shape != (p, p):
            raise DataError(f"covariance has shape {P.shape} but theta has {p} entries: "
                            f"it must be ({p}, {p})")
        if not (np.all(np.isfinite(th)) and np.all(np.isfinite(P))):
            raise DataError("theta and covariance must be finite")
        if not callable(build):
            raise DataError("build must be a callable build(theta) -> model")
        P = 0.5 * (P + P.T)
        self.theta = th
        self.covariance = P
        self.build = build
        self.names = list(names) if names is not None else [f"theta{i}" for i in range(p)]
        if len(self.names) != p:
            raise DataError(f"names has {len(self.names)} entries but theta has {p}")
        self._eig: tuple[np.ndarray, np.ndarray] | None = None
        if blocks is not None:
            self._eig = _block_eigen(P, [int(b) for b in blocks])
        elif dof is None:
            self._eigen()          # the rank, and positive semi-definiteness checked now
        else:
            # the estimator knows the rank: the eigendecomposition (seconds for p ~ 1500, and
            # with a threaded BLAS ~0.1 s of CPU on the idle threads even for p ~ 50) waits
            # until sampling or first-order propagation needs it; a Cholesky factor checks
            # definiteness now
            top = float(np.max(np.diag(P), initial=0.0))
            try:
                np.linalg.cholesky(P + 1e-8 * max(top, 1e-300) * np.eye(p))
            except np.linalg.LinAlgError:
                self._eigen()      # raises with the eigenvalues
        self.dof = int(self._w.size) if dof is None else int(dof)
        self.method = str(method)
        self.undetermined = sorted({int(i) for i in undetermined})
        if any(not 0 <= i < p for i in self.undetermined):
            raise DataError(f"undetermined holds indices outside 0..{p - 1}: "
                            f"{self.undetermined}")
        self._cache: tuple[list[float], list[Any], list[Any]] | None = None

    def through(self, fn: Callable[[Any], Any]) -> ParameterUncertainty:
        """The same parameters and covariance seen through ``fn``: the uncertainty of a
        model derived from the estimate (resampled, converted, delays absorbed), whose
        draws are ``fn`` of the estimate's draws.

        Examples
        --------
        >>> import numpy as np
        >>> p = ParameterUncertainty([0.5], [[1e-4]], lambda t: float(t[0]))
        >>> float(np.round(p.through(lambda a: 2 * a).build(np.array([0.25])), 6))
        0.5
        """
        build = self.build
        self.covariance  # noqa: B018 - a deferred covariance (pem's sandwich) formed first
        # the covariance was checked, and its eigenpairs (when computed) hold: reused, so
        # that a conversion on every call (a polynomial model's response through its
        # state-space form) costs no factorisation; only the draws change
        new = object.__new__(ParameterUncertainty)
        new.__dict__.update(self.__dict__)
        new.__dict__.pop("_pending", None)
        new.build = lambda t: fn(build(t))
        new._cache = None
        return new

    def __reduce__(self) -> Any:
        """Pickling: an estimator's ``build`` is often a closure, which cannot be pickled;
        it is then replaced by the affine map :func:`sysid.save_model` writes (the same
        first-order standard deviations; see :mod:`sysid.models.uncertainty_io`)."""
        import inspect
        import pickle

        unc = self
        try:  # a bound method (a model's own): pickled with its model, cycles and all
            if not inspect.ismethod(self.build):
                pickle.dumps(self.build)
        except (pickle.PicklingError, AttributeError, TypeError, RecursionError):
            unc = self._affine()
        return (ParameterUncertainty, (unc.theta, unc.covariance, unc.build),
                {"names": unc.names, "dof": unc.dof, "method": unc.method,
                 "undetermined": unc.undetermined})

    def _affine(self) -> ParameterUncertainty:
        """This uncertainty with ``build`` replaced by its measured affine map (what
        :func:`sysid.save_model` writes); itself when the model cannot be written."""
        from .affine_map import affine_build, stored_map

        nominal = self.build(self.theta)
        if not callable(getattr(nominal, "to_dict", None)):
            return self
        saved = stored_map(self, type(nominal))
        if "omitted" in saved:
            return self
        build = affine_build(saved, nominal.to_dict(), type(nominal), self.theta)
        method = self.method + ("" if saved["linear"] else
                                " (pickled: first-order map of a nonlinear parameterisation)")
        return ParameterUncertainty(self.theta, self.covariance, build, names=self.names,
                                    dof=self.dof, method=method,
                                    undetermined=self.undetermined)

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.names, self.dof, self.method = state["names"], state["dof"], state["method"]
        self.undetermined = list(state.get("undetermined", []))

    def __copy__(self) -> ParameterUncertainty:
        new = object.__new__(ParameterUncertainty)
        new.__dict__.update(self.__dict__)
        return new

    def __deepcopy__(self, memo: dict[int, Any]) -> ParameterUncertainty:
        """A copy as ``copy.deepcopy`` makes it by default (a function ``build`` shared, a
        model's bound method bound to the copy), not the pickled form of :meth:`__reduce__`."""
        import copy
        import inspect

        new = object.__new__(ParameterUncertainty)
        memo[id(self)] = new
        for k, v in self.__dict__.items():
            keep = k == "build" and not inspect.ismethod(v)
            setattr(new, k, v if keep else copy.deepcopy(v, memo))
        return new

    def _eigen(self) -> tuple[np.ndarray, np.ndarray]:
        """Eigenpairs of the covariance on its range (computed once)."""
        if self._eig is None:
            self._eig = _block_eigen(self.covariance, [self.covariance.shape[0]])
        return self._eig

    @property
    def _w(self) -> np.ndarray:
        return self._eigen()[0]

    @property
    def _V(self) -> np.ndarray:
        return self._eigen()[1]

    # -- parameters ---------------------------------------------------------------------
    @property
    def n_parameters(self) -> int:
        """Number of free parameters p."""
        return self.theta.size

    @property
    def std(self) -> np.ndarray:
        """Standard deviation of each free parameter, shape ``(p,)``; inf for the parameters
        the data do not determine (``undetermined``)."""
        sd = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        sd[getattr(self, "undetermined", [])] = np.inf
        return sd

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix of the parameters (NaN rows/columns where a std is zero or the
        parameter is undetermined)."""
        s = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        with np.errstate(divide="ignore", invalid="ignore"):
            out = self.covariance / np.outer(s, s)
        out[np.outer(s, s) == 0] = np.nan
        out[self.undetermined, :] = np.nan
        out[:, self.undetermined] = np.nan
        return out

    @property
    def model(self) -> Any:
        """The model at the estimate, ``build(theta)``."""
        return self.build(self.theta)

    def sample_parameters(self, n: int, rng: Any = None) -> np.ndarray:
        """``n`` parameter vectors drawn from ``N(theta, covariance)``, shape ``(n, p)``."""
        if int(n) < 1:
            raise DataError(f"n must be a positive number of samples, got {n}")
        rng = np.random.default_rng(rng)
        z = rng.standard_normal((int(n), self._w.size))
        return self.theta + (z * np.sqrt(self._w)) @ self._V.T

    def sample(self, n: int, rng: Any = None) -> list[Any]:
        """``n`` models whose parameters are drawn from the Gaussian approximation.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> unc = ParameterUncertainty([0.5], [[0.01]],
        ...     lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))
        >>> len(unc.sample(3, rng=0))
        3
        """
        return [self.build(t) for t in self.sample_parameters(n, rng)]

    # -- first-order machinery ----------------------------------------------------------
    def _perturbed(self, step: float) -> tuple[list[float], list[Any], list[Any]]:
        """Models at ``theta +- h_k v_k`` along each identifiable eigenvector ``v_k`` (cached:
        every first-order quantity reuses them)."""
        if self._cache is not None and self._cache[0] and self._step == step:
            return self._cache
        hs, plus, minus = [], [], []
        for lam, v in zip(self._w, self._V.T):
            # not below the rounding of the parameters the direction moves (those of the
            # others, large ones among them, would push a well-determined direction hundreds
            # of its standard deviations: into an unstable model, on an output-error fit
            # whose initial state was in the millions)
            h = max(step * np.sqrt(lam), 1e-7 * max(1.0, float(np.linalg.norm(self.theta * v))))
            hs.append(h)
            plus.append(self._built(self.theta + h * v))
            minus.append(self._built(self.theta - h * v))
        self._cache, self._step = (hs, plus, minus), step
        return self._cache

    def _built(self, theta: np.ndarray) -> Any:
        """The model at ``theta``, or the reason (a ``str``) it cannot be built there (a
        continuous-time model whose sampling overflows: a process model's step test)."""
        from ..errors import NonFiniteError, NumericalError

        try:
            return self.build(theta)
        except (NumericalError, NonFiniteError) as e:
            return str(e)

    def scaled_jacobian(self, fn: Callable[[Any], Any], *, step: float = 1e-3
                        ) -> tuple[np.ndarray, np.ndarray]:
        """``fn(model)`` (flattened) and ``G`` with ``G G^T`` its first-order covariance.

        ``G[:, k] = d fn / d theta . v_k sqrt(lambda_k)`` for the eigenpairs ``(lambda_k, v_k)``
        of the covariance (central differences with steps ``step * sqrt(lambda_k)``). ``fn``
        may return complex values (then ``G`` is complex).
        """
        from ..errors import NonFiniteError, NumericalError

        value = np.asarray(fn(self.build(self.theta)))
        flat = value.ravel()
        hs, plus, minus = self._perturbed(step)
        G = np.zeros((flat.size, len(hs)), dtype=complex if np.iscomplexobj(flat) else float)
        failed: list[str] = []

        def at(m: Any) -> tuple[np.ndarray | None, str]:
            # a model this close to the estimate may have no such quantity (its simulation
            # overflows, its matrices are not finite), or not be built at all (a reason)
            if isinstance(m, str):
                return None, m
            try:
                return np.asarray(fn(m)).ravel(), ""
            except (NumericalError, NonFiniteError) as e:
                return None, str(e)

        for k, (h, mp, mm) in enumerate(zip(hs, plus, minus)):
            (fp, ep), (fm, em) = at(mp), at(mm)
            # a step past where ``fn`` is nearly linear (a simulation whose model turns
            # unstable on one side and grows without bound there): shorter steps, until
            # both sides agree on the slope
            for _ in range(BENT_RETRIES):
                if fp is None or fm is None or not _bent(fp, fm, flat):
                    break
                h /= 10.0
                v = self._V[:, k]
                (fp, ep), (fm, em) = (at(self._built(self.theta + h * v)),
                                      at(self._built(self.theta - h * v)))
            # a one-sided difference on the side that has the quantity, and no finite std
            # when neither side has one
            if fp is not None and fm is not None:
                d = (fp - fm) / (2 * h)
            elif fp is not None:
                d = (fp - flat) / h
            elif fm is not None:
                d = (flat - fm) / h
            else:
                failed.append(ep or em)
                G[:, k] = np.inf
                continue
            G[:, k] = d * np.sqrt(self._w[k])
        if failed:
            warnings.warn(
                f"models {step:g} standard deviations from the estimate on both sides along "
                f"{len(failed)} of the covariance's {len(hs)} directions cannot be evaluated "
                f"({failed[0]}): "
                "the estimate is that close to an unstable or degenerate model, so the "
                "standard deviations that depend on them are reported as inf; refit with "
                "fewer parameters, or check with method='monte-carlo'",
                UncertaintyWarning, stacklevel=user_stacklevel())
        return value, G

    def jacobian(self, fn: Callable[[Any], Any], *, step: float = 1e-3) -> np.ndarray:
        """``d fn(model) / d theta``, shape ``(k, p)``, in the directions the covariance spans
        (components along unidentifiable directions are zero)."""
        _, G = self.scaled_jacobian(fn, step=step)
        with np.errstate(divide="ignore"):
            return (G / np.sqrt(self._w)) @ self._V.T

    def propagate(
        self,
        fn: Callable[[Any], Any],
        method: str = "linear",
        *,
        n: int = 1000,
        rng: Any = None,
        jacobian: Any = None,
        step: float = 1e-3,
    ) -> Propagation:
        """Value of a real function of the model and its covariance.

        Parameters
        ----------
        fn : callable
            ``fn(model) -> array`` of real numbers.
        method : {"linear", "monte-carlo"}
            First order ``J P J^T`` (default), or the sample covariance of ``fn`` over ``n``
            models drawn from ``N(theta, P)``.
        n : int
            Monte Carlo samples.
        rng : seed or numpy Generator, optional
        jacobian : array_like or callable, optional
            Analytic ``d fn / d theta`` (``(k, p)``, or ``jacobian(theta)`` returning it) instead
            of central differences.
        step : float
            Difference step in standard deviations along each eigen-direction.

        Returns
        -------
        Propagation
            ``(value, covariance)`` with ``.std``.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> unc = ParameterUncertainty([0.5], [[1e-4]],
        ...     lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]]))
        >>> lin = unc.propagate(lambda m: m.dcgain().ravel())
        >>> mc = unc.propagate(lambda m: m.dcgain().ravel(), "monte-carlo", n=4000, rng=1)
        >>> round(float(lin.std[0]), 3), bool(abs(mc.std[0] / lin.std[0] - 1) < 0.05)
        (0.04, True)
        """
        if method not in _METHODS:
            raise DataError(f"method must be 'linear' or 'monte-carlo', got {method!r}")
        value = _real_vector(fn(self.build(self.theta)))
        if method == "monte-carlo":
            vals = np.array([_real_vector(fn(m)).ravel() for m in self.sample(n, rng)])
            cov = np.atleast_2d(np.cov(vals, rowvar=False)) if len(vals) > 1 else \
                np.zeros((value.size, value.size))
            return Propagation(value, cov.reshape(value.size, value.size))
        if jacobian is not None:
            J = jacobian(self.theta) if callable(jacobian) else jacobian
            J = np.asarray(J, dtype=float).reshape(value.size, self.theta.size)
            return Propagation(value, J @ self.covariance @ J.T)
        _, G = self.scaled_jacobian(lambda m: _real_vector(fn(m)), step=step)
        return Propagation(value, G @ G.T)

    # -- reporting ----------------------------------------------------------------------
    def to_pandas(self) -> Any:
        """Parameters, std and relative std as a :class:`pandas.DataFrame` (index: names)."""
        import pandas as pd

        with np.errstate(divide="ignore", invalid="ignore"):
            rel = self.std / np.abs(self.theta)
        return pd.DataFrame({"value": self.theta, "std": self.std, "relative std": rel},
                            index=pd.Index(self.names, name="parameter"))

    def summary(self, max_rows: int = 40) -> str:
        """A text table of the parameters with their standard deviations."""
        lines = [repr(self), f"{'parameter':>14} {'value':>12} {'std':>11}"]
        for name, v, s in list(zip(self.names, self.theta, self.std))[:max_rows]:
            lines.append(f"{name:>14} {v:12.6g} {s:11.4g}")
        if self.theta.size > max_rows:
            lines.append(f"... {self.theta.size - max_rows} more (to_pandas() has all)")
        return "\n".join(lines)

    def __repr__(self) -> str:
        p = self.theta.size
        return (f"ParameterUncertainty({p} parameter{'s' if p != 1 else ''}, rank {self.dof}, "
                f"{self.method})")


# -- model-level quantities (shared by every model family) ------------------------------
def form_deferred(model: Any) -> None:
    """Form ``model``'s deferred covariance now, if it has one (see
    :class:`sysid.pem.sandwich.DeferredSandwich`): before its ``info`` is written.

    Examples
    --------
    >>> import sysid
    >>> from sysid.models.uncertainty import form_deferred
    >>> form_deferred(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))   # none: nothing
    """
    unc = getattr(model, "__dict__", {}).get("uncertainty")
    if unc is not None and unc.__dict__.get("_pending") is not None:
        _ = unc.covariance  # the first use forms it


def require(model: Any) -> ParameterUncertainty:
    """The model's :class:`ParameterUncertainty`, or a clear error when it has none."""
    unc = getattr(model, "uncertainty", None)
    if unc is None:
        info = getattr(model, "info", None) or {}
        why = info.get("identify_uncertainty")
        why = f"sysid.identify: {why}" if why else None
        none = info.get("uncertainty")
        if not why and isinstance(none, dict) and none.get("method") == "none":
            why = none.get("why")
        raise DataError(
            "this model carries no parameter uncertainty"
            + (f" ({why})" if why else
               ": estimate it with sysid.pem/ssest, a polynomial estimator, "
               "sysid.n4sid/moesp/cva (attached by default), or "
               "SubspaceEstimator.fit(..., uncertainty='bootstrap'); "
               "sysid.pem(data, model, max_iter=0) gives any state-space model the "
               "criterion's at it"))
    return unc  # type: ignore[no-any-return]


def _match(ref: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``p`` reordered to match ``ref`` (minimum total distance)."""
    from scipy.optimize import linear_sum_assignment

    if ref.size != p.size:
        raise DataError("the number of poles changed between samples; cannot match them")
    _, col = linear_sum_assignment(np.abs(ref[:, None] - p[None, :]))
    return p[col]


def _complex_std(G: np.ndarray) -> np.ndarray:
    """std of the real and imaginary parts from a complex scaled Jacobian, as one complex."""
    return (np.sqrt(np.sum(G.real**2, axis=1)) + 1j * np.sqrt(np.sum(G.imag**2, axis=1)))


def freqresp_std(model: Any, omega: Any) -> tuple[np.ndarray, np.ndarray]:
    """Frequency response and its std (complex: real/imaginary parts), first order."""
    H, G = freq_jacobian(model, omega)
    return H, _complex_std(G).reshape(H.shape)


def complex_std(model: Any, fn: Callable[[Any], Any]) -> tuple[np.ndarray, np.ndarray]:
    """A complex (or real) function of the model and its std (complex: real/imag parts)."""
    unc = require(model)
    value, G = unc.scaled_jacobian(fn)
    if np.iscomplexobj(G):
        sd = _complex_std(G)
    else:
        sd = np.sqrt(np.sum(G**2, axis=1))
    return value, sd.reshape(np.shape(value))


def response_band(model: Any, resp: Any, respond: Callable[[Any, int], Any]) -> Any:
    """``resp`` (a time response of ``model``) with ``resp.std``: the first-order standard
    deviation of each sample over the parameter uncertainty, ``respond(m, N)`` giving the
    same response of a perturbed model ``m`` over the ``N`` samples of ``resp`` (the band
    of ``step(std=True)`` and ``impulse(std=True)``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.models.uncertainty import response_band
    >>> def build(t):
    ...     return sysid.StateSpaceModel([[0.5]], [[t[0]]], [[1.0]])
    >>> m = build([1.0])
    >>> m.uncertainty = sysid.ParameterUncertainty([1.0], np.array([[0.01]]), build)
    >>> r = response_band(m, m.impulse(3), lambda p, n: p.impulse(n))
    >>> np.round(r.std[:, 0, 0], 6)
    array([0.  , 0.1 , 0.05])

    A continuous-time response (``resp.continuous``) is sampled on a grid its model chose
    (five time constants of its slowest pole): every perturbed model is evaluated on that
    same grid (``m.step(N, dt=h)``), not on its own, and a response of a perturbed model at
    other times is refused rather than differenced.
    """
    n = len(resp.t)
    t = np.asarray(resp.t, dtype=float)
    h = float(t[1] - t[0]) if n > 1 and getattr(resp, "continuous", False) else None
    h = h if h is not None and h > 0 else None

    def on_grid(m: Any) -> np.ndarray:
        kind = getattr(m, str(resp.kind), None)
        r = kind(n, dt=h) if h is not None and _takes_dt(kind) else respond(m, n)
        tm = np.asarray(r.t, dtype=float)
        if tm.shape != t.shape or not np.allclose(tm, t, rtol=1e-9, atol=0.0):
            raise DataError(
                f"the {resp.kind} response of a model drawn from the parameter covariance is "
                f"sampled at other times than the estimate's (its {resp.kind}() chooses its "
                "own grid): give the model's "
                f"{resp.kind}() a dt= keyword that fixes the sample time, as "
                "sysid.ContinuousStateSpace's does")
        return np.asarray(r.y)

    _, resp.std = complex_std(model, on_grid)
    return resp


def _takes_dt(fn: Any) -> bool:
    """Whether the callable ``fn`` takes a ``dt=`` keyword (by name or ``**kwargs``)."""
    import inspect

    if fn is None:
        return False
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == "dt" and p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)
               or p.kind == p.VAR_KEYWORD for p in params)


def _is_statespace(m: Any) -> bool:
    return all(isinstance(getattr(m, k, None), np.ndarray) for k in "ABCD") and \
        getattr(m, "dt", None) is not None


def freq_jacobian(model: Any, omega: Any) -> tuple[np.ndarray, np.ndarray]:
    """Frequency response ``H`` and its complex scaled Jacobian ``G`` (rows: ``H.ravel()``).

    For state-space models analytically, ``dH = Y dA X + dC X + Y dB + dD`` with
    ``X = (zI - A)^-1 B`` and ``Y = C (zI - A)^-1`` (one solve per frequency, whatever the
    number of parameters); otherwise by differencing ``freqresp``.
    """
    unc = require(model)
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    nominal = unc.build(unc.theta)
    if not _is_statespace(nominal):
        H, G = unc.scaled_jacobian(lambda m: m.freqresp(w))
        return H, G.astype(complex)
    A, B, C = nominal.A, nominal.B, nominal.C
    n, m, l = A.shape[0], B.shape[1], C.shape[0]
    _, J = unc.scaled_jacobian(lambda mm: np.concatenate(
        [mm.A.ravel(), mm.B.ravel(), mm.C.ravel(), mm.D.ravel()]))
    r = J.shape[1]
    cuts = np.cumsum([n * n, n * m, l * n])
    dA, dB, dC, dD = (x.T.reshape((r,) + shape) for x, shape in zip(
        np.split(J, cuts), ((n, n), (n, m), (l, n), (l, m))))
    H = nominal.freqresp(w)
    G = np.empty((w.size, l, m, r), dtype=complex)
    eye = np.eye(n)
    zs = np.exp(1j * w * nominal.dt) if nominal.dt else 1j * w  # continuous time: s = j w
    for i, z in enumerate(zs):
        if n:
            M = z * eye - A
            X = np.linalg.solve(M, B)
            Y = np.linalg.solve(M.T, C.T).T
            d = Y @ dA @ X + dC @ X + Y @ dB + dD
        else:
            d = dD.astype(complex)
        G[i] = np.moveaxis(d, 0, -1)
    return H, G.reshape(-1, r)


def bode_std(model: Any, omega: Any) -> dict[str, np.ndarray]:
    """Frequency response with the std of ``log|H|`` and of the phase (rad), first order:
    ``d log H = dH / H``."""
    H, G = freq_jacobian(model, omega)
    with np.errstate(divide="ignore", invalid="ignore"):
        R = G / H.ravel()[:, None]
    return {"H": H, "log_mag_std": np.sqrt(np.sum(R.real**2, axis=1)).reshape(H.shape),
            "phase_std": np.sqrt(np.sum(R.imag**2, axis=1)).reshape(H.shape)}


def _block_eigen(P: np.ndarray, blocks: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Eigenpairs on the range of the block-diagonal ``P`` (blocks of the sizes given, in
    order), block by block; raises when ``P`` is not positive semi-definite."""
    p = P.shape[0]
    if sum(blocks) != p or any(b < 0 for b in blocks):
        raise DataError(f"blocks {blocks} do not add up to the covariance's {p} rows")
    parts, o = [], 0
    for b in blocks:
        parts.append(np.linalg.eigh(P[o:o + b, o:o + b]) if b else (np.zeros(0),
                                                                     np.zeros((0, 0))))
        o += b
    w = np.concatenate([pw for pw, _ in parts]) if parts else np.zeros(0)
    top = float(w.max()) if w.size else 0.0
    if w.size and w.min() < -1e-8 * max(top, 1e-300):
        raise DataError("covariance is not positive semi-definite (smallest eigenvalue "
                        f"{w.min():.3g}, largest {top:.3g})")
    keep = w > 1e-13 * top if top > 0 else np.zeros(p, bool)
    V = np.zeros((p, int(keep.sum())))
    o = c = 0
    for (_, pv), b in zip(parts, blocks):
        k = keep[o:o + b]
        V[o:o + b, c:c + int(k.sum())] = pv[:, k]
        o, c = o + b, c + int(k.sum())
    # each eigenvector's sign is LAPACK's choice, which differs between builds: fixed (its
    # largest entry positive) so that a seed's Monte Carlo draws are the same on every
    # machine (a test's draw that overflowed on one machine did not on another)
    if V.size:
        V *= np.where(V[np.argmax(np.abs(V), axis=0), np.arange(V.shape[1])] < 0, -1.0, 1.0)
    return w[keep], V
