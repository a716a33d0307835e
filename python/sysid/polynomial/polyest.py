"""The general polynomial model ``A(q) y = B(q)/F(q) u(t-nk) + C(q)/D(q) e`` (MATLAB's
``polyest``) and the refinement of any polynomial model by prediction-error minimisation
(MATLAB's ``pem(data, idpoly)``).

Both run the search :func:`sysid.armax`, :func:`sysid.oe` and :func:`sysid.bj` share (per
output, the shared Gauss-Newton optimiser of ``sysid-core`` on the one-step prediction
errors; ``C``, ``D`` and ``F`` kept stable). ``polyest`` starts from the default start of
that search (an ARX fit; Steiglitz-McBride for ``B/F``), and without ``A`` also from a
subspace fit, keeping the lower criterion (as ``oe`` and ``bj``); ``pem(data, model)``
starts from the model and keeps its structure (its orders and delays).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .._threads import one_blas_thread
from ..data.iodata import as_record
from ..errors import DataError
from ..validation.output_error import output_error
from .estimators import _pem, _warn_diverging
from .initial import check as _check_initial
from .model import PolynomialModel
from .orders import matlab_orders

__all__ = ["polyest", "pem_polynomial"]


def _output_error(a: dict[str, Any]) -> bool:
    """``na = nc = nd = 0``: the output-error structure, whose fit
    :mod:`sysid.validation.output_error` checks for feedback (orders it cannot read: no)."""
    try:
        na, _, nc, nd, _, _ = matlab_orders("polyest", as_record(a["data"]), a["na"], nb=a["nb"],
                                            nc=a["nc"], nd=a["nd"], nf=a["nf"], nk=a["nk"])
    except Exception:  # noqa: BLE001 - polyest's own error follows
        return False
    return all(int(np.max(np.asarray(x, dtype=float), initial=0)) == 0 for x in (na, nc, nd))


@output_error("polyest", when=_output_error)
@one_blas_thread
def polyest(
    data: Any,
    na: Any,
    nb: Any = None,
    nc: Any = None,
    nd: Any = None,
    nf: Any = None,
    nk: Any = None,
    *,
    max_iter: int = 100,
    progress: bool | None | Callable[..., Any] = None,
    init: PolynomialModel | None = None,
    initial_condition: str = "auto",
) -> PolynomialModel:
    """The general polynomial model ``A y = B/F u(t-nk) + C/D e`` (MATLAB's ``polyest``).

    Every structure of the family is one choice of orders: ARX (``nc = nd = nf = 0``),
    ARMAX (``nd = nf = 0``), output error (``na = nc = nd = 0``), Box-Jenkins (``na = 0``),
    and the ones between (``A`` with ``F``, ``D`` with ``A``, ...). The orders may be given
    as MATLAB's one vector, ``polyest(data, [na, nb, nc, nd, nf, nk])`` (``nb``, ``nf`` and
    ``nk`` one per input; :func:`~sysid.polynomial.orders.matlab_orders`); ``nk`` defaults
    to 1.

    Parameters
    ----------
    data : IOData or (u, y)
        Estimation record with inputs (remove offsets first; a large mean warns).
    na, nc, nd : int or sequence of int (one per output)
        Orders of ``A``, ``C`` and ``D`` (``A`` diagonal for several outputs: one equation
        per output).
    nb, nf, nk : int or array_like (outputs x inputs)
        Orders of ``B`` (coefficients) and ``F``, and the delays in samples.
    max_iter : int
        Gauss-Newton iterations per output.
    progress : bool or callable, optional
        Progress display (see :mod:`sysid._progress`).
    init : PolynomialModel, optional
        Start from this model (its polynomials cut or padded with zeros to the orders
        given; unstable ``C``, ``D`` or ``F`` roots reflected into the unit circle,
        ``info["start_stabilized"]``), as MATLAB's ``polyest(data, init_sys)``.
    initial_condition : {"auto", "zero", "estimate"}
        MATLAB's ``InitialCondition``: from rest (``"zero"``), each experiment's initial
        state estimated with the parameters (``"estimate"``; the covariance the marginal
        one), or ``"auto"`` (default): estimated when that lowers the criterion beyond what
        fitting noise would (:mod:`sysid.polynomial.initial`). ``"backcast"`` is not
        offered. ``info["initial_condition"]`` and ``info["initial_state"]`` record it.

    Returns
    -------
    PolynomialModel
        ``info``: iterations, cost, stop per output and the start (``info["start"]``);
        ``uncertainty`` the Gauss-Newton parameter covariance.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(0)
    >>> u, e = rng.standard_normal(4000), 0.1 * rng.standard_normal(4000)
    >>> x = lfilter([0.0, 1.0, 0.5], [1.0, -0.6], u)          # B/F u(t-1)
    >>> v = lfilter([1.0, 0.4], [1.0, -0.3], e)               # C/D e
    >>> y = lfilter([1.0], [1.0, -0.5], x + v)                # A = 1 - 0.5 q^-1
    >>> m = sysid.polyest(sysid.IOData(u, y, 1.0), [1, 2, 1, 1, 1, 1])
    >>> np.round([m.a[0][0][0], m.f[0][0][0], m.c[0][0], m.d[0][0]], 1).tolist()
    [-0.5, -0.6, 0.4, -0.3]
    """
    data = as_record(data)
    _check_initial(initial_condition)
    na, nb, nc, nd, nf, nk = matlab_orders("polyest", data, na, nb=nb, nc=nc, nd=nd, nf=nf,
                                           nk=nk)
    if init is not None:
        m = _pem(data, na, nb, nc, nd, nf, nk, "polyest", max_iter, progress, init,
                 initial_condition=initial_condition)
        m.info["start"] = "init"
        return _warn_diverging(m, "polyest")
    # without A, a subspace fit of B/F is a second start (as oe and bj): the ARX-based
    # start of B/F can stay far from the minimum on a slow plant
    second = bool(np.all(np.asarray(na) == 0)) and bool(np.any(np.asarray(nf) > 0))
    m = _pem(data, na, nb, nc, nd, nf, nk, "polyest", max_iter, progress, second=second,
             initial_condition=initial_condition)
    if not second:
        m.info["start"] = "ARX" if not np.any(np.asarray(nf) > 0) else "Steiglitz-McBride"
    return _warn_diverging(m, "polyest")


def _orders(model: PolynomialModel) -> tuple[list[Any], ...]:
    """``(na, nb, nc, nd, nf, nk)`` of ``model``: ``na`` as the ``(outputs, outputs)`` grid of
    its ``A``'s orders, the rest as :func:`polyest` takes them."""
    ny, nu = model.n_outputs, model.n_inputs
    na = [[len(model.a[i][k]) for k in range(ny)] for i in range(ny)]
    nb = [[len(model.b[i][j]) for j in range(nu)] for i in range(ny)]
    nc = [len(model.c[i]) for i in range(ny)]
    nd = [len(model.d[i]) for i in range(ny)]
    nf = [[len(model.f[i][j]) for j in range(nu)] for i in range(ny)]
    nk = [[int(model.nk[i, j]) for j in range(nu)] for i in range(ny)]
    return na, nb, nc, nd, nf, nk


