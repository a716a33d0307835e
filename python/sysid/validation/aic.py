"""Information criteria with MATLAB's definitions and names (``aic``, ``fpe``).

:func:`sysid.criteria` ranks models with the constants common to all orders left out; these
give MATLAB's numbers, so that a value can be checked against a MATLAB session. With
``Lambda = (1/N) sum e e^T`` the covariance of the one-step prediction errors on the
estimation data, ``N`` its samples, ``ny`` the outputs and ``np`` the free parameters:

- ``nAIC = log det(Lambda) + 2 np / N`` (MATLAB's default, ``aic(sys)``),
- ``AIC = N log det(Lambda) + 2 np + N ny (log(2 pi) + 1)`` (raw, ``aic(sys, 'AIC')``),
- ``AICc = AIC + 2 np (np + 1) / (N - np - 1)``,
- ``BIC = N log det(Lambda) + N (ny log(2 pi) + 1) + np log N`` (MATLAB's constant as its
  documentation writes it: ``N`` once, not ``N ny`` as in its AIC; equal for one output),
- ``FPE = det(Lambda) (1 + np / N) / (1 - np / N)``.

``np`` counts estimated initial states, as MATLAB's does: its documented example
(``tfest(z1, 2)`` on 300 samples: loss 1.6575, nAIC 0.5453, AIC 1015.0, AICc 1015.3, BIC
1037.2, FPE 1.7252) holds with ``np = 6``, the four coefficients and the two initial states.
Known input delays count nothing (MATLAB's ``InputDelay`` is no free parameter).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError

__all__ = ["aic", "fpe"]

_KINDS = ("naic", "aic", "aicc", "bic")
_LOG2PI1 = float(np.log(2 * np.pi) + 1)


def _report(model: Any) -> tuple[float, int, int] | None:
    """``(log det Lambda, N, np)`` of the estimation the model records (a prediction-error
    fit's innovation covariance and sample count: ``ssest``/``pem``, grey-box, ``tfest``,
    ``procest``), or ``None``."""
    from ..models.statespace import delay_free_order

    info = getattr(model, "info", None) or {}
    pem = info.get("pem") if isinstance(info.get("pem"), dict) else {}
    N = pem.get("n_samples", info.get("n_samples"))
    lam = getattr(model, "noise_cov", None)
    if lam is None:
        var = getattr(model, "noise_variance", None)
        var = info.get("noise_variance") if var is None else var
        lam = None if var is None else np.diag(np.atleast_1d(np.asarray(var, float)))
    if N is None or lam is None:
        return None
    sign, logdet = np.linalg.slogdet(np.atleast_2d(np.asarray(lam, float)))
    if sign <= 0:
        return None
    count = int(model.n_parameters)
    modes = pem.get("x0", [])
    if hasattr(model, "A") and not isinstance(modes, str):
        count += delay_free_order(model)[0] * sum(1 for m in modes if m == "estimate")
    return float(logdet), int(N), count


def _loss(model: Any, data: Any, x0: Any) -> tuple[float, int, int]:
    from .criteria import _criteria

    if data is None:
        got = _report(model)
        if got is None:
            raise DataError(f"{type(model).__name__} records no estimation loss (its "
                            "innovation covariance and sample count): pass the estimation "
                            "data, aic(model, data)")
        return got
    c = _criteria(model, data, x0, None, 1e-8)
    return c.log_loss, c.n_samples, c.n_params


def aic(model: Any, data: Any = None, kind: str = "naic", *, x0: Any = "estimate") -> float:
    """Akaike's (or Schwarz's) information criterion as MATLAB's ``aic(sys, measure)``.

    Parameters
    ----------
    model : sysid.Model
        An estimated model; ``np`` is its free parameters (``n_parameters``) plus its
        estimated initial states (module docs).
    data : IOData or (u, y), optional
        The estimation data. Without it, the loss the model records from its estimation
        (MATLAB's ``sys.Report.Fit``: ``ssest``/``pem``, grey-box, ``tfest`` and ``procest``
        fits); a model that records none raises :class:`~sysid.errors.DataError`.
    kind : {"naic", "aic", "aicc", "bic"}
        MATLAB's ``measure`` (case-insensitive): normalised AIC (the default), raw AIC,
        small-sample corrected AIC, or BIC (module docs).
    x0 : "estimate", "zero", "model" or array
        Initial state on ``data`` (see :func:`sysid.criteria`; an estimated one counts).

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(400)
    >>> y = m.simulate(u) + 0.1 * rng.standard_normal((400, 1))
    >>> c = sysid.criteria(m, (u, y))   # np = 2 + 1 initial state, log det(Lambda)
    >>> bool(np.isclose(sysid.aic(m, (u, y)), c.log_loss + 2 * 3 / 400))
    True
    >>> bool(np.isclose(sysid.aic(m, (u, y), "aic"), c.aic + 400 * (np.log(2 * np.pi) + 1)))
    True
    """
    k = str(kind).lower() if isinstance(kind, str) else kind
    if k not in _KINDS:
        raise DataError(f"kind must be one of {', '.join(_KINDS)} (MATLAB's measures "
                        f"'nAIC', 'AIC', 'AICc', 'BIC'), got {kind!r}")
    logv, N, p = _loss(model, data, x0)
    ny = int(model.noutputs)
    if k == "naic":
        return float(logv + 2 * p / N)
    raw = N * logv + 2 * p + N * ny * _LOG2PI1
    if k == "aic":
        return float(raw)
    if k == "aicc":
        return float(raw + 2 * p * (p + 1) / (N - p - 1)) if N - p - 1 > 0 else np.inf
    return float(N * logv + N * (ny * np.log(2 * np.pi) + 1) + p * np.log(N))


def fpe(model: Any, data: Any = None, *, x0: Any = "estimate") -> float:
    """Akaike's final prediction error as MATLAB's ``fpe(sys)``:
    ``det(Lambda) (1 + np/N) / (1 - np/N)`` (module docs); NaN when ``np >= N`` (MATLAB
    returns NaN there too).

    Parameters
    ----------
    model : sysid.Model
    data : IOData or (u, y), optional
        The estimation data; without it, the loss the model records (see :func:`aic`).
    x0 : "estimate", "zero", "model" or array
        Initial state on ``data`` (an estimated one counts in ``np``).

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = rng.standard_normal(400)
    >>> y = m.simulate(u) + 0.1 * rng.standard_normal((400, 1))
    >>> bool(np.isclose(sysid.fpe(m, (u, y)), sysid.criteria(m, (u, y)).fpe))
    True
    """
    logv, N, p = _loss(model, data, x0)
    if p >= N:
        return float("nan")
    return float(np.exp(logv) * (1 + p / N) / (1 - p / N))
