"""Regularised ARX (MATLAB's ``arxRegul``): kernel priors tuned by empirical Bayes.

Output ``i``'s ARX equation is the regression ``y = Phi theta + e``, ``e ~ N(0, sigma^2 I)``.
With the Gaussian prior ``theta ~ N(0, P(eta))`` the output is ``y ~ N(0, Phi P Phi^T +
sigma^2 I)``; the hyper-parameters ``eta`` maximise this marginal likelihood (empirical Bayes,
Chen, Ohlsson and Ljung 2012) and the estimate is the posterior mean
``theta = (Phi^T Phi + sigma^2 P^-1)^-1 Phi^T y``, MATLAB's ``lambda theta^T R theta`` penalty
with ``lambda = sigma^2`` and ``R = P^-1``.

Everything is computed from the compressed regression of the one streaming pass ARX uses
(``sysid-core``'s ``ArxCompressor::output_summary``): the triangular ``[[R1, r], [0, rho]]``
with ``R1^T R1 = Phi^T Phi``, ``R1^T r = Phi^T y``, ``|r|^2 + rho^2 = y^T y``, of size
``(p + 1) x (p + 1)`` whatever the record length. With ``S = sigma^2 I + R1 P R1^T`` (``p x p``),

    -2 log p(y) - N log(2 pi) = rho^2 / sigma^2 + (N - p) log sigma^2 + r^T S^-1 r + log det S

and, with ``a = S^-1 r``, ``d/d eta_k = sum(G * dP/d eta_k)``, ``G = R1^T (S^-1 - a a^T) R1``.
No inverse of ``P`` is formed (TC and SS kernels are badly conditioned for long blocks). The
value and gradient are computed in Rust (``sysid_core::polynomial::regul``, sequential faer
on ``p x p`` matrices; threaded BLAS on such small matrices costs more than it saves).

The prior is block diagonal: one block per polynomial of the equation (each ``A_ik`` and each
``B_ij``), each with its own hyper-parameters (the choice of Chen et al. for ARX), indices
``k, j = 1..n`` within a block:

* ``"tc"``: ``c lambda^max(k, j)``;
* ``"ss"`` (stable spline): ``c (lambda^(k + j + max(k, j)) / 2 - lambda^(3 max(k, j)) / 6)``;
* ``"dc"``: ``c lambda^((k + j) / 2) rho^|k - j|``;
* ``"ridge"``: ``c I`` over the whole equation (one hyper-parameter).

The few hyper-parameters (2 or 3 per block) are tuned with SciPy's L-BFGS-B on ``log c``,
``logit lambda``, ``atanh rho`` (and ``log sigma^2`` with ``noise_variance="ml"``) with the
analytic gradient, started from the best point of a coarse grid: a smooth, non-least-squares
objective on small matrices, which the project's Gauss-Newton search (for sums of squares over
samples) does not fit, and whose cost is independent of ``N``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import optimize

from .. import _sysid
from .._checks import as_int_grid, experiment_arrays, require_inputs_vary
from .._display import HTMLResult
from ..errors import DataError, NumericalError
from .orders import matlab_orders

KERNELS = ("tc", "ss", "dc", "ridge")
_NHYP = {"tc": 2, "ss": 2, "dc": 3, "ridge": 1}


# -- kernels --------------------------------------------------------------------------------
def kernel(name: str, n: int, hyper: Any) -> np.ndarray:
    """The ``n x n`` prior covariance of one block for hyper-parameters ``hyper``
    (``(c, lambda)`` for TC and SS, ``(c, lambda, rho)`` for DC, ``(c,)`` for ridge).

    Examples
    --------
    >>> from sysid.polynomial.arxregul import kernel
    >>> kernel("tc", 3, (2.0, 0.5)).tolist()
    [[1.0, 0.5, 0.25], [0.5, 0.5, 0.25], [0.25, 0.25, 0.25]]
    """
    name = _check_kernel(name)
    h = np.asarray(hyper, float).ravel()
    if h.size != _NHYP[name]:
        raise DataError(f"kernel {name!r} takes {_NHYP[name]} hyper-parameter(s), got {h.size}")
    return _kernel(name, n, _to_x(name, h))[0]


def _check_kernel(name: Any) -> str:
    if not isinstance(name, str) or name.lower() not in KERNELS:
        raise DataError(f"unknown regularization kernel {name!r}; use one of "
                        f"{', '.join(repr(k) for k in KERNELS)} (or a number for a fixed ridge "
                        "weight, or a (lam, R) pair)")
    return name.lower()


def _to_x(name: str, h: np.ndarray) -> np.ndarray:
    """Hyper-parameters -> unconstrained coordinates (log c, logit lambda, atanh rho)."""
    if h[0] <= 0 or not np.isfinite(h[0]):
        raise DataError(f"the kernel scale c must be positive, got {h[0]}")
    x = [np.log(h[0])]
    if name != "ridge":
        if not 0 < h[1] < 1:
            raise DataError(f"the kernel decay lambda must lie in (0, 1), got {h[1]}")
        x.append(np.log(h[1] / (1 - h[1])))
    if name == "dc":
        if not -1 < h[2] < 1:
            raise DataError(f"the DC correlation rho must lie in (-1, 1), got {h[2]}")
        x.append(np.arctanh(h[2]))
    return np.array(x)


def _from_x(name: str, x: np.ndarray) -> np.ndarray:
    h = [np.exp(x[0])]
    if name != "ridge":
        h.append(1.0 / (1.0 + np.exp(-x[1])))
    if name == "dc":
        h.append(np.tanh(x[2]))
    return np.array(h)


def _kernel(name: str, n: int, x: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """Block ``P`` and its derivatives with respect to the unconstrained coordinates ``x``."""
    c = np.exp(x[0])
    if name == "ridge":
        P = c * np.eye(n)
        return P, [P]
    lam = 1.0 / (1.0 + np.exp(-x[1]))
    dlam = lam * (1.0 - lam)
    k = np.arange(1, n + 1, dtype=float)
    K, J = np.meshgrid(k, k, indexing="ij")
    M = np.maximum(K, J)
    if name == "tc":
        base = lam ** M
        dbase = M * lam ** (M - 1)
        P = c * base
        return P, [P, c * dbase * dlam]
    if name == "ss":
        e1, e3 = K + J + M, 3 * M
        base = lam ** e1 / 2 - lam ** e3 / 6
        dbase = e1 * lam ** (e1 - 1) / 2 - e3 * lam ** (e3 - 1) / 6
        P = c * base
        return P, [P, c * dbase * dlam]
    rho = np.tanh(x[2])
    D = np.abs(K - J)
    rp = rho ** D
    drp = np.where(D > 0, D * rho ** np.maximum(D - 1, 0), 0.0)
    half = lam ** ((K + J) / 2)
    P = c * half * rp
    dP_lam = c * (K + J) / 2 * lam ** ((K + J) / 2 - 1) * rp * dlam
    dP_rho = c * half * drp * (1 - rho * rho)
    return P, [P, dP_lam, dP_rho]


# -- marginal likelihood ----------------------------------------------------------------------
def marginal_likelihood(summary: np.ndarray, n_rows: int, prior: np.ndarray,
                        sigma2: float, dprior: list[np.ndarray] | None = None
                        ) -> tuple[float, np.ndarray, float]:
    """``-2 log p(y) - N log(2 pi)`` of the regression summarised by ``summary`` under the
    prior ``theta ~ N(0, prior)`` and noise variance ``sigma2``, with its derivatives with
    respect to the parameters of ``dprior`` (``d prior / d eta_k``) and to ``sigma2``.

    Parameters
    ----------
    summary : ndarray (p + 1, p + 1)
        Upper-triangular factor of ``[Phi y]`` (any orthogonal compression of the rows).
    n_rows : int
        Number of regression rows ``N``.
    prior : ndarray (p, p)
    sigma2 : float
    dprior : list of ndarray (p, p), optional

    Returns
    -------
    value, gradient (one entry per ``dprior``), derivative with respect to ``sigma2``

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.polynomial.arxregul import marginal_likelihood
    >>> rng = np.random.default_rng(0)
    >>> Phi, y = rng.standard_normal((20, 2)), rng.standard_normal(20)
    >>> R = np.linalg.qr(np.column_stack([Phi, y]), mode="r")
    >>> Sigma = Phi @ Phi.T + 0.5 * np.eye(20)           # prior I, sigma^2 = 0.5
    >>> dense = y @ np.linalg.solve(Sigma, y) + np.linalg.slogdet(Sigma)[1]
    >>> bool(np.isclose(marginal_likelihood(R, 20, np.eye(2), 0.5)[0], dense))
    True
    """
    v, g, ds = _sysid.arx_marginal_likelihood(
        np.ascontiguousarray(summary, float), int(n_rows), np.ascontiguousarray(prior, float),
        [np.ascontiguousarray(d, float) for d in (dprior or [])], float(sigma2),
        dprior is not None)
    return float(v), np.asarray(g), (float(ds) if dprior is not None else 0.0)


# -- tuning -----------------------------------------------------------------------------------
def _block_sizes(na_row: list[int], nb_row: list[int]) -> list[tuple[str, int]]:
    """(label, size) of the polynomial blocks of one equation, in the regression's order."""
    out = [(f"a[{k}]", n) for k, n in enumerate(na_row) if n > 0]
    return out + [(f"b[{j}]", n) for j, n in enumerate(nb_row) if n > 0]