def pem_polynomial(data: Any, model: PolynomialModel, *, max_iter: int,
                   progress: bool | None | Callable[..., Any],
                   initial_condition: str = "auto") -> PolynomialModel:
    """:func:`sysid.pem` given a polynomial model (MATLAB's ``pem(data, idpoly)``): the
    prediction-error search from ``model`` in its own structure (orders and delays kept),
    its initial conditions by ``initial_condition`` (:mod:`sysid.polynomial.initial`, as
    :func:`polyest`); an ARX model (no ``C``, ``D``, ``F``; a coupled multi-output ``A``
    too) is fitted again by least squares, its prediction-error minimum (over the samples
    whose lags are all measured: not from rest, whatever ``initial_condition``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(1)
    >>> u = rng.standard_normal(2000); e = 0.1 * rng.standard_normal(2000)
    >>> y = np.zeros(2000)
    >>> for t in range(1, 2000): y[t] = 0.7 * y[t-1] + u[t-1] + e[t] + 0.5 * e[t-1]
    >>> d = sysid.IOData(u, y, 1.0)
    >>> start = sysid.armax(d, 1, 1, 1, 1, max_iter=1)
    >>> m = sysid.pem(d, start)
    >>> round(float(m.c[0][0]), 1), m.info["start"]
    (0.5, 'init')
    """
    if not model.n_inputs:
        raise DataError("pem refines input-output polynomial models; for a time series "
                        "(no inputs) use sysid.arma or sysid.ar")
    if getattr(data, "dt", None) and model.dt and not np.isclose(data.dt, model.dt):
        raise DataError(f"the model is sampled every {model.dt} s but the data every "
                        f"{data.dt} s: resample one of them")
    _check_initial(initial_condition)
    na, nb, nc, nd, nf, nk = _orders(model)
    ny = model.n_outputs
    if not any(nc[i] or nd[i] or any(nf[i]) for i in range(ny)):
        # ARX: the least-squares fit is the prediction-error minimum (a coupled A too)
        from .arx import arx

        m = arx(data, na, nb, nk)
        m.info = dict(m.info or {}, start="init",
                      note="ARX structure: its least-squares fit is the prediction-error "
                           "minimum")
        return m
    coupled = [(i, k) for i in range(ny) for k in range(ny)
               if k != i and np.any(np.asarray(model.a[i][k]) != 0)]
    if coupled:
        i, k = coupled[0]
        raise DataError(
            f"the model's A couples output {i} with output {k} and it has C, D or F: pem "
            "refines such models one equation per output, with a diagonal A; refine a "
            "state-space form instead, sysid.pem(data, model.to_statespace())")
    na = [na[i][i] for i in range(ny)]
    m = _pem(data, na, nb, nc, nd, nf, nk, "pem", max_iter, progress, model,
             initial_condition=initial_condition)
    m.info["start"] = "init"
    return _warn_diverging(m, "pem")
