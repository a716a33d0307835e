"""Time series (signals without an input): :func:`ar` (Burg, Yule-Walker, least squares,
forward-backward), :func:`arma`, and :func:`forecast` with confidence bands."""

from .ar import ar, arma
from .forecast import Forecast, forecast

__all__ = ["ar", "arma", "forecast", "Forecast"]