class _Prior:
    """Block-diagonal prior of one equation as a function of the stacked coordinates."""

    def __init__(self, name: str, sizes: list[int]) -> None:
        self.name = name
        self.sizes = [sum(sizes)] if name == "ridge" else list(sizes)
        self.nh = _NHYP[name]
        self.p = sum(sizes)

    def __call__(self, x: np.ndarray, grad: bool = True
                 ) -> tuple[np.ndarray, list[np.ndarray]]:
        P = np.zeros((self.p, self.p))
        dP: list[np.ndarray] = []
        o = 0
        for b, n in enumerate(self.sizes):
            Pb, dPb = _kernel(self.name, n, x[b * self.nh:(b + 1) * self.nh])
            P[o:o + n, o:o + n] = Pb
            for d in (dPb if grad else []):
                full = np.zeros((self.p, self.p))
                full[o:o + n, o:o + n] = d
                dP.append(full)
            o += n
        return P, dP


def _tune(summary: np.ndarray, n_rows: int, prior: _Prior, noise: str
          ) -> tuple[np.ndarray, float, float, dict[str, Any]]:
    """Coordinates, sigma^2, value and optimiser info maximising the marginal likelihood."""
    p = prior.p
    r, rho = summary[:p, p], summary[p, p]
    ysq = float(r @ r + rho * rho)
    s2_ls = max(rho * rho / (n_rows - p), 1e-12 * ysq / n_rows, np.finfo(float).tiny)
    theta_ls = _sysid.arx_regularized_solve(np.ascontiguousarray(summary, float), np.eye(p),
                                            0.0)[0]  # least squares (pseudo-inverse)
    nh, nb = prior.nh, len(prior.sizes)
    c0, o = [], 0
    for n in prior.sizes:
        c0.append(max(float(np.mean(theta_ls[o:o + n] ** 2)), 1e-12 * ysq / n_rows, 1e-300))
        o += n

    def fun(z: np.ndarray, grad: bool = True) -> tuple[float, np.ndarray]:
        x, s2 = (z[:-1], np.exp(z[-1])) if noise == "ml" else (z, s2_ls)
        P, dP = prior(x, grad)
        v, g, ds = marginal_likelihood(summary, n_rows, P, s2, dP if grad else None)
        if not np.isfinite(v):
            return 1e300, np.zeros_like(z)
        return v, (np.r_[g, ds * s2] if noise == "ml" else g)

    def start(scale: float, lam: float, rho_: float = 0.0) -> np.ndarray:
        x = np.concatenate([
            _to_x(prior.name, np.array([c * scale, lam, rho_][:nh])) for c in c0])
        return np.r_[x, np.log(s2_ls)] if noise == "ml" else x

    # Coarse grid: every block's scale c0 times one factor, decays and correlations shared.
    scales = 10.0 ** np.linspace(-4, 4, 17)
    shapes = [(lam, rho_) for lam in ((0.5,) if prior.name == "ridge" else
                                      (0.5, 0.8, 0.9, 0.95))
              for rho_ in ((0.0,) if prior.name != "dc" else (0.3, 0.9))]
    best = (np.inf, 1.0, shapes[0])
    for lam, rho_ in shapes:
        for sc in scales:
            v = fun(start(sc, lam, rho_), False)[0]
            if v < best[0]:
                best = (v, float(sc), (lam, rho_))
    z0 = start(best[1], *best[2])
    best_v = fun(z0, False)[0]
    lo = np.concatenate([[np.log(c) - 30, -9.0, -4.0][:nh] for c in c0])
    hi = np.concatenate([[np.log(c) + 30, 9.0, 4.0][:nh] for c in c0])
    if noise == "ml":
        lo, hi = np.r_[lo, np.log(s2_ls) - 12], np.r_[hi, np.log(s2_ls) + 12]
    z0 = np.clip(z0, lo, hi)
    res = optimize.minimize(fun, z0, jac=True, method="L-BFGS-B",
                            bounds=list(zip(lo, hi)), options={"maxiter": 500})
    z = res.x if res.fun <= best_v else z0
    value = min(float(res.fun), best_v)
    if not np.isfinite(value) or value >= 1e300:
        raise NumericalError("arxregul: the marginal likelihood is not finite at any start "
                             "point; check the data (constant or non-finite signals?)")
    x, s2 = (z[:-1], float(np.exp(z[-1]))) if noise == "ml" else (z, s2_ls)
    info = {"iterations": int(res.nit), "evaluations": int(res.nfev),
            "stop": str(res.message), "success": bool(res.success),
            "grid_points": len(shapes) * scales.size, "n_blocks": nb}
    return x, s2, value, info


