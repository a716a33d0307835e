"""The spectrum of a model's simulation error beside the measured output's
(:func:`error_spectrum`): where the model explains the output and where it misses."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._checks import as_int
from .compare import compare_quiet
from .runner import X0, _model_first

__all__ = ["ErrorSpectrum", "error_spectrum"]


class ErrorSpectrum:
    """Welch power spectra of the simulation error and of the measured output.

    Attributes
    ----------
    freq : ndarray
        Frequencies in Hz.
    error_psd, output_psd : ndarray
        ``(len(freq), noutputs)`` one-sided power spectral densities (units^2 / Hz).
    """

    def __init__(self, model: Any, freq: np.ndarray, err: np.ndarray,
                 out: np.ndarray) -> None:
        self.model, self.freq, self.error_psd, self.output_psd = model, freq, err, out
        self.output_names = list(model.output_names)

    def worst_frequency(self) -> np.ndarray:
        """Frequency (Hz, above zero) of the largest simulation-error power, per output."""
        return self.freq[np.argmax(self.error_psd[1:], axis=0) + 1]

    def relative_error(self) -> np.ndarray:
        """Error-to-output power ratio per frequency, ``(len(freq), noutputs)``."""
        return self.error_psd / np.maximum(self.output_psd, 1e-300)

    def plot(self, fig: Any = None) -> Any:
        """Both spectra on a log scale, one axis per output."""
        from ..plot.validation import plot_error_spectrum

        return plot_error_spectrum(self, fig=fig)

    def __repr__(self) -> str:
        return (f"ErrorSpectrum({len(self.freq)} frequencies up to {self.freq[-1]:g} Hz, "
                f"{len(self.output_names)} output(s))")


def error_spectrum(model: Any, data: Any, *, x0: X0 = "estimate",
                   nperseg: int | None = None) -> ErrorSpectrum:
    """Power spectrum of the simulation error ``y - yhat`` beside the output's (Welch).

    Where the error spectrum approaches the output spectrum the model explains nothing;
    a peak in the error marks a mode the model misses or misplaces.

    Parameters
    ----------
    model : sysid.Model
    data : IOData or (u, y)
    x0 : "estimate", "zero", "model" or array
        Initial state of the simulation.
    nperseg : int, optional
        Welch segment length (default ``min(256, shortest experiment)``).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[1.0]])
    >>> u = np.random.default_rng(0).standard_normal(512)
    >>> s = sysid.error_spectrum(m, (u, m.simulate(u) + np.sin(0.5 * np.arange(512))[:, None]))
    >>> bool(abs(s.worst_frequency()[0] - 0.5 / (2 * np.pi)) < 0.01)
    True
    """
    model, data = _model_first(model, data)  # MATLAB's order accepted too
    cmp = compare_quiet(model, data, None, x0=x0)
    # the samples the model predicts: a NARX model's copied start is no error of its own
    # (:func:`~sysid.validation.runner.given_start`, as compare's fit leaves it out)
    s = int(getattr(cmp, "start", 0) or 0)
    pairs = [(y[s:], yh[s:]) for y, yh in zip(cmp.y, cmp.yhat)]
    shortest = min(y.shape[0] for y, _ in pairs)
    if nperseg is None:
        nperseg = min(256, shortest)
    else:
        nperseg = as_int(nperseg, "nperseg", 4, shortest)
    fs = 1.0 / cmp.dt
    err_sum, out_sum, weight = 0.0, 0.0, 0
    freq = np.zeros(0)
    for y, yh in pairs:
        import scipy.signal

        freq, pe = scipy.signal.welch(y - yh, fs=fs, nperseg=int(nperseg), axis=0)
        _, py = scipy.signal.welch(y, fs=fs, nperseg=int(nperseg), axis=0)
        err_sum = err_sum + pe * y.shape[0]
        out_sum = out_sum + py * y.shape[0]
        weight += y.shape[0]
    return ErrorSpectrum(cmp.model, freq, np.asarray(err_sum) / weight,
                         np.asarray(out_sum) / weight)
