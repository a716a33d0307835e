"""Bode plots of frequency-response data (:class:`sysid.FRD`) and models."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _pyplot

__all__ = ["plot_frd"]


def plot_frd(frd: Any, *, models: Any = None, fig: Any = None) -> Any:
    """Magnitude (dB) and phase (deg) of every output/input pair, with the confidence band
    (shaded) and, when known, the coherence (a third row per input); ``models`` (objects with
    ``freqresp(omega)``, or a dict name -> model) are drawn on top. The frequency axis is in
    the FRD's ``units`` (Hz when they are not given).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np, sysid, matplotlib
    >>> matplotlib.use("Agg")
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0]], [[1.0]])
    >>> w = np.linspace(0.1, 3.0, 20)
    >>> fig = sysid.FRD(w, m.freqresp(w)).plot(models=m)
    >>> len(fig.axes)
    2
    """
    plt = _pyplot()
    l, m = frd.n_outputs, frd.n_inputs
    rows = 3 if frd.coherence is not None else 2
    if fig is None:
        fig = plt.figure(figsize=(3.6 * m + 1, 2.0 * rows * l + 0.6))
    axes = fig.subplots(rows * l, m, sharex=True, squeeze=False)
    if models is None:
        models = {}
    elif not isinstance(models, dict):
        seq = list(models) if isinstance(models, (list, tuple)) else [models]
        models = {("model" if len(seq) == 1 else f"model {k}"): mod for k, mod in enumerate(seq)}
    from ..models.checks import require_freqresp

    for name, mod in models.items():
        require_freqresp(mod, "models" if len(models) == 1 else f"models[{name!r}]")
    unit = "rad/s" if frd.units == "rad/s" else "Hz"
    f = frd.frequencies_in(unit)
    mag_db = 20 * np.log10(np.maximum(frd.magnitude, 1e-300))
    phase = np.degrees(frd.phase)
    rad = frd.radius
    model_g = {name: np.asarray(mod.freqresp(frd.omega)) for name, mod in models.items()}
    for i in range(l):
        for j in range(m):
            am, ap = axes[rows * i, j], axes[rows * i + 1, j]
            am.semilogx(f, mag_db[:, i, j], color="C0", lw=1.0, label=frd.method or "data")
            ap.semilogx(f, phase[:, i, j], color="C0", lw=1.0)
            if rad is not None:
                g = frd.magnitude[:, i, j]
                r = rad[:, i, j]
                lo = 20 * np.log10(np.maximum(g - r, g * 1e-3))
                hi = 20 * np.log10(g + r)
                am.fill_between(f, lo, hi, color="C0", alpha=0.2, lw=0)
                dph = np.degrees(np.arcsin(np.clip(r / np.maximum(g, 1e-300), 0, 1)))
                dph[r >= g] = 180.0  # the circle holds the origin: any phase is possible
                ap.fill_between(f, phase[:, i, j] - dph, phase[:, i, j] + dph, color="C0",
                                alpha=0.2, lw=0)
            for k, (name, g) in enumerate(model_g.items()):
                am.semilogx(f, 20 * np.log10(np.maximum(np.abs(g[:, i, j]), 1e-300)),
                            color=f"C{k + 1}", lw=1.0, label=name)
                ph = np.degrees(np.unwrap(np.angle(g[:, i, j])))
                # align the branch with the data's phase
                ph += 360 * np.round((phase[0, i, j] - ph[0]) / 360)
                ap.semilogx(f, ph, color=f"C{k + 1}", lw=1.0)
            am.set_title(f"{frd.input_names[j]} -> {frd.output_names[i]}", fontsize="small")
            am.set_ylabel("mag [dB]")
            ap.set_ylabel("phase [deg]")
            for ax in (am, ap):
                ax.grid(True, which="both", alpha=0.3)
            if rows == 3:
                ac = axes[rows * i + 2, j]
                ac.semilogx(f, frd.coherence[:, i, j], color="C2", lw=1.0)
                ac.set_ylim(0, 1.02)
                ac.set_ylabel("coherence")
                ac.grid(True, which="both", alpha=0.3)
            if i == 0 and j == 0 and model_g:
                am.legend(fontsize="small")
    for j in range(m):
        axes[-1, j].set_xlabel(f"frequency [{unit}]")
    fig.tight_layout()
    return fig
