"""Plots of models: Bode, singular values (sigma), pole-zero map, time responses."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import DataError
from ..models.checks import FREQUENCY, _optional, check_model
from . import _pyplot

__all__ = ["plot_bode", "plot_sigma", "plot_pzmap", "plot_time_response"]


def _models(models: Any) -> list[Any]:
    ms = list(models) if isinstance(models, (list, tuple)) else [models]
    return [check_model(m, "every model", FREQUENCY) for m in ms]


def _omega(models: list[Any], omega: Any, n: int = 400) -> np.ndarray:
    if omega is not None:
        return np.asarray(omega, dtype=float)
    measured = [m.omega for m in models if isinstance(getattr(m, "omega", None), np.ndarray)]
    if measured:  # frequency-response data: their own grid, where they are defined
        lo, hi = max(w.min() for w in measured), min(w.max() for w in measured)
        return np.unique(np.concatenate([w[(w >= lo) & (w <= hi)] for w in measured]))
    sampled = [m for m in models if getattr(m, "dt", None)]
    if sampled:
        nyq = min(np.pi / m.dt for m in sampled)
        return np.logspace(np.log10(nyq) - 3, np.log10(nyq), n)
    # continuous models: two decades either side of the pole magnitudes
    mags = np.concatenate([np.abs(_optional(m, "poles", "the frequency grid")) for m in models]
                          + [np.ones(1)])
    mags = mags[mags > 0]
    return np.logspace(np.log10(mags.min()) - 2, np.log10(mags.max()) + 2, n)


def _z(confidence: float) -> float:
    from scipy.stats import norm

    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be between 0 and 1, got {confidence}")
    return float(norm.ppf(0.5 + confidence / 2))


def plot_bode(models: Any, omega: Any = None, *, hz: bool = True, fig: Any = None,
              labels: Sequence[str] | None = None, confidence: float | None = None) -> Any:
    """Magnitude (dB) and phase (deg) of each input-output pair, for one or more models.

    Parameters
    ----------
    models : sysid.Model or list of them
        Models (any family, discrete or continuous, or :class:`sysid.FRD`) with the same
        channels.
    omega : array_like, optional
        Angular frequencies in rad/s (default: three decades below Nyquist).
    hz : bool
        Label the frequency axis in Hz (else rad/s).
    fig : matplotlib Figure, optional
    labels : sequence of str, optional
        Legend entries, one per model.
    confidence : float, optional
        Draw confidence bands at this level (e.g. ``0.95``) for the models that carry a
        parameter ``uncertainty``: first-order std of ``log|H|`` and of the phase.
    """
    plt = _pyplot()
    ms = _models(models)
    zc = None if confidence is None else _z(confidence)
    if zc is not None:
        _warn_bare(ms, confidence)
    w = _omega(ms, omega)
    l, m = ms[0].noutputs, ms[0].ninputs
    if fig is None:
        fig = plt.figure(figsize=(4 * m + 2, 3.2 * l + 1))
    axes = fig.subplots(2 * l, m, squeeze=False, sharex=True)
    x = w / (2 * np.pi) if hz else w
    for k, mod in enumerate(ms):
        H = mod.freqresp(w)
        info = getattr(mod, "info", {})
        lab = labels[k] if labels is not None else str(
            info.get("method", getattr(mod, "method", None) or f"model {k}"))
        band = None
        if zc is not None and getattr(mod, "uncertainty", None) is not None:
            from ..models.uncertainty import bode_std

            band = bode_std(mod, w)
        for i in range(l):
            for j in range(m):
                mag = 20 * np.log10(np.maximum(np.abs(H[:, i, j]), 1e-300))
                ph = np.degrees(np.unwrap(np.angle(H[:, i, j])))
                axes[2 * i, j].semilogx(x, mag, color=f"C{k}", label=lab)
                axes[2 * i + 1, j].semilogx(x, ph, color=f"C{k}")
                if band is not None and zc is not None:
                    dm = zc * 20 / np.log(10) * band["log_mag_std"][:, i, j]
                    dp = zc * np.degrees(band["phase_std"][:, i, j])
                    axes[2 * i, j].fill_between(x, mag - dm, mag + dm, color=f"C{k}", alpha=0.25,
                                                lw=0)
                    axes[2 * i + 1, j].fill_between(x, ph - dp, ph + dp, color=f"C{k}",
                                                    alpha=0.25, lw=0)
                axes[2 * i, j].set_ylabel(f"|{mod.output_names[i]}/{mod.input_names[j]}| [dB]",
                                          fontsize=8)
                axes[2 * i + 1, j].set_ylabel("phase [deg]", fontsize=8)
    for ax in axes.ravel():
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("frequency [Hz]" if hz else "frequency [rad/s]")
    if len(ms) > 1:
        axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_sigma(models: Any, omega: Any = None, *, hz: bool = True, ax: Any = None) -> Any:
    """Singular values of the frequency response (MIMO gain envelope), in dB."""
    plt = _pyplot()
    ms = _models(models)
    w = _omega(ms, omega)
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3.5))
    x = w / (2 * np.pi) if hz else w
    for k, mod in enumerate(ms):
        sv = np.linalg.svd(mod.freqresp(w), compute_uv=False)
        ax.semilogx(x, 20 * np.log10(np.maximum(sv, 1e-300)), color=f"C{k}")
    ax.set_xlabel("frequency [Hz]" if hz else "frequency [rad/s]")
    ax.set_ylabel("singular values [dB]")
    ax.grid(True, which="both", alpha=0.3)
    return ax


def plot_pzmap(models: Any, ax: Any = None, confidence: float | None = None) -> Any:
    """Poles (x) and zeros (o): z-plane with the unit circle, or s-plane (continuous).

    Any model with ``poles()``/``zeros()`` or ``to_statespace()``; a model with neither
    raises a :class:`~sysid.DataError` naming the missing method. ``confidence`` (e.g.
    ``0.95``): around each pole of a model that carries a parameter ``uncertainty``, the
    region of that level from the poles' first-order standard deviations
    (``model.poles(std=True)``): an ellipse with half-axes ``k`` times the standard
    deviations of the real and imaginary parts for a complex pole (``k`` the radius of a
    two-dimensional normal's region), an interval along the real axis for a real one
    (MATLAB's ``showConfidence`` on a pole-zero plot).
    """
    plt = _pyplot()
    ms = _models(models)
    if confidence is not None:
        _z(confidence)  # checked
        _warn_bare(ms, confidence)
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    discrete = all(getattr(m, "dt", None) for m in ms)
    if discrete:  # the stability boundary: unit circle (z) or imaginary axis (s)
        th = np.linspace(0, 2 * np.pi, 400)
        ax.plot(np.cos(th), np.sin(th), color="0.5", lw=0.8)
    for k, mod in enumerate(ms):
        p = np.asarray(_optional(mod, "poles", "the pole-zero map"))
        z = np.asarray(_optional(mod, "zeros", "the pole-zero map"))
        name = "" if len(ms) == 1 else \
            f"{(getattr(mod, 'info', None) or {}).get('method', f'model {k}')}: "
        ax.plot(p.real, p.imag, "x", color=f"C{k}", ms=8, label=f"{name}poles")
        if confidence is not None and getattr(mod, "uncertainty", None) is not None:
            _pole_regions(ax, mod, confidence, f"C{k}")
        ax.plot(z.real, z.imag, "o", color=f"C{k}", mfc="none", ms=8, label=f"{name}zeros")
    ax.axhline(0, color="0.8", lw=0.5)
    ax.axvline(0, color="0.8", lw=0.5)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("Re z" if discrete else "Re s")
    ax.set_ylabel("Im z" if discrete else "Im s")
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title("pole-zero map")
    return ax


def _pole_regions(ax: Any, mod: Any, confidence: float, color: str) -> None:
    """The ``confidence`` regions of a model's poles (:func:`plot_pzmap`)."""
    from matplotlib.patches import Ellipse

    p, sd = mod.poles(std=True)
    p, sd = np.asarray(p), np.asarray(sd)
    k2 = float(np.sqrt(-2.0 * np.log1p(-confidence)))  # 2-D normal: P(|x| <= k2) = confidence
    k1 = _z(confidence)
    for pole, s in zip(p, sd):
        if not (np.isfinite(s.real) and np.isfinite(s.imag)):
            continue  # coinciding poles: no first-order std (poles(std=True) says so)
        if pole.imag == 0:
            ax.plot([pole.real - k1 * s.real, pole.real + k1 * s.real], [0.0, 0.0],
                    color=color, lw=3, alpha=0.35, solid_capstyle="butt")
        else:
            ax.add_patch(Ellipse((pole.real, pole.imag), 2 * k2 * s.real, 2 * k2 * s.imag,
                                 color=color, alpha=0.25, lw=0))


def _warn_bare(ms: list[Any], confidence: float) -> None:
    """The warning for models without parameter uncertainty asked for confidence regions."""
    bare = [k for k, mod in enumerate(ms) if getattr(mod, "uncertainty", None) is None
            and not hasattr(mod, "omega")]  # an FRD draws its own band (FRD.plot)
    if bare:
        import warnings

        from .._checks import user_stacklevel
        from ..models.uncertainty import UncertaintyWarning

        warnings.warn(f"confidence={confidence} but model(s) {bare} carry no parameter "
                      "uncertainty: no band for them (fit with a prediction-error method, "
                      "or SubspaceEstimator(...).fit(..., uncertainty='bootstrap'))",
                      UncertaintyWarning, stacklevel=user_stacklevel())


def plot_time_response(resp: Any, fig: Any = None) -> Any:
    """A :class:`~sysid.TimeResponse`, one axis per (output, input); a 95 % band
    where the response carries ``std`` (``sysid.step(model, std=True)``)."""
    plt = _pyplot()
    _, l, m = resp.y.shape
    if fig is None:
        fig = plt.figure(figsize=(3.5 * m + 1, 2.4 * l + 1))
    axes = fig.subplots(l, m, squeeze=False, sharex=True)
    for i in range(l):
        for j in range(m):
            ax = axes[i, j]
            line = getattr(resp, "continuous", False)  # a continuous model's: a line
            if line:
                ax.plot(resp.t, resp.y[:, i, j])
            else:
                ax.step(resp.t, resp.y[:, i, j], where="post")
            if getattr(resp, "std", None) is not None:
                d = 1.96 * resp.std[:, i, j]
                ax.fill_between(resp.t, resp.y[:, i, j] - d, resp.y[:, i, j] + d,
                                step=None if line else "post", alpha=0.25, lw=0,
                                label="95 %")
            ax.set_title(f"{resp.kind}: {resp.input_names[j]} -> {resp.output_names[i]}",
                         fontsize=8)
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.tight_layout()
    return fig


def bode(*models: Any, omega: Any = None, hz: bool = True, confidence: float | None = None,
         labels: Sequence[str] | None = None, fig: Any = None) -> Any:
    """MATLAB's ``bode(sys1, sys2, ...)``: magnitude and phase of one or more models in one
    figure (:func:`plot_bode`), with confidence bands for models that carry an
    ``uncertainty`` when ``confidence`` is given. Returns the figure; the values themselves
    are ``model.freqresp(omega)`` or :meth:`sysid.FRD.from_model`.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.9]], [[1.0]], [[0.1]], dt=0.1)
    >>> fig = sysid.bode(m, sysid.StateSpaceModel([[0.5]], [[1.0]], [[0.5]], dt=0.1))
    >>> len(fig.axes)
    2
    """
    if not models:
        raise DataError("bode needs at least one model: sysid.bode(model, ...)")
    return plot_bode(list(models), omega, hz=hz, fig=fig, labels=labels, confidence=confidence)


def pzmap(*models: Any, ax: Any = None, confidence: float | None = None) -> Any:
    """MATLAB's ``pzmap(sys1, sys2, ...)``: poles (x) and zeros (o) of one or more models
    (:func:`plot_pzmap`); returns the axis. The values are ``model.poles()`` and
    ``model.zeros()``; ``confidence`` (e.g. ``0.95``) draws each pole's region of that level
    for the models that carry a parameter uncertainty (MATLAB's ``showConfidence``).

    Examples
    --------
    >>> import sysid
    >>> ax = sysid.pzmap(sysid.StateSpaceModel([[0.9]], [[1.0]], [[0.1]], [[1.0]], dt=1.0))
    >>> ax.get_title()
    'pole-zero map'
    """
    if not models:
        raise DataError("pzmap needs at least one model: sysid.pzmap(model, ...)")
    return plot_pzmap(list(models), ax=ax, confidence=confidence)
