"""Best linear approximation (BLA) from periodic excitation: the robust method.

With ``R`` realisations (experiments with independent random-phase multisines) of ``P``
steady-state periods each, the DFT of every period gives, at the excited lines ``k``,

.. code-block:: text

    G[r, p](k) = Y[r, p](k) U[r, p](k)^-1                      (one period, one realisation)
    G[r](k)    = mean_p G[r, p](k),    s2_n[r](k) = var_p G[r, p](k) / P     (noise)
    G_BLA(k)   = mean_r G[r](k),       s2_BLA(k)  = var_r G[r](k) / R        (total)
    s2_n(k)    = mean_r s2_n[r](k) / R                                    (noise part)
    s2_S(k)    = R (s2_BLA(k) - s2_n(k))            (nonlinear distortion, one realisation)

(Pintelon & Schoukens, *System Identification: A Frequency Domain Approach*, 2nd ed., 2012,
the robust method of Section 4.3). ``s2_BLA`` is the variance of the averaged estimate;
``s2_S`` the variance of the stochastic nonlinear contribution of one realisation, which a
linear model cannot explain. With several inputs, ``m`` consecutive experiments form one
realisation block and ``U`` is an ``m x m`` matrix per line (their phases must differ).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.iodata import IOData, require_record
from ..errors import DataError
from ..models.frd import FRD
from ..validation.output_error import feedback_checked

__all__ = ["bla", "bla_model"]


def _periods(x: np.ndarray, n_per: int, periods: int, transient: int) -> np.ndarray:
    """``(periods - transient, n_per, channels)`` DFTs of the steady-state periods."""
    x = x[: periods * n_per].reshape(periods, n_per, -1)[transient:]
    return np.fft.fft(x, axis=1)


#: A drop in input power between consecutive lines (sorted by power) of more than this
#: factor separates the excited lines from those a measured input carries without being
#: excited there (its own distortion, feedback of the structure, noise).
LINE_GAP = 100.0


def _excited(U: np.ndarray, lines: Any, n_per: int) -> tuple[np.ndarray, np.ndarray]:
    """Excited DFT lines (1 .. n_per // 2 - 1) and the lines left out as not excited.

    Given, or found from the input power of every experiment: above 1e-8 of the largest (a
    random-odd grid leaves out different lines in each realisation, and those are dropped),
    and above the first drop of more than :data:`LINE_GAP` when the lines are sorted by
    power. A measured input (a shaker's force) holds periodic power at lines the multisine
    does not excite, 1e-4 and less of the excited lines' (the F-16 record: 821 such lines
    next to 267 excited ones); ``Y / U`` there is the ratio of two distortions, up to 100
    times the response, and was returned as part of the BLA."""
    if lines is not None:
        k = np.unique(np.asarray(lines, dtype=int).ravel())
        if k.size == 0 or k.min() < 1 or k.max() >= n_per / 2.0:
            raise DataError(f"lines must lie in 1..{int(np.ceil(n_per / 2.0)) - 1}")
        return k, np.zeros(0, dtype=int)
    power = np.sum(np.abs(U) ** 2, axis=(1, 3))[:, : (n_per + 1) // 2]
    power[:, 0] = 0.0
    rel = np.min(power / np.maximum(power.max(axis=1, keepdims=True), 1e-300), axis=0)
    k = np.flatnonzero(np.all(power > 1e-8 * power.max(), axis=0))
    if k.size == 0:
        raise DataError("the input excites no frequency line; is the input zero?")
    level = np.sort(np.log10(np.maximum(rel[k], 1e-300)))[::-1]
    drops = np.flatnonzero(level[:-1] - level[1:] > np.log10(LINE_GAP))
    if drops.size == 0:
        return k, np.zeros(0, dtype=int)
    floor = level[drops[0]]
    keep = np.log10(np.maximum(rel[k], 1e-300)) >= floor
    return k[keep], k[~keep]


def bla(
    data: IOData,
    periods: int | str,
    *,
    transient: int | None = None,
    lines: Any = None,
    confidence: float = 0.95,
) -> FRD:
    """Best linear approximation from periodic data, with noise and distortion variances.

    Parameters
    ----------
    data : IOData
        One experiment per realisation (independent random-phase multisines, e.g.
        ``sysid.multisine(..., phases="random", seed=r)``), each holding ``periods`` whole
        periods of the same length. With ``m`` inputs, every ``m`` consecutive experiments
        form one realisation block (their phases must differ so that the ``m x m`` input
        matrix of each line is invertible).
    periods : int or "auto"
        Periods in each experiment (the record length must be a multiple). ``"auto"``: the
        period the input repeats with (:func:`sysid.detect_period`, exact repetition in
        every experiment; a trailing partial period is dropped), as ``pem``'s
        ``periods="auto"``; ``info["periodicity"]`` says what was found.
    transient : int, optional
        Leading periods to drop (transients); ``periods - transient >= 2`` gives the noise
        variance, and two realisation blocks or more the nonlinear-distortion variance.
        Default 0 with a declared ``periods`` (they are in steady state), 1 with ``"auto"``
        (the usual practice with a multisine applied from rest).
    lines : array_like of int, optional
        Excited DFT lines of one period; default: the lines the input excites, found from
        its power (above 1e-8 of the largest in every experiment, and above the first drop
        by more than a factor 100 between lines sorted by power: the periodic power that a
        measured input holds between its excited lines is left out; the lines so left out
        are ``info["unexcited_lines"]``).
    confidence : float
        Level of the band of the returned FRD.

    Returns
    -------
    FRD
        ``G_BLA`` at the excited lines with ``std`` the standard deviation of the estimate
        (total: noise plus nonlinear distortions over the realisations, or the noise alone
        with one realisation). ``info`` holds ``noise_std`` (noise part of the estimate's
        std), ``distortion_std`` (std of the nonlinear distortion of one realisation,
        ``sqrt(s2_S)``; NaN with one realisation), ``lines``, ``n_per``, ``periods``,
        ``realizations``, and the period-averaged steady-state record (``averaged``) that
        :func:`bla_model` refines on.

    Examples
    --------
    A Wiener system (linear block, then ``x + 0.2 x^3``) excited by four random-phase
    multisines of two periods:

    >>> import numpy as np, sysid
    >>> G = sysid.StateSpaceModel([[0.7]], [[1.0]], [[0.3]], dt=1.0)
    >>> us = [sysid.multisine(256, band=(0, 0.8), phases="random", seed=r, periods=3)
    ...       for r in range(4)]
    >>> ys = [(lambda x: x + 0.2 * x**3)(G.simulate(u)) for u in us]
    >>> f = sysid.bla(sysid.IOData(us, ys, 1.0), periods=3, transient=1)
    >>> f.method, f.response.shape[1:]
    ('bla', (1, 1))
    >>> bool(np.all(f.info["distortion_std"] > 0))
    True
    """
    data = require_record(data, "bla", pairs=False)
    from .._checks import as_int

    found = None
    if isinstance(periods, str) and periods == "auto":
        from ..data.periodicity import detect, whole_periods

        found, why = detect(data)
        if found is None:
            raise DataError(f"bla averages whole periods of a periodic excitation, and "
                            f"{why}: use sysid.spa or sysid.welch_frf for non-periodic data")
        data, periods = whole_periods(data, found), found.periods
        transient = 1 if transient is None else transient
    P = as_int(periods, "periods", 1, alt="'auto'")  # not "auto": checked above
    T = as_int(0 if transient is None else transient, "transient", 0)
    if P - T < 1:
        raise DataError(f"transient ({T}) leaves no period of the {P}; lower it")
    exps = data.experiments
    m, ell = exps[0][0].shape[1], exps[0][1].shape[1]
    if m == 0:
        raise DataError("bla needs inputs; the data have none")
    if len(exps) % m:
        raise DataError(f"{len(exps)} experiments for {m} inputs: give a multiple of {m} "
                        "(each block of m experiments is one realisation)")
    n_tot = exps[0][0].shape[0]
    if any(u.shape[0] != n_tot for u, _ in exps) or n_tot % P:
        raise DataError(f"every experiment must hold {P} whole periods of one length; "
                        f"got lengths {[u.shape[0] for u, _ in exps]}")
    n_per = n_tot // P
    U = np.stack([_periods(u, n_per, P, T) for u, _ in exps])  # (E, P', N, m)
    Y = np.stack([_periods(y, n_per, P, T) for _, y in exps])  # (E, P', N, l)
    if U.shape[1] > 1:  # the averages over periods assume the input repeats
        mean = U.mean(axis=1, keepdims=True)
        spread = float(np.sqrt(np.mean(np.abs(U - mean) ** 2)))  # the spectra of the periods
        level = float(np.sqrt(np.mean(np.abs(mean) ** 2)))
        if spread > 0.5 * level:
            raise DataError(
                f"the input does not repeat every {n_per} samples (its periods differ by "
                f"{spread / max(level, 1e-300):.2g} of their own level): bla averages whole "
                "periods of a periodic excitation; give the true number of periods "
                "(sysid.detect_period finds it), or use sysid.spa / sysid.welch_frf for "
                "non-periodic data")
    k, unexcited = _excited(U, lines, n_per)
    R = len(exps) // m
    Pp = P - T
    # (R, P', K, l, m) and (R, P', K, m, m): experiments of one block side by side
    Ub = U[:, :, k, :].reshape(R, m, Pp, k.size, m).transpose(0, 2, 3, 4, 1)
    Yb = Y[:, :, k, :].reshape(R, m, Pp, k.size, ell).transpose(0, 2, 3, 4, 1)
    cond = np.linalg.cond(Ub.reshape(-1, m, m))
    if not np.all(np.isfinite(cond)) or cond.max() > 1e10:
        raise DataError("the input matrix of some excited line is singular: with several "
                        "inputs use independent phases per experiment, or give lines=")
    Gp = Yb @ np.linalg.inv(Ub)  # (R, P', K, l, m)
    Gr = Gp.mean(axis=1)
    Gbla = Gr.mean(axis=0)
    noise = (np.sum(np.abs(Gp - Gr[:, None]) ** 2, axis=1) / (Pp * (Pp - 1))
             if Pp > 1 else np.full(Gr.shape, np.nan))
    s2n = noise.mean(axis=0) / R
    if R > 1:
        s2bla = np.sum(np.abs(Gr - Gbla) ** 2, axis=0) / (R * (R - 1))
        s2s = R * np.maximum(s2bla - np.nan_to_num(s2n), 0.0)
        std = np.sqrt(s2bla)
    else:
        s2s = np.full(Gbla.shape, np.nan)
        std = np.sqrt(s2n)
    dt = float(data.dt)
    avg_u = [np.real(np.fft.ifft(U[e].mean(axis=0), axis=0)) for e in range(len(exps))]
    avg_y = [np.real(np.fft.ifft(Y[e].mean(axis=0), axis=0)) for e in range(len(exps))]
    dof = 2.0 * (R - 1) if R > 1 else (2.0 * (Pp - 1) if Pp > 1 else None)
    info = {"noise_std": np.sqrt(s2n), "distortion_std": np.sqrt(s2s), "lines": k,
            "unexcited_lines": unexcited, "n_per": n_per, "periods": P, "transient": T,
            "realizations": R,
            "averaged": (avg_u, avg_y)}
    if found is not None:
        info["periodicity"] = {"periods": "auto", "period": found.period,
                               "whole_periods": found.periods,
                               "unused_samples": list(found.unused), "mismatch": found.mismatch}
    return FRD(2 * np.pi * k / (n_per * dt), Gbla,
               std=None if not np.all(np.isfinite(std)) else std, confidence=confidence,
               dof=dof, dt=dt, input_names=data.input_names, output_names=data.output_names,
               method="bla", info=info)


def bla_model(frd: FRD, order: int, *, refine: bool = True, max_iter: int = 50,
              feedthrough: bool = False) -> Any:
    """A linear state-space model of a BLA: weighted frequency-domain subspace, then refined.

    The subspace fit weights each line by the inverse variance of the BLA (its ``std``);
    the refinement minimises the simulation error of the model on the period-averaged,
    steady-state records the BLA came from (``frd.info["averaged"]``; output-error PEM
    with the shared optimiser, periodic so the noise there is already reduced ``P`` times).

    Parameters
    ----------
    frd : FRD
        From :func:`bla`.
    order : int
        State dimension.
    refine : bool
        Run the output-error refinement (kept only if it lowers the weighted FRF misfit).
    max_iter : int
        Iterations of the refinement.
    feedthrough : bool
        Estimate ``D`` (default ``False``: ``D = 0``, as every sysid state-space estimator).

    Returns
    -------
    StateSpaceModel

    Examples
    --------
    >>> import numpy as np, sysid
    >>> G = sysid.StateSpaceModel([[0.7]], [[1.0]], [[0.3]], dt=1.0)
    >>> us = [sysid.multisine(256, band=(0, 0.8), phases="random", seed=r, periods=3)
    ...       for r in range(2)]
    >>> f = sysid.bla(sysid.IOData(us, [G.simulate(u) for u in us], 1.0), periods=3, transient=1)
    >>> m = sysid.bla_model(f, 1)
    >>> bool(abs(m.poles()[0] - 0.7) < 1e-6)
    True
    """
    import sysid

    if not isinstance(frd, FRD) or "averaged" not in frd.info:
        raise DataError("bla_model needs the FRD returned by sysid.bla")
    w = None
    if frd.std is not None and np.all(frd.std > 0):
        w = 1.0 / np.mean(frd.std ** 2, axis=(1, 2))
        w = w / w.mean()
    model = sysid.frd_subspace(frd, int(order), weights=w, feedthrough=feedthrough)
    if not refine:
        return model
    avg_u, avg_y = frd.info["averaged"]
    n_per = frd.info["n_per"]
    # two copies of the averaged period: the first settles the state, the second is fitted
    us = [np.vstack([u, u]) for u in avg_u]
    ys = [np.vstack([y, y]) for y in avg_y]
    d = IOData(us, ys, frd.dt, input_names=frd.input_names, output_names=frd.output_names)

    def misfit(mod: Any) -> float:
        e = np.abs(mod.freqresp(frd.omega) - frd.response) ** 2
        wt = 1.0 if frd.std is None else 1.0 / np.maximum(frd.std ** 2, 1e-300)
        return float(np.sum(e * wt))

    try:
        with feedback_checked():  # the averaged periods: no noise, no feedback check
            ref = sysid.pem(d, model, focus="simulation", max_iter=max_iter, progress=False,
                            x0="estimate", feedthrough=feedthrough)
    except Exception:  # noqa: BLE001 - the subspace model stands when the refinement fails
        return model
    del n_per
    return ref if misfit(ref) <= misfit(model) else model