@dataclass
class ArxRegularization(HTMLResult):
    """Tuned regularisation of an ARX structure (the result of :func:`arxregul`).

    Per output ``i``: ``lam[i]`` and ``R[i]`` are MATLAB's ``Lambda`` and ``R`` (the penalty
    ``lam theta^T R theta`` on ``theta = [a, b]``, the model's ``parameters``, ``lam =
    sigma^2``, ``R = P^-1`` computed by a pseudo-inverse), ``prior[i]`` is the prior
    covariance ``P`` of that ``theta`` itself (what the fit uses: it needs no
    inverse), ``hyperparameters[i]`` one dict per block, ``neg_log_likelihood[i]`` the value
    of ``-log p(y)`` at the optimum.
    """

    kernel: str
    orders: tuple[list[list[int]], list[list[int]], list[list[int]]]
    lam: np.ndarray
    prior: list[np.ndarray]
    hyperparameters: list[list[dict[str, Any]]]
    neg_log_likelihood: np.ndarray
    info: list[dict[str, Any]] = field(default_factory=list)

    @property
    def R(self) -> list[np.ndarray]:  # noqa: N802 (MATLAB's name)
        """MATLAB's weighting ``R = P^-1`` per output (pseudo-inverse; may be badly
        conditioned for TC/SS kernels with fast decay: prefer :attr:`prior`)."""
        return [np.linalg.pinv(P, hermitian=True) for P in self.prior]

    def __repr__(self) -> str:
        lines = [f"ArxRegularization(kernel={self.kernel!r}, outputs={len(self.prior)})"]
        for i, blocks in enumerate(self.hyperparameters):
            hyp = ", ".join(
                f"{b['block']}: " + " ".join(f"{k}={v:.3g}" for k, v in b.items()
                                            if k not in ("block", "size"))
                for b in blocks)
            lines.append(f"  y{i}: lam={self.lam[i]:.4g}, -log p(y)="
                         f"{self.neg_log_likelihood[i]:.6g}; {hyp}")
        return "\n".join(lines)

    def summary(self) -> str:
        """Text table of the hyper-parameters (same as ``repr``)."""
        return repr(self)

    def to_pandas(self) -> Any:
        """One row per output and block: hyper-parameters, ``lam`` and ``-log p(y)``."""
        import pandas as pd

        rows = [dict(output=i, **b, lam=self.lam[i],
                     neg_log_likelihood=self.neg_log_likelihood[i])
                for i, blocks in enumerate(self.hyperparameters) for b in blocks]
        return pd.DataFrame(rows)

    def plot(self, ax: Any = None) -> Any:
        """Prior standard deviation ``sqrt(diag P)`` of every coefficient, per output."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots()
        for i, P in enumerate(self.prior):
            ax.semilogy(np.sqrt(np.clip(np.diag(P), 1e-300, None)), "o-", label=f"y{i}")
        ax.set_xlabel("coefficient (A blocks, then B blocks)")
        ax.set_ylabel("prior std")
        ax.set_title(f"{self.kernel.upper()} prior")
        ax.legend()
        return ax


def summaries(data: Any, na: Any, nb: Any, nk: Any
              ) -> tuple[list[tuple[np.ndarray, int]], tuple[list[list[int]], ...]]:
    """Per output, the compressed regression ``(summary, n_rows)`` (one streaming pass in
    Rust) and the orders as ``(ny x ny, ny x nu, ny x nu)`` grids."""
    exps = experiment_arrays(data)
    ny, nu = exps[0][1].shape[1], exps[0][0].shape[1]
    g = (as_int_grid(na, (ny, ny), "na"), as_int_grid(nb, (ny, nu), "nb"),
         as_int_grid(nk, (ny, nu), "nk"))
    return [(np.asarray(s), int(n)) for s, n in _sysid.arx_summary(exps, *g)], g


def arxregul(data: Any, na: Any, nb: Any = None, nk: Any = None, kernel: str = "tc", *,
             noise_variance: str = "ls") -> ArxRegularization:
    """Regularisation constants of an ARX structure by empirical Bayes (MATLAB's
    ``arxRegul``).

    Parameters
    ----------
    data : IOData
        Estimation record (several experiments are used together).
    na, nb, nk : int or array_like
        The ARX orders, as for :func:`sysid.arx` (``nk`` default 1); or MATLAB's one vector
        ``[na, nb, nk]`` as ``na``, then the kernel may follow it as MATLAB's
        ``arxRegul(data, orders, kernel)``.
    kernel : {"tc", "ss", "dc", "ridge"}
        Prior covariance of each polynomial block (see the module docstring).
    noise_variance : {"ls", "ml"}
        ``"ls"``: ``sigma^2`` fixed at the least-squares residual variance of the structure
        (as MATLAB); ``"ml"``: tuned with the kernel hyper-parameters.

    Returns
    -------
    ArxRegularization
        Pass it as ``sysid.arx(data, na, nb, nk, regularization=reg)``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(200)
    >>> y = signal.lfilter([0, 1.0], [1, -1.6, 0.9], u) + 0.5 * rng.standard_normal(200)
    >>> d = sysid.IOData(u[:, None], y[:, None], 1.0)
    >>> reg = sysid.arxregul(d, 0, 40, 1, "tc")          # a 40-tap FIR model
    >>> bool(0.8 < reg.hyperparameters[0][0]["lambda"] < 1)
    True
    >>> same = sysid.arxregul(d, [0, 40, 1], "tc")     # MATLAB's arxRegul(data, orders, kernel)
    >>> same.hyperparameters == reg.hyperparameters
    True
    """
    if isinstance(nb, str) and nk is None and kernel == "tc":  # arxregul(data, orders, kernel)
        kernel, nb = nb, None
    name = _check_kernel(kernel)
    if noise_variance not in ("ls", "ml"):
        raise DataError(f"noise_variance must be 'ls' or 'ml', got {noise_variance!r}")
    exps = experiment_arrays(data)  # a constant channel first, as arx (else a NaN scale)
    require_inputs_vary(exps, "arxregul", getattr(data, "input_names", None))
    require_inputs_vary(exps, "arxregul", getattr(data, "output_names", None), side=1)
    na, nb, nk = matlab_orders("arxregul", data, na, nb=nb, nk=nk)
    sums, g = summaries(data, na, nb, nk)
    lam, priors, hyps, nll, infos = [], [], [], [], []
    for i, (s, n) in enumerate(sums):
        blocks = _block_sizes(g[0][i], g[1][i])
        if not blocks:
            raise DataError(f"output {i} has no parameters to regularise (na = nb = 0)")
        prior = _Prior(name, [b[1] for b in blocks])
        x, s2, value, info = _tune(s, n, prior, noise_variance)
        P, _ = prior(x)
        labels = [("all", prior.p)] if name == "ridge" else blocks
        keys = ("c", "lambda", "rho")[:prior.nh]
        hyps.append([{"block": lb, "size": sz,
                      **dict(zip(keys, _from_x(name, x[b * prior.nh:(b + 1) * prior.nh])))}
                     for b, (lb, sz) in enumerate(labels)])
        lam.append(s2)
        priors.append(P)
        nll.append(0.5 * (value + n * np.log(2 * np.pi)))
        infos.append(info)
    return ArxRegularization(name, g, np.array(lam), priors, hyps, np.array(nll), infos)


def regularized_fits(data: Any, na: Any, nb: Any, nk: Any, reg: ArxRegularization
                     ) -> list[dict[str, Any]]:
    """Per output: posterior mean ``theta = P R1^T (lam I + R1 P R1^T)^-1 r`` (regression
    signs), residual mean square and posterior covariance ``P - P R1^T S^-1 R1 P``
    (``S = lam I + R1 P R1^T``), from the summaries, through the SVD of ``R1 P^(1/2)`` (in
    Rust: ``sysid_core::polynomial::regul::regularized_solve``).

    ``reg.prior`` is the prior covariance of MATLAB's ``theta = [a, b]`` (``reg.R`` its
    ``R``); the regression's unknowns are ``[-a, b]``, so its ``A`` rows and columns are
    negated first: a change only where the prior couples ``A`` and ``B`` coefficients (the
    tuned kernels are block diagonal, and their prior is the same in both)."""
    sums, g = summaries(data, na, nb, nk)
    if [list(map(list, x)) for x in g] != [list(map(list, x)) for x in reg.orders]:
        raise DataError(f"the regularisation was tuned for orders {reg.orders}, not {g}; "
                        "call arxregul with the same na, nb, nk")
    out = []
    for i, (s, n) in enumerate(sums):
        P, lam = np.asarray(reg.prior[i], float), float(reg.lam[i])
        sign = np.r_[-np.ones(sum(g[0][i])), np.ones(P.shape[0] - sum(g[0][i]))]
        if np.any(P[sign < 0][:, sign > 0]):  # A-B cross terms: the prior of [-a, b]
            P = sign[:, None] * P * sign[None, :]
        theta, cov, rss = _sysid.arx_regularized_solve(np.ascontiguousarray(s, float),
                                                       np.ascontiguousarray(P, float), lam)
        out.append({"theta": theta, "loss": rss / n, "cov": np.asarray(cov),
                    "n_rows": n})
    return out
