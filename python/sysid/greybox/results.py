"""The result of grey-box estimation (:class:`GreyEstimate`) and the identifiability warning,
shared by the linear and nonlinear branches of :func:`sysid.greyest`.

Examples
--------
>>> import numpy as np, sysid
>>> s = sysid.GreyBox(lambda p: ([[p.a]], [[1.0]], [[1.0]], [[0.0]]), {"a": 0.5},
...                   continuous=False)
>>> u = np.sin(np.arange(100) * 0.3)
>>> y = sysid.StateSpaceModel([[0.7]], [[1.0]], [[1.0]]).simulate(u)
>>> fit = sysid.greyest(sysid.IOData(u=u, y=y), s, x0="zero")
>>> round(fit.parameters["a"]["value"], 8)
0.7
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._checks import user_stacklevel
from .._display import HTMLResult
from ..models.paramtable import ParameterTable
from .greybox import IdentifiabilityWarning

__all__ = ["GreyEstimate"]


class GreyEstimate(HTMLResult):
    """The result of :func:`greyest`.

    Attributes
    ----------
    parameters : ParameterTable
        Name, value, std, fixed, active bound, 95 % interval (``.to_pandas()``).
    covariance, correlation : ndarray
        Of the free parameters (order of ``free_names``).
    free_names : list of str
    model : Model
        The estimated model (with ``uncertainty``), usable by ``compare``, ``residuals``, plots.
    structure : GreyBox or NonlinearGreyBox
        The structure at the estimated values.
    initial_states : list of ndarray
        Initial state of every experiment.
    info : dict
        Iterations, ``cost`` history (of ``criterion``: ``"det"`` of the error covariance
        with the noise weighting, else ``"sum of squares"``; the values the progress callback
        got), ``weighted_cost``, ``loss_history`` (det), stop reason, rank, ...
    """

    def __init__(self, parameters: ParameterTable, covariance: np.ndarray, free_names: list[str],
                 model: Any, structure: Any, initial_states: list[np.ndarray],
                 info: dict[str, Any]) -> None:
        self.parameters = parameters
        self.covariance = covariance
        self.free_names = free_names
        self.model = model
        self.structure = structure
        self.initial_states = initial_states
        self.info = info

    @property
    def covariance(self) -> np.ndarray:
        """Of the free parameters (order of ``free_names``); a sandwich still deferred (a
        nonlinear fit's, :mod:`sysid.greybox.coloured`) is formed when first read."""
        d = self.__dict__
        c = d.get("_covariance", d.get("covariance"))
        if not isinstance(c, np.ndarray) and hasattr(c, "covariance"):  # the model's
            # uncertainty, its sandwich formed now
            c = d["_covariance"] = np.asarray(c.covariance, float)
        return c

    @covariance.setter
    def covariance(self, value: Any) -> None:
        self.__dict__["_covariance"] = value

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix of the free parameters."""
        s = np.sqrt(np.clip(np.diag(self.covariance), 0, None))
        with np.errstate(divide="ignore", invalid="ignore"):
            c = self.covariance / np.outer(s, s)
        c[np.outer(s, s) == 0] = np.nan
        return c

    def to_pandas(self) -> Any:
        """The parameter table as a :class:`pandas.DataFrame`."""
        return self.parameters.to_pandas()

    def summary(self) -> str:
        """Parameters, fit and how the search ended, as text."""
        i = self.info
        return "\n".join([
            repr(self), str(self.parameters),
            f"{_LABEL.get(i.get('criterion', 'det'), 'cost')} {i['cost'][0]:.4g} -> "
            f"{i['cost'][-1]:.4g} in "
            f"{i['iterations']} iterations ({i['stop']}); rank {i['rank']} of "
            f"{i['n_free']} free quantities; {i['n_samples']} samples"])

    def plot(self, ax: Any = None) -> Any:
        """Free parameters with their 95 % intervals, relative to their values."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots()
        t = self.parameters
        idx = [i for i in range(len(t)) if not t.fixed[i]]
        val = t.value[idx]
        scale = np.where(val != 0, np.abs(val), 1.0)
        ax.errorbar(np.arange(len(idx)), val / scale, yerr=1.96 * t.std[idx] / scale, fmt="o")
        ax.set_xticks(np.arange(len(idx)), [t.names[i] for i in idx], rotation=45)
        ax.set_ylabel("estimate / |estimate| with 95 % interval")
        return ax

    def __repr__(self) -> str:
        nf = len(self.free_names)
        return (f"GreyEstimate({len(self.parameters)} parameters, {nf} free, "
                f"{self.info['stop']}, {self.info.get('criterion', 'det')} "
                f"{self.info['cost'][-1]:.4g})")


_LABEL = {"det": "loss det(Lambda)", "sum of squares": "sum of squares"}


def _criterion(weighting: str) -> str:
    return "det" if weighting == "noise" else "sum of squares"


def _costs(res: dict[str, Any], reweight: bool) -> dict[str, Any]:
    """The search's histories as ``info`` items: ``cost`` (the criterion it decreases, the
    values the progress callback gets), ``weighted_cost`` and ``loss_history`` (det)."""
    return {"cost": list(res["history"]), "criterion": _criterion(
        "noise" if reweight else "identity"), "weighted_cost": list(res["weighted_history"]),
        "loss_history": list(res["loss_history"])}


def _warn_unidentifiable(null: np.ndarray, names: list[str], scale: np.ndarray,
                         values: np.ndarray | None = None) -> list[int]:
    """An :class:`IdentifiabilityWarning` naming the parameters in each direction the data
    do not determine (null vectors of the Gauss-Newton matrix); returns their indices, whose
    standard deviations the tables report as inf (as ``tfest`` does). ``values``: the
    parameters (in the units of ``scale * null``), to also name (and count as undetermined)
    those the direction moves by a comparable fraction of their value though by less in
    absolute terms (a similarity of two states moves large entries of ``K`` most, and the
    entries of ``C`` and the initial state by as much relatively)."""
    if null.size == 0 or null.ndim != 2 or null.shape[1] == 0:
        return []
    parts, weak = [], set()
    for v in null.T:
        v = v * scale
        v = v / np.linalg.norm(v)
        big = np.abs(v) >= 0.05 * np.max(np.abs(v))
        weak |= {int(i) for i in np.nonzero(big)[0]}
        combo = " + ".join(f"{v[i]:.3g}*{names[i]}" for i in np.nonzero(big)[0])
        also = ""
        if values is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                rel = np.abs(v) / np.abs(np.asarray(values, float))
            rel[~np.isfinite(rel)] = 0.0  # a parameter at zero: its change is in `big`
            top = float(np.max(rel[big]))  # 0 when the named parameters all sit at zero
            more = np.nonzero(~big & (rel > 0.0) & (rel >= 0.05 * top))[0] if top > 0 else \
                np.zeros(0, int)
            weak |= {int(i) for i in more}  # moved along it: as undetermined
            if more.size:
                listed = ", ".join(names[i] for i in more[:6]) + (", ..." if more.size > 6
                                                                 else "")
                also = (f", with smaller changes of {more.size} other parameter(s) as large "
                        f"relative to their values ({listed}),")
        parts.append(f"{', '.join(names[i] for i in np.nonzero(big)[0])} (the combination "
                     f"{combo}{also} does not change the fit)")
    warnings.warn("the data cannot determine these parameters separately: "
                  + "; ".join(parts) + ". Fix one of them, reparameterise, or use more "
                  "informative data; their standard deviations are reported as inf (poles, "
                  "responses and other functions of the model keep theirs).",
                  IdentifiabilityWarning, stacklevel=user_stacklevel())
    return sorted(weak)
