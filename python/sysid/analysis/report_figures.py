"""The figures of :func:`sysid.report` as data: one JSON-ready dict per chart.

Each figure is ``{"title", "x": {"label", "log"}, "y": {"label", "log"}, "series": [...],
"bands": [...]}``, drawn in the page by the inline script ``report_chart.js`` (zoomable SVG,
no network). Axis labels carry the channel names and units; long records are reduced to
their min/max envelope (:data:`MAX_POINTS` points per series), which keeps every spike.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

__all__ = ["MAX_POINTS", "channel_label", "time_figures", "bode_figures", "residual_figures",
           "error_spectrum_figures", "step_figures", "pzmap_figure", "singular_value_figure",
           "stabilization_figure", "stabilization_classes", "consistent_phase"]

MAX_POINTS = 20000
BLUE, RED, GREEN, ORANGE, GREY = "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#888888"
Z95 = 1.959963984540054


def _num(a: Any) -> list[Any]:
    """Floats with 6 significant digits; NaN and inf become ``None`` (JSON null)."""
    out: list[Any] = []
    for v in np.asarray(a, dtype=float).ravel().tolist():
        out.append(float(f"{v:.6g}") if np.isfinite(v) else None)
    return out


def _envelope(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At most :data:`MAX_POINTS` points: the min and max of each of ``MAX_POINTS/2`` bins."""
    if y.size <= MAX_POINTS:
        return t, y
    edges = np.linspace(0, y.size, MAX_POINTS // 2 + 1).astype(int)[:-1]
    lo, hi = np.minimum.reduceat(y, edges), np.maximum.reduceat(y, edges)
    return np.repeat(t[edges], 2), np.column_stack([lo, hi]).ravel()


def series(name: str, x: Any, y: Any, color: str, **kw: Any) -> dict[str, Any]:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    x, y = _envelope(x, y)
    return {"name": name, "x": _num(x), "y": _num(y), "color": color, **kw}


def band(name: str, x: Any, lo: Any, hi: Any, color: str) -> dict[str, Any]:
    return {"name": name, "x": _num(x), "lo": _num(lo), "hi": _num(hi), "color": color}


def figure(title: str, xlabel: str, ylabel: str, series: list[dict[str, Any]],
           bands: list[dict[str, Any]] | None = None, *, logx: bool = False,
           logy: bool = False, equal: bool = False) -> dict[str, Any]:
    return {"title": title, "x": {"label": xlabel, "log": logx},
            "y": {"label": ylabel, "log": logy}, "series": series, "bands": bands or [],
            "equal": equal}


def channel_label(name: str, units: dict[str, str]) -> str:
    """``"name [unit]"``, or the name alone when the data give no unit."""
    u = units.get(name, "")
    return f"{name} [{u}]" if u else name


def _joined(times: list[np.ndarray], values: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Experiments end to end, a NaN between them (a gap in the line)."""
    ts, vs = [], []
    for t, v in zip(times, values):
        ts += [t, [np.nan]]
        vs += [v, [np.nan]]
    return np.concatenate(ts[:-1]), np.concatenate(vs[:-1])


# -- time domain ----------------------------------------------------------------------------
def time_figures(sim: Any, pred: Any, times: list[np.ndarray], units: dict[str, str],
                 which: str) -> list[dict[str, Any]]:
    """Measured, simulated and 1-step-predicted output, one chart per output."""
    figs = []
    for j, name in enumerate(sim.output_names):
        t, y = _joined(times, [y[:, j] for y in sim.y])
        _, ys = _joined(times, [y[:, j] for y in sim.yhat])
        _, yp = _joined(times, [y[:, j] for y in pred.yhat])
        fit, fitp = float(np.mean(sim.fit[:, j])), float(np.mean(pred.fit[:, j]))
        figs.append(figure(
            f"{name}: {which} data, simulation fit {fit:.1f} %, 1-step {fitp:.1f} %",
            "time [s]", channel_label(name, units),
            [series("measured", t, y, "#222222", width=1.0),
             series(f"simulated ({fit:.1f} %)", t, ys, BLUE),
             series(f"1-step predicted ({fitp:.1f} %)", t, yp, ORANGE, dash="4 3")]))
    return figs


def step_figures(model: Any, units: dict[str, str]) -> list[dict[str, Any]]:
    """Step response per (output, input) with its 95 % band when the model has one."""
    from .lti import step

    has = getattr(model, "uncertainty", None) is not None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the band is optional; the page says when absent
        try:
            r = step(model, std=has)
        except Exception:  # noqa: BLE001 - no std for this family: the response alone
            r, has = step(model), False
    figs = []
    for i, on in enumerate(r.output_names):
        for j, inn in enumerate(r.input_names):
            y = r.y[:, i, j]
            bands = []
            if has and r.std is not None:
                s = Z95 * r.std[:, i, j]
                bands = [band("95 % band", r.t, y - s, y + s, BLUE)]
            figs.append(figure(f"step response: {inn} -> {on}", "time [s]",
                               f"{channel_label(on, units)} per unit of "
                               f"{channel_label(inn, units)}",
                               [series("step response", r.t, y, BLUE)], bands))
    return figs


# -- frequency domain -----------------------------------------------------------------------
def consistent_phase(model_phase: np.ndarray, w_model: np.ndarray, est_phase: np.ndarray,
                     w_est: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Phases in degrees on one branch: the model's unwrapped along frequency and started in
    (-180, 180] at its lowest frequency; the estimate's wrapped value moved by the multiple
    of 360 that puts it nearest the model's phase at the same frequency.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.analysis.report_figures import consistent_phase
    >>> m, e = consistent_phase(np.array([-170.0, 170.0, 110.0]), np.array([1.0, 2, 3]),
    ...                         np.array([170.0, 110.0]), np.array([2.0, 3.0]))
    >>> m.round(6).tolist(), e.round(6).tolist()
    ([-170.0, -190.0, -250.0], [-190.0, -250.0])
    """
    m = np.rad2deg(np.unwrap(np.deg2rad(model_phase)))
    if m.size:
        m = m - 360.0 * np.ceil((m[0] - 180.0) / 360.0)
    ref = np.interp(w_est, w_model, m) if m.size else np.zeros_like(est_phase)
    e = est_phase + 360.0 * np.round((ref - est_phase) / 360.0)
    return m, e


def bode_figures(model: Any, frd: Any, units: dict[str, str]) -> list[dict[str, Any]]:
    """Magnitude and phase per (output, input): the model (with its 95 % band when it has an
    uncertainty) and the non-parametric estimate ``frd`` (with its confidence band)."""
    dt = float(model.dt) if model.dt else 0.0
    if frd is not None:
        w_lo, w_hi = float(frd.omega[frd.omega > 0][0]), float(frd.omega[-1])
    else:
        w_hi = np.pi / dt if dt > 0 else 100.0
        w_lo = w_hi / 1000.0
    w = np.logspace(np.log10(w_lo), np.log10(w_hi), 400)
    H = np.asarray(model.freqresp(w))
    mag_sd = ph_sd = None
    if getattr(model, "uncertainty", None) is not None:
        from ..models.uncertainty import bode_std

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                b = bode_std(model, w)
                mag_sd, ph_sd = b["log_mag_std"], b["phase_std"]
            except Exception:  # noqa: BLE001, S110 - the band is optional
                pass
    f = w / (2 * np.pi)
    figs = []
    for i, on in enumerate(model.output_names):
        for j, inn in enumerate(model.input_names):
            pair = f"{inn} -> {on}"
            ratio = f"{units.get(on) or on} / {units.get(inn) or inn}"
            with np.errstate(divide="ignore"):
                mag = 20 * np.log10(np.abs(H[:, i, j]))
            mser = [series("model", f, mag, BLUE, width=1.6)]
            pser: list[dict[str, Any]] = []
            mb: list[dict[str, Any]] = []
            pb: list[dict[str, Any]] = []
            ph = np.angle(H[:, i, j], deg=True)
            if frd is not None:
                wf = frd.omega
                keep = wf > 0
                G = frd.response[keep, i, j]
                ph, eph = consistent_phase(ph, w, np.angle(G, deg=True), wf[keep])
                with np.errstate(divide="ignore", invalid="ignore"):
                    emag = 20 * np.log10(np.abs(G))
                mser.append(series(f"{frd.method or 'non-parametric'} estimate", wf[keep] /
                                   (2 * np.pi), emag, RED, width=1.0))
                pser.append(series(f"{frd.method or 'non-parametric'} estimate", wf[keep] /
                                   (2 * np.pi), eph, RED, width=1.0))
                r = frd.radius
                if r is not None:
                    rr = r[keep, i, j]
                    a = np.abs(G)
                    with np.errstate(divide="ignore", invalid="ignore"):
                        lo = 20 * np.log10(np.maximum(a - rr, 1e-300))
                        hi = 20 * np.log10(a + rr)
                        dph = np.rad2deg(np.arcsin(np.clip(rr / a, 0, 1)))
                    lo = np.where(a > rr, lo, np.nan)
                    level = f"{100 * frd.confidence:.0f} %"
                    mb.append(band(f"estimate {level}", wf[keep] / (2 * np.pi), lo, hi, RED))
                    pb.append(band(f"estimate {level}", wf[keep] / (2 * np.pi), eph - dph,
                                   eph + dph, RED))
            else:
                ph, _ = consistent_phase(ph, w, np.zeros(0), np.zeros(0))
            pser.insert(0, series("model", f, ph, BLUE, width=1.6))
            if mag_sd is not None and ph_sd is not None:
                s = Z95 * 20 / np.log(10) * mag_sd[:, i, j]
                mb.insert(0, band("model 95 %", f, mag - s, mag + s, BLUE))
                sp = Z95 * np.rad2deg(ph_sd[:, i, j])
                pb.insert(0, band("model 95 %", f, ph - sp, ph + sp, BLUE))
            figs.append(figure(f"magnitude: {pair} (|G| in {ratio})", "frequency [Hz]",
                               "|G| [dB]", mser, mb, logx=True))
            figs.append(figure(f"phase: {pair}", "frequency [Hz]", "phase [deg]", pser, pb,
                               logx=True))
    return figs


def error_spectrum_figures(spec: Any, units: dict[str, str]) -> list[dict[str, Any]]:
    """Power spectra of the simulation error and of the measured output, per output."""
    figs = []
    for j, name in enumerate(spec.output_names):
        u = units.get(name, "")
        figs.append(figure(f"simulation error spectrum: {name}", "frequency [Hz]",
                           f"PSD [{u}^2/Hz]" if u else "PSD [1/Hz]",
                           [series("measured output", spec.freq[1:], spec.output_psd[1:, j],
                                   "#222222"),
                            series("simulation error", spec.freq[1:], spec.error_psd[1:, j],
                                   RED)], logx=True, logy=True))
    return figs


def residual_figures(res: Any) -> list[dict[str, Any]]:
    """Autocorrelation of each output's residual and its cross-correlation with each input,
    with the band a white, input-independent residual stays in."""
    figs = []
    level = f"{100 * (1 - res.alpha):.0f} % bound"
    for i, on in enumerate(res.output_names):
        lags = res.lags[1:]
        figs.append(figure(
            f"residual autocorrelation: {on} (Ljung-Box p = {res.ljung_box_pvalue[i]:.3g})",
            "lag [samples]", "correlation",
            [series("autocorrelation", lags, res.autocorr[1:, i, i], BLUE, mode="markers")],
            [band(level, lags, -res.bounds[1:], res.bounds[1:], GREY)]))
        for j, inn in enumerate(res.input_names):
            x = res.xlags
            figs.append(figure(
                f"cross-correlation: residual of {on} with {inn} (independence p = "
                f"{res.independence_pvalue[i]:.3g})", "lag [samples] (positive: past inputs)",
                "correlation",
                [series("cross-correlation", x, res.crosscorr[:, i, j], BLUE, mode="markers")],
                [band(level, x, -res.xbounds, res.xbounds, GREY)]))
    return figs


# -- poles and orders -----------------------------------------------------------------------
def pzmap_figure(model: Any) -> dict[str, Any] | None:
    """Poles (x) and zeros (o) with the unit circle (discrete) or the imaginary axis."""
    try:
        p = np.asarray(model.poles(), dtype=complex)
    except Exception:  # noqa: BLE001 - a model without poles
        return None
    try:
        z = np.asarray(model.zeros(), dtype=complex)
    except Exception:  # noqa: BLE001
        z = np.zeros(0, dtype=complex)
    z = z[np.isfinite(z)]
    s = [series("poles", p.real, p.imag, RED, mode="markers", marker="x", size=4.5)]
    if z.size:
        s.append(series("zeros", z.real, z.imag, BLUE, mode="markers", marker="open"))
    if model.dt:
        th = np.linspace(0, 2 * np.pi, 361)
        s.append(series("unit circle", np.cos(th), np.sin(th), GREY, width=0.8))
        return figure("pole-zero map (z plane)", "real", "imaginary", s, equal=True)
    top = float(np.max(np.abs(p.imag), initial=1.0)) * 1.2
    s.append(series("imaginary axis", [0.0, 0.0], [-top, top], GREY, width=0.8))
    return figure("pole-zero map (s plane)", "real [1/s]", "imaginary [rad/s]", s, equal=True)


def singular_value_figure(sel: Any) -> dict[str, Any] | None:
    """Singular values of the order choice, the chosen order marked."""
    sv = sel.singular_values.get(sel.method)
    if sv is None or not np.size(sv):
        return None
    n = np.arange(1, sv.size + 1)
    k = min(sel.order, sv.size) - 1
    return figure(f"singular values ({sel.method}); chosen order {sel.order}", "index",
                  "singular value",
                  [series("singular values", n, sv, BLUE, mode="markers"),
                   series(f"order {sel.order}", [n[k]], [sv[k]], RED, mode="markers",
                          marker="x", size=6)], logy=True)


#: Tolerances of the stabilisation diagram (relative change from the next lower order).
FREQ_TOL, DAMP_TOL = 0.01, 0.05


def stabilization_classes(sel: Any, method: str | None = None,
                          ) -> tuple[dict[str, list[tuple[float, int]]], list[int]]:
    """``({class: [(frequency Hz, order), ...]}, orders)`` of every pole of every order of
    the sweep (one per conjugate pair). Classes: ``"new"``; ``"f"`` (stable in frequency: the
    nearest pole of the next lower order within :data:`FREQ_TOL`); ``"fd"`` (and in damping,
    within :data:`DAMP_TOL`); ``"unstable"``."""
    cats: dict[str, list[tuple[float, int]]] = {"new": [], "f": [], "fd": [], "unstable": []}
    prev = None
    orders = []
    for order, d in sel.damping(method or sel.method):
        orders.append(order)
        keep = np.isfinite(d.wn_hz) & (d.poles.imag >= 0)
        f, z = d.wn_hz[keep], d.zeta[keep]
        inside = (np.abs(d.poles[keep]) < 1) if d.dt else (d.poles[keep].real < 0)
        for fi, zi, ok in zip(f, z, inside):
            kind = "new"
            if prev is not None and prev[0].size:
                k = int(np.argmin(np.abs(prev[0] - fi)))
                if abs(prev[0][k] - fi) <= FREQ_TOL * max(fi, 1e-12):
                    kind = "fd" if abs(prev[1][k] - zi) <= DAMP_TOL * max(abs(zi), 1e-2) \
                        else "f"
            cats["unstable" if not ok else kind].append((float(fi), order))
        prev = (f, z)
    return cats, orders


#: Legend name, colour and marker of each class of :func:`stabilization_classes`.
STAB_STYLE = {"new": ("new", "#9ecae1", "open"), "f": ("stable in frequency", BLUE, "open"),
              "fd": ("stable in frequency and damping", BLUE, "filled"),
              "unstable": ("unstable", RED, "x")}


def stabilization_figure(sel: Any, frd: Any = None) -> dict[str, Any] | None:
    """Stabilisation diagram (:func:`stabilization_classes`) with the estimate's magnitude
    (log, scaled to the order axis) behind."""
    cats, orders = stabilization_classes(sel)
    if not orders:
        return None
    s = []
    for key, pts in cats.items():
        if pts:
            a = np.array(pts)
            name, color, marker = STAB_STYLE[key]
            s.append(series(f"{name} ({len(pts)})", a[:, 0], a[:, 1], color, mode="markers",
                            marker=marker))
    top = max(orders)
    if frd is not None and frd.response.shape[2] and frd.omega.size > 2:
        keep = frd.omega > 0
        g = np.log10(np.maximum(np.abs(frd.response[keep, 0, 0]), 1e-300))
        g = 0.5 + top * (g - g.min()) / max(g.max() - g.min(), 1e-12)
        s.insert(0, series(f"|G| of the {frd.method or 'estimate'} (log, scaled)",
                           frd.omega[keep] / (2 * np.pi), g, GREY, width=0.8))
    return figure(f"stabilisation diagram ({sel.method}, orders {orders[0]}..{top}); chosen "
                  f"order {sel.order}", "natural frequency [Hz]", "model order", s, logx=True)
