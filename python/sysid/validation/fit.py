"""The fit numbers of :func:`~sysid.validation.compare.compare`: NRMSE fit, VAF and RMSE per
output (:func:`fit_metrics`), the divergence rule, and the refusal of an output that stands
still (its fit is undefined).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_2d
from ..errors import DataError, ShapeError

__all__ = ["fit_metrics", "diverged", "require_outputs_vary"]


def output_weights(y: np.ndarray) -> np.ndarray:
    """``1 / std`` of each output over the record (1 for one that stands still): the initial
    state is fitted to the errors relative to each output's spread, as the fit % weighs them,
    not to whichever output has the largest numbers in its units."""
    s = _unit(y)
    sd = np.std(y / s, axis=0) * s
    return 1.0 / np.where(sd > 0, sd, 1.0)


def _unit(y: np.ndarray) -> np.ndarray:
    """Per output, the power of two nearest its largest deviation from its mean (1 for one
    that stands still): norms and variances are taken of ``y / unit`` and scaled back, since
    the squares of outputs near 1e-200 underflow (a fit of nan) and near 1e200 overflow
    (-inf). Dividing by a power of two is exact: outputs of ordinary size give the same
    numbers to the last bit."""
    with np.errstate(over="ignore", invalid="ignore"):
        spread = np.max(np.abs(y - y.mean(0)), axis=0, initial=0.0)
    ok = (spread > 0) & np.isfinite(spread)
    return np.where(ok, np.ldexp(1.0, np.frexp(np.where(ok, spread, 1.0))[1]), 1.0)



def fit_metrics(y: Any, yhat: Any) -> dict[str, np.ndarray]:
    """NRMSE fit, VAF (both %) and RMSE per output column.

    ``fit = 100 (1 - ||y - yhat|| / ||y - mean(y)||)`` (MATLAB's ``compare``; 100 is
    perfect, 0 is no better than the mean, negative is worse), ``vaf = 100 (1 - var(y - yhat)
    / var(y))`` and ``rmse = sqrt(mean((y - yhat)^2))``. Fit and VAF are undefined for a
    constant output channel: it raises a :class:`~sysid.errors.DataError` (as
    :func:`compare` does). The measurement comes first; MATLAB's ``goodnessOfFit(x, xref)``
    takes the reference second: :func:`sysid.goodness_of_fit` has its order and costs.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> y = np.array([0.0, 1.0, 2.0, 3.0])
    >>> sysid.fit_metrics(y, y + 0.1)["fit"]
    array([91.05572809])
    """
    y = as_2d(y, "y")
    yhat = as_2d(yhat, "yhat", ncols=y.shape[1])
    if yhat.shape != y.shape:
        raise ShapeError(f"yhat has shape {yhat.shape} but y has {y.shape}")
    require_outputs_vary([y])
    return _metrics(y, yhat)


def _metrics(y: np.ndarray, yhat: np.ndarray) -> dict[str, np.ndarray]:
    s = _unit(y)
    # an unstable model's simulation may overflow: its fit is then -inf, not a warning
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        y, err = y / s, (y - yhat) / s
        dev = np.linalg.norm(y - y.mean(0), axis=0)
        fit = 100.0 * (1.0 - np.linalg.norm(err, axis=0) / dev)
        vaf = 100.0 * (1.0 - err.var(0) / y.var(0))
        rmse = np.sqrt(np.mean(err**2, axis=0)) * s
    fit = np.where(np.isnan(fit) & ~np.isfinite(rmse), -np.inf, fit)
    fit = np.where(dev == 0, np.nan, fit)  # undefined for a constant channel (documented)
    return {"fit": fit, "vaf": vaf, "rmse": rmse}



def diverged(y: np.ndarray, yhat: np.ndarray) -> bool:
    """A model output that overflowed or grew beyond ``1e8`` times the measured range (the
    rule of :func:`compare`'s ``diverged``, shared by the fits' own free-run checks).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.validation.fit import diverged
    >>> diverged(np.ones(3), np.array([1.0, 2.0, 3e9])), diverged(np.ones(3), np.ones(3))
    (True, False)
    """
    if not np.all(np.isfinite(yhat)):
        return True
    scale = float(np.max(np.abs(y))) if y.size else 0.0
    return bool(yhat.size and np.max(np.abs(yhat)) > 1e8 * max(scale, 1e-300))


def require_outputs_vary(ys: list[np.ndarray], names: Any = None) -> None:
    """Refuse records with an output that is constant in an experiment: a fit against it
    (NRMSE against the mean) is undefined (:func:`compare`, and ``identify``'s validation
    data before its search)."""
    for i, y in enumerate(ys):
        flat = np.ptp(y, axis=0) == 0
        if flat.any():
            names = names or [f"y{j}" for j in range(y.shape[1])]
            which = ", ".join(str(names[j]) for j in np.flatnonzero(flat))
            raise DataError(
                f"output {which} is constant"
                + (f" in experiment {i}" if len(ys) > 1 else "")
                + ": the fit (NRMSE against the mean) is undefined for a constant signal; "
                "compare on a record where the output varies, or look at the residuals"
            )


#: An output whose standard deviation is below this share of its level (``|mean|``, in the
#: coordinates the model is compared in) barely moves on the record.
FLAT_LEVEL_SHARE = 0.1
#: An input whose standard deviation is below this share of its level (or zero) stands still
#: (a raw input at an operating point, 20 +- 1, moves: 5 %).
STILL_INPUT_SHARE = 0.01
#: ... and an output whose standard deviation is below this many times its noise (the
#: sample-to-sample scatter, ``std(diff(y)) / sqrt(2)``) shows little but noise.
FLAT_NOISE_MULTIPLE = 3.0


def flat_outputs(u: np.ndarray | None, y: np.ndarray) -> list[tuple[int, str]]:
    """``(output index, why)`` of every output whose NRMSE fit is not a meaningful measure on
    this record: every input stands still (its standard deviation below
    :data:`STILL_INPUT_SHARE` of its level ``|mean|``, or zero) and the output's variation is
    below :data:`FLAT_LEVEL_SHARE` of its level or :data:`FLAT_NOISE_MULTIPLE` times its noise
    (``std(diff(y)) / sqrt(2)``). The fit divides the error by the variation about the mean:
    on the settled end of a step test a level error of 1 % of the output is several times
    that variation, and the fit reads -300 % for a model whose level is nearly right. While
    an input moves, the output's response to it is what the fit measures (a record far from
    zero is not flat: its offset is the model's to carry); a time series is never flat.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.validation.fit import flat_outputs
    >>> t = np.arange(300.0)
    >>> settled = 100.0 + 0.5 * np.sin(t / 7)[:, None]  # a step test's settled end
    >>> flat_outputs(np.ones((300, 1)), settled)[0][0]
    0
    >>> flat_outputs(np.sin(t / 5)[:, None], settled)  # an input that moves: not flat
    []
    """
    y = np.asarray(y, float)
    if y.ndim == 1:
        y = y[:, None]
    u = None if u is None else np.asarray(u, float)
    if y.shape[0] < 3 or u is None or u.size == 0 or not _still(u.reshape(u.shape[0], -1)):
        return []
    s = _unit(y)
    with np.errstate(all="ignore"):
        ys = y / s
        sd, level = ys.std(0), np.abs(ys.mean(0))
        noise = np.diff(ys, axis=0).std(0) / np.sqrt(2.0)
    out = []
    for j in range(y.shape[1]):
        if not (np.isfinite(sd[j]) and sd[j] > 0):
            continue
        if sd[j] < FLAT_LEVEL_SHARE * level[j]:
            out.append((j, f"the inputs stand still and its variation (std {sd[j] * s[j]:.3g}) "
                           f"is {100 * sd[j] / level[j]:.2g} % of its level "
                           f"({level[j] * s[j]:.4g})"))
        elif sd[j] < FLAT_NOISE_MULTIPLE * noise[j]:
            out.append((j, f"the inputs stand still and its variation (std {sd[j] * s[j]:.3g}) "
                           f"is {sd[j] / noise[j]:.2g} times its noise"))
    return out


def _still(u: np.ndarray) -> bool:
    """Whether every input stands still: a standard deviation below :data:`STILL_INPUT_SHARE`
    of its level, or none at all."""
    s = _unit(u)
    with np.errstate(all="ignore"):
        us = u / s
        sd, level = us.std(0), np.abs(us.mean(0))
    return bool(np.all((sd == 0) | (sd < STILL_INPUT_SHARE * level)))


#: The error's constant part counts as a level apart from the dynamics when the fit without it
#: is at least this many points higher (a small offset on a near-perfect fit does not).
LEVEL_GAIN_POINTS = 10.0


def level_errors(y: np.ndarray, yhat: np.ndarray) -> list[tuple[int, float, float, float]]:
    """``(output index, level, its multiple of the output's std, fit without it)`` of every
    output whose simulation error is mostly a constant: the error's mean exceeds its spread
    about the mean (``|mean(e)| > std(e)``, over half the squared error), the means of its
    two halves are within half of it of each other (a level, not an error that grows, as an
    unstable model's), and taking it out raises the fit by :data:`LEVEL_GAIN_POINTS` or more,
    to zero or above (without it the response is simulated). The model then puts the output
    at a level the record does not have; the fit measures that level, not the response (a
    sensor offset that differs between records, or a static gain wrong at this record's
    input level).

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.validation.fit import level_errors
    >>> t = np.arange(400.0)
    >>> y = np.sin(t / 9)[:, None]
    >>> [(j, round(lv, 2), round(k, 1), round(f, 1)) for j, lv, k, f in level_errors(y, y - 2)]
    [(0, 2.0, 2.8, 100.0)]
    >>> level_errors(y, y - 0.01)      # a small offset on a near-perfect fit: not a level
    []
    """
    y, yhat = np.asarray(y, float), np.asarray(yhat, float)
    if y.ndim == 1:
        y, yhat = y[:, None], yhat[:, None]
    out: list[tuple[int, float, float, float]] = []
    if y.shape[0] < 3 or not np.all(np.isfinite(yhat)):
        return out
    s = _unit(y)
    with np.errstate(all="ignore"):
        ys, err = y / s, (y - yhat) / s
        dev = np.linalg.norm(ys - ys.mean(0), axis=0)
        level, spread = err.mean(0), err.std(0)
        h = y.shape[0] // 2
        halves = np.abs(err[:h].mean(0) - err[h:].mean(0))
        fit = 100.0 * (1.0 - np.linalg.norm(err, axis=0) / dev)
        fit_flat = 100.0 * (1.0 - np.linalg.norm(err - level, axis=0) / dev)
        sd = ys.std(0)
    for j in range(y.shape[1]):
        if (dev[j] > 0 and np.isfinite(fit[j]) and abs(level[j]) > spread[j]
                and halves[j] < 0.5 * abs(level[j]) and fit_flat[j] >= 0
                and fit_flat[j] - fit[j] >= LEVEL_GAIN_POINTS):
            out.append((j, float(level[j] * s[j]), float(abs(level[j]) / sd[j]),
                        float(fit_flat[j])))
    return out
