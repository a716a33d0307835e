"""ARX: ``A(q) y(t) = B(q) u(t - nk) + e(t)`` by least squares (streaming QR in Rust), with
ridge, kernel or tuned-prior regularisation and MATLAB's ``IntegrateNoise`` (ARIX); the
structure search over ARX orders is :mod:`sysid.polynomial.structure`."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _sysid
from .._checks import experiment_arrays, require_inputs_vary
from .._threads import one_blas_thread
from ..data.iodata import as_record
from ..data.offsets import check_offsets
from ..errors import DataError
from .arx_penalty import kernel_penalties, pair_penalties, penalised_fits
from .estimators import _differenced, _grid, _integrated, _names_of, _warn_diverging
from .feedthrough import check_polynomial_feedthrough, left_out
from .model import PolynomialModel
from .orders import matlab_orders
from .uncertainty import attach_uncertainty as _attach_uncertainty

__all__ = ["arx"]


@one_blas_thread
def arx(
    data: Any,
    na: Any,
    nb: Any = None,
    nk: Any = None,
    *,
    regularization: Any = 0.0,
    kernel: np.ndarray | None = None,
    integrate_noise: bool = False,
) -> PolynomialModel:
    """Least-squares (or regularised) ARX ``A(q) y(t) = B(q) u(t - nk) + e(t)``.

    Parameters
    ----------
    data : IOData
        Estimation record (several experiments are used together).
    na : int or array_like (n_outputs, n_outputs)
        Orders of ``A`` (off-diagonal entries couple outputs); or all the orders as MATLAB's
        one vector ``[na, nb, nk]`` (``nb`` and ``nk`` one per input; one row per output,
        ``na`` then one per output), with ``nb`` and ``nk`` left out
        (:func:`~sysid.polynomial.orders.matlab_orders`).
    nb, nk : int or array_like (n_outputs, n_inputs)
        Number of ``B`` coefficients and input delays (``nk`` default 1).
    regularization : float, str, (lam, R) or ArxRegularization
        * a number ``lambda``: the penalty ``lambda |M theta|^2`` (ridge when ``kernel`` is
          None); 0 is plain least squares;
        * ``"tc"``, ``"ss"``, ``"dc"`` or ``"ridge"``: a kernel prior tuned by empirical Bayes
          (:func:`sysid.arxregul`), the estimate its posterior mean and ``covariance`` its
          posterior covariance; ``info["regularization"]`` holds the tuning result;
        * ``(lam, R)``: MATLAB's ``Lambda`` and ``R``, the penalty ``lam theta^T R theta`` on
          ``theta = [a, b]``, the polynomials' coefficients (``parameters``), ``R`` as many
          rows and columns as that output's equation has parameters; one pair for every
          output, or a sequence of one pair per output;
        * an :class:`~sysid.polynomial.arxregul.ArxRegularization` from :func:`sysid.arxregul`.
    kernel : ndarray, optional
        With a number ``regularization``: the factor ``M`` (for example the inverse Cholesky
        factor of a kernel) of the penalty ``lambda |M theta|^2`` on ``theta = [a, b]`` (as
        ``(lam, R)``, ``R = M^T M``); as many columns as each output's equation has
        parameters.
    integrate_noise : bool
        MATLAB's ``IntegrateNoise`` (ARIX): ``A y = B u + e / (1 - q^-1)``, a disturbance
        that drifts (a random walk, a slowly moving offset). Fitted by least squares on the
        differenced record (each experiment's first sample dropped); the model's ``D(q) = 1 -
        q^-1`` makes its predictions follow the drift; its simulation is the same ``B/A``.

    Returns
    -------
    PolynomialModel
        With ``info`` (loss per output) and ``covariance`` per output.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((300, 1)); y = np.zeros((300, 1))
    >>> for t in range(1, 300): y[t] = 0.5 * y[t - 1] + u[t - 1]
    >>> m = sysid.polynomial.arx.arx(sysid.IOData(u, y, 1.0), 1, 1, 1)
    >>> np.round(m.a[0][0], 8).tolist(), np.round(m.b[0][0], 8).tolist()
    ([-0.5], [1.0])
    >>> sysid.arx(sysid.IOData(u, y, 1.0), [1, 1, 1]).a == m.a  # MATLAB's [na nb nk]
    True
    """
    data = as_record(data)  # a (u, y) pair, as ssest and compare take
    if integrate_noise is not False:  # ARIX: least squares on the differenced record
        m = arx(_differenced(data, integrate_noise), na, nb, nk,
                regularization=regularization, kernel=kernel)
        return _integrated(m)
    exps = experiment_arrays(data)
    na, nb, nk = matlab_orders("arx", data, na, nb=nb, nk=nk)
    off = check_offsets(data)  # then its warning explains a poor simulation too
    require_inputs_vary(exps, "arx", getattr(data, "input_names", None))
    require_inputs_vary(exps, "arx", getattr(data, "output_names", None), side=1)
    ny, nu = exps[0][1].shape[1], exps[0][0].shape[1]
    na_g, nb_g, nk_g = _grid(na, ny, ny, "na"), _grid(nb, ny, nu, "nb"), _grid(nk, ny, nu, "nk")
    if isinstance(regularization, str) or hasattr(regularization, "prior"):
        return _warn_diverging(_arx_posterior(data, na_g, nb_g, nk_g, regularization, kernel),
                               "arx", None if off else exps)
    if isinstance(regularization, (tuple, list)):
        if kernel is not None:
            raise DataError("kernel= goes with a numeric regularization; a (lam, R) pair "
                            "carries R")
        lams, factors = pair_penalties(regularization, na_g, nb_g)
        m = _arx_model(data, penalised_fits(exps, na_g, nb_g, nk_g, lams, factors), nk_g)
        m.info["regularization"] = {"lam": lams}
        return _warn_diverging(m, "arx", None if off else exps)
    if isinstance(regularization, bool) or not isinstance(regularization, (int, float, np.number)):
        raise DataError("regularization must be a number, a kernel name ('tc', 'ss', 'dc', "
                        f"'ridge'), a (lam, R) pair or an ArxRegularization, got "
                        f"{type(regularization).__name__}")
    if not (regularization >= 0 and np.isfinite(regularization)):
        raise DataError(f"regularization must be a finite number >= 0, got {regularization}")
    if kernel is not None:  # lam |M theta|^2 on theta = [a, b], as a (lam, R) pair
        lams, factors = kernel_penalties(float(regularization), kernel, na_g, nb_g)
        fits = penalised_fits(exps, na_g, nb_g, nk_g, lams, factors)
    else:  # ridge: lam |theta|^2, the same on [-a, b]
        fits = _sysid.arx_fit(exps, na_g, nb_g, nk_g, float(regularization), None)
    m = _arx_model(data, fits, nk_g)
    ft = check_polynomial_feedthrough(exps, "arx", [max([*na_g[i], *nb_g[i]]) for i in range(ny)],
                                      nb_g, nk_g)
    m.info.update({} if ft is None else {"feedthrough_check": ft})
    return _warn_diverging(m, "arx", None if off or left_out(ft) else exps)


def _arx_model(data: Any, fits: list[Any], nk_g: list[list[int]]) -> PolynomialModel:
    model = PolynomialModel(
        a=[[np.asarray(x) for x in f["a"]] for f in fits],
        b=[[np.asarray(x) for x in f["b"]] for f in fits],
        nk=nk_g,
        dt=data.dt,
        noise_variance=[f["loss"] for f in fits],
    )
    _names_of(model, data)
    model.info = {"method": "arx", "loss": [f["loss"] for f in fits]}
    model.covariance = [f["covariance"] if "covariance" in f else  # type: ignore[attr-defined]
                        f["loss"] * f["unscaled_cov"] for f in fits]
    model.parameters = [f["theta"] for f in fits]  # type: ignore[attr-defined]
    _attach_uncertainty(model, model.covariance, "arx",  # type: ignore[attr-defined]
                        "posterior" if "covariance" in fits[0] else "least-squares")
    return model


def _arx_posterior(data: Any, na_g: Any, nb_g: Any, nk_g: Any, reg: Any,
                   kernel: Any) -> PolynomialModel:
    """ARX as the posterior mean of a tuned kernel prior (:mod:`.arxregul`)."""
    from .arxregul import arxregul, regularized_fits

    if kernel is not None:
        raise DataError("kernel= goes with a numeric regularization, not with a kernel name")
    if isinstance(reg, str):
        reg = arxregul(data, na_g, nb_g, nk_g, reg)
    ny = len(na_g)
    fits = []
    for i, f in enumerate(regularized_fits(data, na_g, nb_g, nk_g, reg)):
        th, cov = np.array(f["theta"]), np.array(f["cov"])
        na_tot = sum(na_g[i])
        sign = np.r_[-np.ones(na_tot), np.ones(th.size - na_tot)]
        th *= sign
        a, o = [], 0
        for k in range(ny):
            a.append(th[o:o + na_g[i][k]])
            o += na_g[i][k]
        b = []
        for n in nb_g[i]:
            b.append(th[o:o + n])
            o += n
        fits.append({"a": a, "b": b, "theta": th, "loss": f["loss"],
                     "covariance": sign[:, None] * cov * sign[None, :]})
    model = _arx_model(data, fits, nk_g)
    model.info["method"] = f"arx ({reg.kernel} regularised)"
    model.info["regularization"] = reg
    return model
