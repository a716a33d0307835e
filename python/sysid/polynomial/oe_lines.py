"""``sysid.oe`` on periodic data (``periods=``, issue 28) and on frequency-response data
(an FRD, MATLAB's ``oe(idfrd, [nb nf nk])``): ``B/F`` fitted on the excited lines (or the
FRD's) by the weighted frequency-response fit of ``tfest``
(:func:`sysid.tf.frequency.fit_lines`: Sanathanan-Koerner start, then weighted NLS with the
``1/std`` of :func:`sysid.bla`'s averaged response or the FRD's, uniform without one;
covariance scaled by the residual scale, ``info["residual_scale"]``, and the
sample-variance factor, ``info["sample_variance_factor"]``), returned as the
:class:`~sysid.PolynomialModel` the time-domain ``oe`` gives."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from .._checks import as_int, as_int_grid
from ..errors import DataError
from .model import PolynomialModel

__all__: list[str] = []


def oe_lines(data: Any, nb: Any, nf: Any, nk: Any, *, periods: Any, transient: Any,
             max_iter: int, progress: Any, init: Any) -> tuple[PolynomialModel | None,
                                                               dict[str, Any]]:
    """The OE model on the lines of periodic ``data``, and what was found of the
    periodicity; no model when ``periods="auto"`` finds no usable period (the caller then
    fits in the time domain). Internal: called by :func:`sysid.oe`."""
    from ..tf.frequency import record_lines

    if init is not None:
        raise DataError("periods= starts from Sanathanan-Koerner iterations on the lines: "
                        "leave init out, or leave periods out for the time-domain fit")
    nb_g, nf_g, nk_g = _grids(data, nb, nf, nk, "periods=")
    lines, periodicity = record_lines(data, periods, transient)
    if lines is None:
        return None, periodicity
    m = _fit(lines, nb_g, nf_g, nk_g, float(data.dt), max_iter, progress)
    m.noise_variance = _noise_variance(m, lines)
    m.info.update(periods=lines.info.get("periods"), periodicity=periodicity)
    return m, periodicity


def oe_frd(frd: Any, nb: Any, nf: Any, nk: Any, *, max_iter: int, progress: Any,
           init: Any) -> PolynomialModel:
    """:func:`sysid.oe` on frequency-response data (MATLAB's ``oe(idfrd, [nb nf nk])``):
    ``B/F`` fitted to the response, weighted by its ``std`` or uniformly without one.
    Internal: called by :func:`sysid.oe`."""
    if init is not None:
        raise DataError("oe on an FRD starts from Sanathanan-Koerner iterations on its "
                        "lines: leave init out")
    if not frd.dt:
        raise DataError("oe fits a discrete model and needs the FRD's sample time: pass dt= "
                        "to sysid.FRD (for a continuous model use sysid.tfest(frd, n))")
    nb_g, nf_g, nk_g = _grids(frd, nb, nf, nk, "oe on an FRD")
    m = _fit(frd, nb_g, nf_g, nk_g, float(frd.dt), max_iter, progress)
    # a response carries no time-domain noise level: none is claimed
    m.noise_variance = np.zeros(frd.n_outputs)
    m.info.update(weighting="noise" if frd.std is not None else "uniform",
                  noise_variance="not estimated (frequency-response data)")
    return m


def _grids(data: Any, nb: Any, nf: Any, nk: Any, who: str) -> tuple[np.ndarray, ...]:
    """``nb``, ``nf``, ``nk`` as ``(outputs, inputs)`` grids, each pair fitted."""
    shape = (data.n_outputs, data.n_inputs)
    nb_g, nf_g, nk_g = (np.array(as_int_grid(v, shape, name)) for v, name in
                        ((nb, "nb"), (nf, "nf"), (nk, "nk")))
    if np.any(nb_g < 1) or np.any(nf_g < 0) or np.any(nk_g < 0):
        raise DataError(f"{who} fits every input-output pair: give nb >= 1, nf >= 0 and "
                        "nk >= 0 for each")
    return nb_g, nf_g, nk_g


def _fit(lines: Any, nb_g: np.ndarray, nf_g: np.ndarray, nk_g: np.ndarray, dt: float,
         max_iter: int, progress: Any) -> PolynomialModel:
    """``B/F`` of every pair fitted to the FRD ``lines`` (:func:`sysid.tf.frequency.fit_lines`)
    as a :class:`PolynomialModel` with its covariance."""
    from ..tf.frequency import fit_lines, warn_held, warn_insisting
    from ..tf.options import blockdiag

    ny, nu = lines.n_outputs, lines.n_inputs
    # tfest's discrete pair lags 1 + delay samples: the delay is nk - 1
    insisting: list[dict[str, Any]] = []
    _, _, _, _, thetas, covs, scales, factor = fit_lines(  # F kept stable, as in the time
        lines, nf_g, nb_g - 1, nk_g - 1.0, False, dt, as_int(max_iter, "max_iter", 0), 1e-10,
        progress, "oe", stable=True, insisting=insisting)  # domain (oe's F search)
    free = "fit it with sysid.tfest(..., dt=..., enforce_stability=False) or sysid.arx"
    if not warn_insisting(insisting, "oe", dt, free=free):
        f_of = [[np.concatenate([[1.0], thetas[i * nu + j][:nf_g[i, j]]]) for j in range(nu)]
                for i in range(ny)]
        warn_held(SimpleNamespace(den=f_of, output_names=lines.output_names,
                                  input_names=lines.input_names), lines.omega, dt, "oe",
                  free="sysid.tfest(..., dt=..., enforce_stability=False) shows it")
    b = [[thetas[i * nu + j][nf_g[i, j]:-1] for j in range(nu)] for i in range(ny)]
    f = [[thetas[i * nu + j][:nf_g[i, j]] for j in range(nu)] for i in range(ny)]
    m = PolynomialModel([[np.zeros(0)] * ny for _ in range(ny)], b, nk_g, dt, f=f)
    m.input_names, m.output_names = list(lines.input_names), list(lines.output_names)
    m.info = {"method": "oe", "domain": "frequency", "lines": int(lines.omega.size),
              "criterion": "weighted sum of squares on the excited lines",
              "residual_scale": scales, "sample_variance_factor": factor}
    cov = []
    for i in range(ny):  # oe's order per output: b_i1.., f_i1.. (the delays are fixed)
        o, blocks = 0, []
        for j in range(nu):
            nf_, nb_ = int(nf_g[i, j]), int(nb_g[i, j])
            blocks.append((o, nf_, nb_))
            o += nf_ + nb_
        idx = [o_ + nf_ + k for o_, nf_, nb_ in blocks for k in range(nb_)] + \
            [o_ + k for o_, nf_, _ in blocks for k in range(nf_)]
        P = blockdiag([np.asarray(covs[i * nu + j])[:-1, :-1] for j in range(nu)])
        cov.append(P[np.ix_(idx, idx)])
    m.covariance = cov  # type: ignore[attr-defined]
    from .uncertainty import attach_uncertainty as _attach_uncertainty

    _attach_uncertainty(m, cov, "pem", "frequency lines")
    return m


def _noise_variance(m: PolynomialModel, lines: Any) -> np.ndarray:
    """Per output, the variance of the output noise: the period-averaged output less the
    model's steady-state response to the averaged input (exact, on one period by the DFT),
    times the number of periods averaged."""
    avg_u, avg_y = lines.info["averaged"]
    P = lines.info["periods"] - lines.info["transient"]
    res = []
    for u, y in zip(avg_u, avg_y):
        n = u.shape[0]
        w = 2 * np.pi * np.arange(n // 2 + 1) / (n * m.dt)
        Y = np.einsum("kij,kj->ki", m.freqresp(w), np.fft.rfft(u, axis=0))
        res.append(y - np.fft.irfft(Y, n=n, axis=0))
    r = np.concatenate(res)
    return P * np.mean(r ** 2, axis=0)
