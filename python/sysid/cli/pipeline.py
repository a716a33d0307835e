"""The command's pipeline: compress, sweep the orders, fit, validate, write the report
(:func:`identify`), and the summary it prints."""

from __future__ import annotations

import time
import warnings
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .._display import pvalue
from ..data.iodata import IOData
from ..errors import DataError, OrderError


def identify(
    est_data: IOData,
    val_data: IOData | None,
    *,
    order: str | int = "auto",
    method: str = "moesp",
    horizon: int | None = None,
    report: str | Path | None = None,
    preprocessing: dict[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
    uncertainty: str | None = None,
    n_boot: int = 100,
    compressor: str = "auto",
    bars: bool | None = False,
    feedthrough: bool | str | None = None,
) -> dict[str, Any]:
    """Identify, validate and (optionally) write a report; returns a summary dict.

    ``order="auto"``: the rule of the subspace methods' ``order="auto"``, on ``est_data`` alone
    (held-out blocks of it: ``select_order(criterion="cv")``); ``val_data`` are only reported
    on, so the fit reported there is not flattered by the choice.

    ``feedthrough``: estimate ``D``; ``"auto"``: decided once from the estimation data,
    :func:`sysid.subspace.feedthrough.choose_feedthrough`; default as every sysid state-space
    estimator: ``D = 0`` at a given order, ``"auto"`` with ``order="auto"``.

    A time series (no inputs) without ``horizon`` is fitted at the time-series default
    horizons (:mod:`sysid.subspace.series_horizon`, as ``sysid.moesp(data, n)``): the order
    sweep at the autoregression's past (future = past), the model of the order chosen or
    given at its own, shorter future (``model.info["horizon_selection"]``).

    ``compressor`` is passed to :class:`~sysid.SubspaceEstimator` (its decision is in
    ``model.info["compression"]``); ``bars`` draws progress bars in the order sweep (None:
    on a terminal). ``uncertainty="bootstrap"`` attaches the residual-bootstrap parameter
    uncertainty (``n_boot`` records) so the report's pole table has standard deviations.

    The summary holds ``model``, ``selection`` (:class:`~sysid.validation.criteria.OrderSelection`),
    ``compare``, ``prediction`` (validation 1-step), ``residuals``, ``warnings`` (of the run:
    in the report's summary, and re-issued) and, with ``report``, the written ``files``.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = _pipeline(est_data, val_data, order=order, method=method, horizon=horizon,
                        report=report, preprocessing=preprocessing, progress=progress,
                        uncertainty=uncertainty, n_boot=n_boot, compressor=compressor,
                        bars=bars, caught=caught, feedthrough=feedthrough)
    from ..analysis.report_page import reissue

    out["warnings"] = reissue(caught)
    return out


def _pipeline(est_data: IOData, val_data: IOData | None, *, order: str | int, method: str,
              horizon: int | None, report: Any, preprocessing: Any, progress: Any, uncertainty:
              str | None, n_boot: int, compressor: str, bars: Any, caught: list[Any],
              feedthrough: bool | str | None = None) -> Any:
    from ..subspace.estimator import SubspaceEstimator
    from ..subspace.feedthrough import check_feedthrough, choose_feedthrough, default_feedthrough
    from ..subspace.shortcuts import _at_order_future, order_estimator
    from ..validation.criteria import select_order

    say = progress or (lambda _msg: None)
    if order != "auto":  # its form is checked before the record is compressed
        if isinstance(order, str):
            if not order.isdigit():
                raise DataError(f"--order must be 'auto' or a positive integer, got {order!r}")
            order = int(order)
        if order < 1:
            raise DataError(f"--order must be >= 1, got {order}")
    say(f"compressing {est_data.n_samples} samples "
        f"({est_data.n_inputs} in, {est_data.n_outputs} out, horizon {horizon or 'default'})")
    t0 = time.perf_counter()
    # a time series without --horizon: the default horizons of moesp(data, order), from its
    # AIC autoregression (:mod:`sysid.subspace.series_horizon`; "auto": future = past)
    series = est_data.n_inputs == 0 and horizon is None
    est = (order_estimator(est_data, order, None, method, compressor=compressor)
           if series and order != "auto" else
           SubspaceEstimator(est_data, horizon, method=method, compressor=compressor))
    dt_c = time.perf_counter() - t0
    say(f"compressed with {est.factor.source} in {dt_c:.2f} s "
        f"({est_data.n_samples / max(dt_c, 1e-9) / 1e6:.1f} M samples/s)")
    if order != "auto":
        if order > est.max_order:
            raise OrderError(
                f"order {order} is larger than the data and horizon support (at most "
                f"{est.max_order} with horizon {est.past}); lower --order or raise --horizon"
            )
    if check_feedthrough(default_feedthrough(feedthrough, order)) == "auto":
        feedthrough, why = choose_feedthrough(est, "auto" if order == "auto" else int(order))
        say(f"feedthrough: {why['reason']}")
    top = min(est.max_order, max(10, 2 * est.auto_order, 0 if order == "auto" else int(order)))
    while True:
        say(f"sweeping orders 1..{top} on one compression")
        # chosen on the estimation part alone (the rule of order="auto"), so that the fit
        # reported on the validation part is an honest one; the sweep's table shows both
        sel = select_order(est, range(1, top + 1), validation=val_data, progress=bars,
                           feedthrough=bool(feedthrough),
                           criterion="cv" if order == "auto" else None)
        if order != "auto" or sel.order < top or top >= est.max_order:
            break
        # the best order sits at the edge of the sweep: look further
        top = min(est.max_order, 2 * top)
    n = sel.order if order == "auto" else int(order)
    if order != "auto":
        sel = sel.given(n)  # the summary and report say the order was given, not chosen
    say(f"fitting order {n} ({est.method})")
    # B, D from the regression on the factor: on the DaISy records it loses less validation
    # fit than B, D, x0 by least squares (benches/results/subspace_defaults.md)
    x0 = False
    if uncertainty is not None:
        say(f"fitting order {n} with a residual bootstrap of {n_boot} records")
    # the model saved and reported is the one the sweep validated (same fit, same settings);
    # the bootstrap adds its uncertainty without changing the estimate
    fit_kw = {} if uncertainty is None else {"x0": x0, "uncertainty": uncertainty,
                                             "n_boot": n_boot, "rng": 0}
    model = (sel.model(n, est.method) if uncertainty is None
             else est.fit(n, feedthrough=bool(feedthrough), **fit_kw))
    if series and order == "auto":  # refitted at the chosen order's future, as moesp's
        model = _at_order_future(est, model, est_data, est.method, None, compressor, **fit_kw)
    model.info["settings"] = {**model.info.get("settings", {}), "method": est.method,
                              "order": n, "order_rule": (
        sel.criterion if order == "auto" else "given"), "x0": x0,
        "past": model.info.get("settings", {}).get("past", est.past),
        "future": model.info.get("settings", {}).get("future", est.future)}
    model.info["preprocessing"] = {**model.info.get("preprocessing", {}),
                                   **dict(preprocessing or {})}
    return _validate(model, sel, est_data, val_data, report, say, caught)


def _validate(model: Any, sel: Any, est_data: IOData, val_data: IOData | None,
              report: str | Path | None, say: Callable[[str], None],
              caught: list[Any] | None = None) -> dict[str, Any]:
    """Simulation and prediction fits, residuals and the report of one model (``caught``:
    the warnings of the run so far, for the report's summary)."""
    from ..validation.compare import compare_quiet as compare  # the summary shows -inf
    from ..validation.residuals import default_max_lag, residuals

    check = val_data if val_data is not None else est_data
    which = "validation" if val_data is not None else "estimation"
    say(f"validating on the {which} data")
    sim = compare(model, check)
    pred = compare(model, check, horizon=1)
    res = residuals(model, check, max_lag=default_max_lag(check))
    out: dict[str, Any] = {"model": model, "selection": sel, "compare": sim,
                           "prediction": pred, "residuals": res, "which": which}
    if report is not None:
        say(f"writing the report to {report}")
        out["files"] = _write_report(Path(report), out, check, list(caught or []))
    say("done")
    return out


def _write_report(root: Path, out: dict[str, Any], check: Any,
                  run_warnings: list[Any]) -> dict[str, Path]:
    from ..analysis.report import report

    return report(out["model"], check, root, selection=out["selection"], which=out["which"],
                  max_lag=out["residuals"].max_lag, warnings=run_warnings)


def _print_summary(out: dict[str, Any]) -> None:
    model, sel = out["model"], out["selection"]
    print(model)
    print("order choice:", sel.reason)
    print("poles:", np.array2string(model.poles(), precision=4))
    for kind, r in (("simulation", out["compare"]), ("1-step prediction", out["prediction"])):
        fits = ", ".join(f"{n}: {f:.1f} %" for n, f in zip(r.output_names, r.fit.mean(0)))
        print(f"{out['which']} fit ({kind}): {fits}")
    res = out["residuals"]
    print("residual whiteness (Ljung-Box): " + ", ".join(
        f"{n}: {pvalue(p, 3)}" for n, p in zip(res.output_names, res.ljung_box_pvalue)))
    if "files" in out:
        print(f"report: {out['files']['html']}")



def _check_report_dir(report: str | Path) -> None:
    p = Path(report)
    if p.exists() and not p.is_dir():
        raise DataError(f"--report {str(p)!r} is an existing file, not a directory; give a "
                        "directory name (it is created if missing)")

