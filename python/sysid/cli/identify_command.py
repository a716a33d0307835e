"""``sysid identify``: a record read from a file, split, detrended, identified (by
:func:`sysid.identify` or a subspace method's order sweep), and the model saved so that
it predicts the file's raw signals."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError, InsufficientDataError
from ..validation.crossval import MIN_BLOCK
from .load import _load, fill_gaps
from .pipeline import _check_report_dir, _print_summary, _validate, identify
from .progress import _bars, _Progress


def _split_index(split: str, n: int) -> int:
    try:
        val = float(split)
    except ValueError:
        raise DataError(f"--split must be a fraction (0.5) or a sample count (500), "
                        f"got {split!r}") from None
    if val > 1 and not split.strip().isdigit():
        raise DataError(f"--split {split} is neither a fraction in (0, 1] nor a whole "
                        f"sample count; give e.g. 0.5 or {int(val)}")
    k = int(round(val * n)) if val <= 1 else int(val)
    if not 0 < k <= n:
        raise DataError(f"--split {split} leaves no estimation data (record has {n} samples)")
    return k


def _check_parts(split: str, n: int, k: int, by_identify: bool) -> None:
    """The parts ``--split`` leaves, long enough, before any check of their channels (a
    3-row file left one validation sample, reported as "output y is constant")."""
    need = 2 * MIN_BLOCK  # identify holds out two blocks of MIN_BLOCK samples at least
    if by_identify and n < need:
        raise InsufficientDataError(
            f"the record is too short: it has {n} samples, and sysid.identify holds out two "
            f"blocks of {MIN_BLOCK} from the estimation part (at least {need}); pass a longer "
            "record")
    if by_identify and k < need:
        raise InsufficientDataError(
            f"the record is too short: --split {split} leaves {k} of its {n} samples for "
            f"estimation, and sysid.identify holds out two blocks of {MIN_BLOCK} from them "
            f"(at least {need}); pass a longer record or a larger --split")
    if 0 < n - k < 2:
        raise InsufficientDataError(
            f"the record is too short: --split {split} leaves {n - k} validation sample of "
            f"its {n}, and a fit needs an output that can vary; pass a longer record or a "
            "smaller --split")



def _identify(args: argparse.Namespace) -> int:
    from ..subspace.estimator import _method

    auto = args.method == "auto" and args.order == "auto"
    if not auto:
        _method("moesp" if args.method == "auto" else args.method)  # before reading anything
    _check_report_dir(args.report)
    if args.horizon is not None and args.horizon < 1:
        raise DataError(f"--horizon must be a positive integer, got {args.horizon}")
    say = _Progress(args.quiet)
    names, ui, yi, u, y, t = _load(args, say)
    from ..identify.command import refuse_still_part, uniform_time

    pre: dict[str, Any] = {"file": str(args.data), "inputs": [names[i] for i in ui],
                           "outputs": [names[i] for i in yi]}
    u, y, t, filled = fill_gaps(u, y, t, args.fill_gaps, [names[i] for i in ui + yi], say)
    if filled is not None:
        pre["filled_gaps"] = filled
    if t is not None:
        if args.dt is not None:
            raise DataError("give either --dt or --time, not both")
        # the dt the column was written with (0.1, not 0.10000000000000009), after checking
        # it is uniform, as IOData.from_csv reads it (gaps and jitter were read at the
        # median); or the record interpolated onto a uniform grid (--resample)
        u, y, t, dt = uniform_time(u, y, t, args.time, args.resample, args.resample_gap,
                                   say, pre)
    elif args.resample is not None:
        raise DataError("--resample needs a time column (--time COLUMN)")
    else:
        dt = 1.0 if args.dt is None else float(args.dt)
    N = y.shape[0]
    k = _split_index(args.split, N)
    # the default path is sysid.identify, unless the options ask for a subspace fit
    via_identify = auto and bool(ui) and args.uncertainty == "none" and args.horizon is None
    _check_parts(args.split, N, k, via_identify)
    refuse_still_part(u, y, k, args.split, pre["inputs"], pre["outputs"],  # one part only
                      via_identify or args.detrend != "none")
    pre.update({"estimation_samples": [0, k], "validation_samples": [k, N]})
    if args.detrend == "auto":
        # sysid.identify removes the offsets itself (and restores them in the saved model);
        # every other path fits a linear model, which has no constant term: a record on an
        # offset gives it a pole near 1 and a wrong gain (fits far below zero on the DaISy
        # and other real records), so the estimation part's means are taken out first
        args.detrend = "none" if via_identify else "mean"
    trend = None  # the lines --detrend linear takes out, as a sysid.Trend
    if args.detrend == "mean":
        mu, my = u[:k].mean(0), y[:k].mean(0)
        u, y = u - mu, y - my
        pre["removed_means"] = {"inputs": mu.tolist(), "outputs": my.tolist()}
    elif args.detrend == "linear":
        # the line fitted on the estimation part, extended over the whole record
        tt = np.arange(N, dtype=float)
        basis = np.c_[np.ones(N), tt]
        coef_u = np.linalg.lstsq(basis[:k], u[:k], rcond=None)[0] if ui else None
        coef_y = np.linalg.lstsq(basis[:k], y[:k], rcond=None)[0]
        if coef_u is not None:
            u = u - basis @ coef_u
        y = y - basis @ coef_y
        pre["removed_lines"] = {
            "inputs": [] if coef_u is None else coef_u.T.tolist(),
            "outputs": coef_y.T.tolist(), "basis": "offset + slope * sample index"}
        # the same lines as a trend on the record's clock (seconds from its first sample, or
        # from the time column's first instant, as IOData.from_csv reads the file), which the
        # saved model adds back (TrendedModel): offset + slope / dt per second
        no_u = np.zeros((2, 0))
        trend = _line_trend(no_u if coef_u is None else coef_u, coef_y, dt,
                            0.0 if t is None else float(t[0]))
    pre["detrend"] = args.detrend
    kw = {"dt": dt, "input_names": pre["inputs"], "output_names": pre["outputs"]}
    est_data = IOData(u=u[:k] if ui else None, y=y[:k], **kw)
    val_data = IOData(u=u[k:] if ui else None, y=y[k:], **kw) if k < N else None
    if via_identify:
        from ..analysis.report_page import reissue
        from ..identify.command import prepare, write_leaderboard

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            p = prepare(est_data, val_data, pre, _bars(args), say)
            out = _validate(p["model"], p["selection"], p["est"], p["val"], args.report, say,
                            caught)
            if "files" in out and "model" in out["files"]:
                # the file holds the model with its offsets: it predicts the raw signals
                # (the report is of the deviations, which the model of the deviations fits);
                # the means --detrend mean took out first are offsets of it too, the lines
                # --detrend linear took out its trend
                from ..models.serialize import save_model

                m = p["result"].model
                save_model(_raw_model(m.statespace, pre, trend, m.u_offset, m.y_offset),
                           out["files"]["model"])
                out["files"]["leaderboard"] = write_leaderboard(
                    p["result"], Path(out["files"]["model"]).with_name("leaderboard.csv"))
        out["warnings"] = reissue(caught)
        print(p["result"].summary())
        _print_summary(out)
        return 0
    if auto:  # the default path would be sysid.identify: say why it is not taken
        why = ("there are no --inputs (a time-series model)" if not ui else
               "--uncertainty bootstrap needs a subspace fit" if args.uncertainty != "none"
               else "--horizon is given")
        say(f"not sysid.identify: {why}; sweeping the orders of moesp instead (pass "
            f"--method to choose another subspace method)")
    out = identify(est_data, val_data, order=args.order,
                   method="moesp" if args.method == "auto" else args.method,
                   horizon=args.horizon, report=args.report, preprocessing=pre, progress=say,
                   compressor=args.compressor, bars=_bars(args),
                   uncertainty=None if args.uncertainty == "none" else args.uncertainty,
                   n_boot=args.n_boot,
                   feedthrough={"no": False, "yes": True, "auto": "auto"}.get(args.feedthrough))
    if ("removed_means" in pre or trend is not None) and ui and "model" in out.get("files",
                                                                                  {}):
        # as on the identify path: the file holds the model with the means (or lines) taken
        # out first as its offsets (or trend), so that it predicts the raw signals (the report
        # is of the deviations)
        from ..models.serialize import save_model

        save_model(_raw_model(out["model"], pre, trend), out["files"]["model"])
    _print_summary(out)
    return 0


def _line_trend(coef_u: np.ndarray, coef_y: np.ndarray, dt: float, t0: float) -> Any:
    """The lines ``offset + slope * sample index`` (``coef_*``: rows offset, slope; a column
    per channel) fitted on the estimation part, as a :class:`sysid.Trend` that applies to
    other data: ``offset + slope / dt * t``, ``t`` seconds from the record's start ``t0``
    (what :func:`sysid.detrend` with ``"linear"`` returns)."""
    from ..data.trend import Trend

    cu, cy = np.atleast_2d(coef_u), np.atleast_2d(coef_y)
    return Trend([], [], np.ones(cu.shape[1]), np.ones(cy.shape[1]), kind="linear",
                 offsets=(cu[0].copy(), cy[0].copy()), slopes=(cu[1] / dt, cy[1] / dt),
                 dt=dt, t0=t0)


def _raw_model(model: Any, pre: dict[str, Any], trend: Any, u_offset: Any = 0.0,
               y_offset: Any = 0.0) -> Any:
    """The model ``model.json`` holds: ``model`` (of the deviations from ``u_offset``,
    ``y_offset``: identify's, about the record it was given) taking and returning the
    file's raw signals. The means ``--detrend mean`` took out first are offsets of it too
    (an :class:`~sysid.identify.result.IdentifiedModel`); the lines ``--detrend linear``
    took out, its trend (a :class:`~sysid.models.trended.TrendedModel`: the lines' offsets
    plus ``u_offset``, ``y_offset``, their slopes, on the record's clock). A model fitted
    on the detrended record alone predicted only the deviations (a record on a trend of 0.01
    per sample from 50: simulations about 0.8 where the output is 57.5, a fit of -2615 %)."""
    from ..identify.result import IdentifiedModel

    u0 = np.zeros(model.ninputs) + np.asarray(u_offset, float)
    y0 = np.zeros(model.noutputs) + np.asarray(y_offset, float)
    if trend is not None:
        from ..data.trend import Trend
        from ..models.trended import TrendedModel

        line = Trend([], [], trend.u_scale, trend.y_scale, kind="linear",
                     offsets=(trend.u_offset + u0, trend.y_offset + y0),
                     slopes=(trend.u_slope, trend.y_slope), dt=trend.dt, t0=trend.t0)
        return TrendedModel(model, line)
    if "removed_means" in pre:
        u0 = u0 + np.asarray(pre["removed_means"]["inputs"], float)
        y0 = y0 + np.asarray(pre["removed_means"]["outputs"], float)
    return IdentifiedModel(model, u0, y0)

