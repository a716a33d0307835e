"""A model that takes and returns raw data: a model fitted on a detrended record, with the
trend (offsets, slopes) that was removed from it.

``d, tr = sysid.detrend(raw, return_trend=True)``, ``m = sysid.n4sid(d, 4)``, then
``tr.attach(m)`` (or ``TrendedModel(m, tr)``) simulates and predicts in raw units:

.. math::

    \\hat y_{raw} = \\mathrm{model}(u_{raw} - u_0(t)) + y_0(t)

with ``u_0(t), y_0(t)`` the trend from the first sample of the arrays (``offset + slope
t``; :func:`sysid.compare` on a record evaluates it at the record's instants, as
:meth:`Trend.apply`). :func:`sysid.compare` estimates the initial state on the detrended
record, so the fit numbers equal those of ``model`` on ``tr.apply(raw)`` (for offsets; a linear
trend changes the variance the fit is normalised by).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .protocol import ModelMixin

__all__ = ["TrendedModel"]


class TrendedModel(ModelMixin):
    """``model`` (fitted on detrended data) that takes and returns raw data.

    Parameters
    ----------
    model : sysid.Model
        Any model of the protocol, fitted on the detrended record.
    trend : Trend
        From ``sysid.detrend(data, "mean" or "linear", return_trend=True)``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> rng = np.random.default_rng(0)
    >>> true = sysid.StateSpaceModel([[0.8]], [[1.0]], [[1.0]], dt=1.0)
    >>> du = rng.standard_normal(300)
    >>> raw = sysid.IOData(u=20.0 + du, y=50.0 + true.simulate(du), dt=1.0)
    >>> d, tr = sysid.detrend(raw, "mean", return_trend=True)
    >>> m = tr.attach(sysid.n4sid(d, 1))
    >>> m
    TrendedModel(StateSpaceModel(nstates=1, ...), Trend(mean, ...))
    >>> yhat = m.simulate(raw.u)                 # raw inputs in, raw outputs out
    >>> bool(abs(yhat.mean() - raw.y.mean()) < 0.1)
    True
    """

    def __init__(self, model: Any, trend: Any) -> None:
        from ..errors import DataError

        if not callable(getattr(trend, "restore_outputs", None)):
            raise DataError(f"trend must be a sysid.Trend, got {type(trend).__name__}")
        trend._parametric()
        if (len(trend.u_scale), len(trend.y_scale)) != (model.ninputs, model.noutputs):
            raise DataError(
                f"the trend has {len(trend.u_scale)} input(s) and {len(trend.y_scale)} "
                f"output(s) but the model {model.ninputs} and {model.noutputs}")
        self.model = model
        self.trend = trend

    # -- the protocol: names and sizes from the model --------------------------------------
    @property
    def dt(self) -> float:
        return float(self.model.dt)

    @property
    def ninputs(self) -> int:
        return int(self.model.ninputs)

    @property
    def noutputs(self) -> int:
        return int(self.model.noutputs)

    @property
    def input_names(self) -> list[str]:
        return list(self.model.input_names)

    @property
    def output_names(self) -> list[str]:
        return list(self.model.output_names)

    @property
    def n_parameters(self) -> int:
        return int(self.model.n_parameters)

    @property
    def info(self) -> dict[str, Any]:
        return {**dict(self.model.info), "trend": repr(self.trend)}

    @property
    def uncertainty(self) -> Any:
        """The inner model's parameter uncertainty (``None`` when it has none; a trend adds
        no parameter): what ``dcgain(std=True)``, ``sysid.damp(model, std=True)``,
        ``summary()`` and ``to_pandas()`` read, as ``poles(std=True)`` and the responses do.

        Examples
        --------
        >>> import numpy as np, sysid
        >>> raw = sysid.IOData(u=[21.0, 19.0, 20.0, 20.0], y=[50.0, 51.0, 49.0, 50.0])
        >>> d, tr = sysid.detrend(raw, "mean", return_trend=True)
        >>> build = lambda t: sysid.StateSpaceModel([[t[0]]], [[1.0]], [[1.0]])
        >>> inner = build([0.5])
        >>> inner.uncertainty = sysid.ParameterUncertainty([0.5], [[1e-4]], build)
        >>> m = tr.attach(inner)
        >>> m.uncertainty is inner.uncertainty
        True
        >>> gain, sd = m.dcgain(std=True)              # 1 / (1 - a), std 0.01 / (1 - a)^2
        >>> float(gain[0, 0]), round(float(sd[0, 0]), 6)
        (2.0, 0.04)
        """
        return getattr(self.model, "uncertainty", None)

    def dcgain(self, std: bool = False) -> Any:
        """The inner model's DC gain (a trend does not change it); ``std=True``: with its
        standard deviation, as the inner model's ``dcgain``."""
        fn = getattr(self.model, "dcgain", None)
        if fn is None:
            return super().dcgain(std=std)
        return fn(std=True) if std else fn()

    # -- raw data in, raw data out ---------------------------------------------------------
    def simulate(self, u: Any, x0: Any = None) -> np.ndarray:
        """Raw outputs for raw inputs (``x0``: the inner model's initial state)."""
        du = self.trend.remove_inputs(u, self.dt)
        y = self.model.simulate(du) if x0 is None else self.model.simulate(du, x0=x0)
        return self.trend.restore_outputs(y, self.dt)

    def predict(self, u: Any, y: Any = None, horizon: int = 1, **kw: Any) -> np.ndarray:
        """``horizon``-step predictions of the raw outputs from raw data (arrays or a
        record)."""
        from .._measured import predict_args

        u, y = predict_args(u, y)
        du = self.trend.remove_inputs(u, self.dt)
        dy = self.trend.remove_outputs(y, self.dt)
        out = self.model.predict(du, dy, horizon, **kw)
        return self.trend.restore_outputs(out, self.dt)

    def freqresp(self, omega: Any, std: bool = False) -> Any:
        """The inner model's frequency response (a trend does not change it); ``std=True``:
        with its standard deviations, as the inner model's ``freqresp``."""
        if std:
            return self.model.freqresp(omega, std=True)
        return np.asarray(self.model.freqresp(omega))

    def poles(self, std: bool = False, method: str = "linear") -> Any:
        """The inner model's poles (a trend does not change them); ``std``, ``method``: as
        the inner model's ``poles``."""
        return self.model.poles(std=True, method=method) if std else np.asarray(
            self.model.poles())

    # -- responses: of the linear model, in deviation variables (MATLAB's step on a model) --
    def step(self, n_samples: int | None = None, *args: Any, **kw: Any) -> Any:
        """The inner model's step response (``args``, ``kw``: as its ``step``): a unit step
        in deviation from the operating point, from rest, as :func:`sysid.step` and
        :func:`sysid.stepinfo` read it; the trend's offsets are no part of it (``simulate``
        with raw inputs gives raw outputs).

        Examples
        --------
        >>> import numpy as np, sysid
        >>> raw = sysid.IOData(u=[21.0, 19.0, 20.0, 20.0], y=[50.0, 51.0, 49.0, 50.0])
        >>> d, tr = sysid.detrend(raw, "mean", return_trend=True)
        >>> m = tr.attach(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
        >>> m.step(4).y[:, 0, 0]                  # from 0, not through the offsets
        array([0.  , 1.  , 1.5 , 1.75])
        """
        return self._respond("step", n_samples, *args, **kw)

    def impulse(self, n_samples: int | None = None, *args: Any, **kw: Any) -> Any:
        """The inner model's impulse response (``args``, ``kw``: as its ``impulse``), in
        deviation variables as :meth:`step`.

        Examples
        --------
        >>> import sysid
        >>> raw = sysid.IOData(u=[21.0, 19.0, 20.0, 20.0], y=[50.0, 51.0, 49.0, 50.0])
        >>> d, tr = sysid.detrend(raw, "mean", return_trend=True)
        >>> tr.attach(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])).impulse(3).y[:, 0, 0]
        array([0. , 1. , 0.5])
        """
        return self._respond("impulse", n_samples, *args, **kw)

    def _respond(self, kind: str, n_samples: int | None, *args: Any, **kw: Any) -> Any:
        fn = getattr(self.model, kind, None)
        if fn is None:
            from .protocol import sampled_response

            return sampled_response(self.model, kind, n_samples)
        return fn(n_samples, *args, **kw)

    def is_stable(self) -> bool:
        """The inner model's stability (a trend does not change it)."""
        return bool(self.model.is_stable())

    # -- saving: the inner model (any registered family, with its uncertainty) and the trend
    def to_dict(self) -> dict[str, Any]:
        """The inner model (its family and :func:`sysid.model_to_dict` body, uncertainty
        included) and the trend's offsets and slopes (:meth:`sysid.Trend.to_dict`), for
        :func:`sysid.save_model`; :func:`sysid.load_model` gives back a model that still
        takes and returns raw data.

        Examples
        --------
        >>> import os, tempfile, numpy as np, sysid
        >>> raw = sysid.IOData(u=[1.0, 2.0, 0.0, 1.0], y=[5.0, 5.5, 6.0, 5.0])
        >>> d, tr = sysid.detrend(raw, "mean", return_trend=True)
        >>> m = tr.attach(sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]]))
        >>> path = os.path.join(tempfile.mkdtemp(), "m.json")
        >>> m.save(path)
        >>> bool(np.allclose(sysid.load_model(path).simulate(raw.u), m.simulate(raw.u)))
        True
        """
        from .serialize import family_name
        from .uncertainty_io import body_with_uncertainty

        return {"model_family": family_name(self.model),
                "model": body_with_uncertainty(self.model), "trend": self.trend.to_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrendedModel:
        """Inverse of :meth:`to_dict`."""
        from .serialize import REGISTRY, family_class
        from .uncertainty_io import model_from_body

        inner = model_from_body(family_class(str(d["model_family"])), d["model"], REGISTRY)
        return cls(inner, family_class("Trend").from_dict(d["trend"]))  # type: ignore[attr-defined]

    def __repr__(self) -> str:
        return f"TrendedModel({self.model!r}, {self.trend!r})"


def _register() -> None:
    from .serialize import register_model

    register_model(TrendedModel)


_register()
