"""The ``sysid`` command line.

``sysid identify DATA.csv --inputs U --outputs Y --report OUT/``
    Identify a state-space model from a CSV file: split into estimation and validation
    parts, compress once, sweep the orders, fit the chosen order, validate, and write the
    model (JSON), the tables (CSV) and the plots (PNG) with an HTML page that shows them.
``sysid demo [--report DIR]``
    The same on the bundled hair-dryer record (estimation samples 1-500, validation
    501-1000, horizon 15, order auto); prints a short summary.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .data.blocks import read_columns
from .data.iodata import IOData
from .data.table import (
    Table,
    datetime_seconds,
    first_rows,
    header,
    numeric,
    read_table,
    stamps_ns,
    text_bytes,
    units_row,
)
from .data.units import (
    check_dt_against_time,
    split_header,
    time_column,
    time_unit_seconds,
)
from .errors import DataError, InsufficientDataError, OrderError, SysidError
from .validation.crossval import MIN_BLOCK

__all__ = ["main", "read_csv", "read_columns", "identify"]


# -- progress -------------------------------------------------------------------------
class _Progress:
    """Stage lines on stderr with elapsed time (quiet mode prints nothing)."""

    def __init__(self, quiet: bool) -> None:
        self.quiet, self.t0 = quiet, time.perf_counter()

    def __call__(self, msg: str) -> None:
        if not self.quiet:
            print(f"[sysid {time.perf_counter() - self.t0:6.1f} s] {msg}", file=sys.stderr,
                  flush=True)


# -- CSV input ------------------------------------------------------------------------
def read_csv(path: str | Path, delimiter: str | None = None) -> tuple[list[str], np.ndarray]:
    r"""Read a numeric table: ``(column names, values (rows, columns))``.

    The first line is a header of names unless every field in it is a number (then the
    columns are named ``"0", "1", ...``). The delimiter is guessed (semicolon, comma, tab,
    else white space) unless given; a trailing delimiter at the end of every line is
    allowed, and fields may be quoted. Empty lines and lines starting with ``#`` are
    skipped. A field that is not a number raises a :class:`~sysid.DataError` naming its
    column and line. The same reader serves :meth:`sysid.IOData.from_csv`
    (``sysid.data.table``).

    Examples
    --------
    >>> import os, tempfile
    >>> from sysid.cli import read_csv
    >>> path = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("u,y,\n1,2,\n3,4,\n")
    >>> read_csv(path)
    (['u', 'y'], array([[1., 2.],
           [3., 4.]]))
    """
    table = read_table(path, delimiter)
    return table.names, numeric(table, list(range(len(table.names))))


def _columns(spec: str, names: list[str], what: str) -> list[int]:
    want = [s.strip() for s in spec.split(",") if s.strip()]
    if not want:
        raise DataError(f"--{what} is empty; give column names separated by commas")
    idx = []
    for w in want:
        if w in names:
            idx.append(names.index(w))
        else:
            one = len(names) == 1 and any(d in names[0] for d in (",", ";", "|", "\t"))
            raise DataError(f"{what[:-1]} column {w!r} not found; the file has columns: "
                            + ", ".join(names)
                            + ("; the header was read as one column: the file's delimiter is "
                               "not the one used (give it with --delimiter)" if one else ""))
    return idx


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


# -- the pipeline ---------------------------------------------------------------------
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
    from .analysis.report_page import reissue

    out["warnings"] = reissue(caught)
    return out


def _pipeline(est_data: IOData, val_data: IOData | None, *, order: str | int, method: str,
              horizon: int | None, report: Any, preprocessing: Any, progress: Any, uncertainty:
              str | None, n_boot: int, compressor: str, bars: Any, caught: list[Any],
              feedthrough: bool | str | None = None) -> Any:
    from .subspace.estimator import SubspaceEstimator
    from .subspace.feedthrough import check_feedthrough, choose_feedthrough, default_feedthrough
    from .subspace.shortcuts import _at_order_future, order_estimator
    from .validation.criteria import select_order

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
    from .validation.compare import compare_quiet as compare  # the summary shows -inf
    from .validation.residuals import default_max_lag, residuals

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
    from .analysis.report import report

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
    print("residual whiteness (Ljung-Box p): " + ", ".join(
        f"{n}: {p:.3g}" for n, p in zip(res.output_names, res.ljung_box_pvalue)))
    if "files" in out:
        print(f"report: {out['files']['html']}")


# -- commands -------------------------------------------------------------------------
def _demo(args: argparse.Namespace) -> int:
    from .data import datasets

    _check_report_dir(args.report)
    data = datasets.load_dryer()
    print(data)
    u, y = data.u, data.y
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    est_data = IOData(u=u[:500], y=y[:500], **kw)
    val_data = IOData(u=u[500:], y=y[500:], **kw)
    print("estimation: samples 1-500, validation: samples 501-1000, horizon 15")
    out = identify(est_data, val_data, order="auto", horizon=15, report=args.report,
                   preprocessing={"samples": "estimation 1-500, validation 501-1000",
                                  "detrend": "none (raw data, as SLICOT)"},
                   progress=_Progress(args.quiet), uncertainty="bootstrap")
    _print_summary(out)
    return 0


def _check_report_dir(report: str | Path) -> None:
    p = Path(report)
    if p.exists() and not p.is_dir():
        raise DataError(f"--report {str(p)!r} is an existing file, not a directory; give a "
                        "directory name (it is created if missing)")


#: CSV files holding more text than this (decompressed) are read by pyarrow's streaming
#: reader, in blocks.
STREAM_BYTES = 8 << 20
#: how the command says to read decimal commas (in a number's error)
DECIMAL_HINT = "pass --decimal ,"


def _load(args: argparse.Namespace, say: Callable[[str], None]) -> tuple[
        list[str], list[int], list[int], np.ndarray, np.ndarray, np.ndarray | None]:
    """Names, input and output column indices, u, y and the time column if asked, in seconds
    (numbers in the unit of the column's header, units row or name, as
    :meth:`sysid.IOData.from_csv` reads them: ``time_ms``, ``Time [ms]``); a ``--dt`` given
    beside a time column is checked against it, as the readers check ``dt=``."""
    path = Path(args.data)
    # the size that counts is the text's, decompressed; white-space separated files go to
    # read_table (pyarrow splits on one character)
    big = path.is_file() and (path.suffix.lower() in (".parquet", ".pq")
                              or (text_bytes(path, STREAM_BYTES) > STREAM_BYTES
                                  and header(path, args.delimiter, decimal=args.decimal
                                             ).delimiter not in (" ", "\t")))
    if big:
        say(f"reading {args.data} in blocks")
        names = _header(path, args.delimiter, args.decimal)
        ui = _columns(args.inputs, names, "inputs") if args.inputs else []
        yi = _columns(args.outputs, names, "outputs")
        _find_time(args, names, ui + yi, say)
        _check_dt_streamed(args, path, names, ui + yi)
        ti = [_columns(args.time, names, "times")[0]] if args.time is not None else []
        z = read_columns(path, [names[i] for i in ui + yi + ti], delimiter=args.delimiter,
                         progress=_bars(args), stamps=args.time and names[ti[0]],
                         decimal=args.decimal, hint=DECIMAL_HINT)
        u, y = z[:, :len(ui)], z[:, len(ui):len(ui) + len(yi)]
        t = z[:, -1] * _streamed_time_scale(args, path, names[ti[0]]) if ti else None
        return names, ui, yi, u, y, t
    say(f"reading {args.data}")
    dec = args.decimal  # a logger's units row skipped; decimal commas if asked
    table, row_units = units_row(read_table(args.data, args.delimiter, decimal=dec), dec)
    names = table.names
    ui = _columns(args.inputs, names, "inputs") if args.inputs else []
    yi = _columns(args.outputs, names, "outputs")
    say(f"{len(table.rows)} samples; converting {len(ui)} input and {len(yi)} output "
        "column(s)")
    _find_time(args, names, ui + yi, say)
    _check_dt(args, table, row_units, ui + yi)
    u = numeric(table, ui, decimal=dec, hint=DECIMAL_HINT)
    y = numeric(table, yi, decimal=dec, hint=DECIMAL_HINT)
    t = None
    if args.time is not None:
        ti = _columns(args.time, names, "times")[0]
        t = _time_seconds(table, ti, row_units, dec)
    return names, ui, yi, u, y, t


def _seconds_per_unit(name: str, row_unit: str = "") -> float:
    """Seconds per unit of a numeric time column named ``name``, as
    :meth:`sysid.IOData.from_csv` takes it: the ``[unit]`` of its header, else the logger's
    units row (``row_unit``), else its name (``(ms)``, ``time_ms``): one function,
    :func:`sysid.data.units.time_unit_seconds`; seconds without one."""
    return time_unit_seconds(name, split_header(name, row_unit)[1])


def _time_seconds(table: Table, k: int, row_units: dict[int, str], dec: str) -> np.ndarray:
    """Column ``k`` of ``table`` in seconds: date-time stamps as seconds after the first,
    numbers in the column's unit (:func:`_seconds_per_unit`)."""
    t = datetime_seconds(table, k, dec)
    if t is not None:
        return t
    return (numeric(table, [k], decimal=dec, hint=DECIMAL_HINT)[:, 0]
            * _seconds_per_unit(table.names[k], row_units.get(k, "")))


def _check_dt(args: argparse.Namespace, table: Table, row_units: dict[int, str],
              used: list[int]) -> None:
    """``--dt`` given while the file has a time column (``time``, ``time_ms``, ``Time [s]``,
    ...: not an input or output, and not read then): they must agree, as
    ``IOData.from_csv(dt=...)`` requires of the same file (a column 10 ms apart read at
    --dt 10, or at a --dt off by the column's unit, was taken silently). A column that is
    not numbers or date-time stamps is not compared."""
    k = time_column(table.names, used)
    if args.dt is None or args.time is not None or k is None:
        return
    try:
        t = _time_seconds(table, k, row_units, args.decimal)
    except DataError:
        return  # text, not times: nothing to compare
    _refuse_dt(args, t, table.names[k], _seconds_per_unit(table.names[k],
                                                          row_units.get(k, "")))


def _refuse_dt(args: argparse.Namespace, t: np.ndarray, name: str, unit: float) -> None:
    """The readers' test (:func:`sysid.data.units.check_dt_against_time`) of ``--dt``
    against the time column ``name`` (``t`` in seconds; ``unit``: seconds per its unit),
    its error in the command's terms."""
    try:
        check_dt_against_time(t, float(args.dt), name)
    except DataError:
        spacing = float(np.median(np.diff(t)))
        raise DataError(
            f"{Path(args.data).name}: --dt {args.dt:g} s disagrees with its time column "
            f"{name!r}, whose samples are {spacing:g} s apart"
            + (f" (its numbers are in units of {unit:g} s)" if unit != 1.0 else "")
            + "; leave --dt out (the time column gives the sample time), or correct it "
            "(--dt is in seconds)") from None


def _check_dt_streamed(args: argparse.Namespace, path: Path, names: list[str],
                       used: list[int]) -> None:
    """:func:`_check_dt` for a file read in blocks: on its first rows (CSV), or on its time
    column when that holds numbers (Parquet)."""
    k = time_column(names, used)
    if args.dt is None or args.time is not None or k is None:
        return
    if path.suffix.lower() in (".parquet", ".pq"):
        import pyarrow as pa
        import pyarrow.parquet as pq

        pf = pq.ParquetFile(path)
        kind = pf.schema_arrow.field(names[k]).type
        if pa.types.is_integer(kind) or pa.types.is_floating(kind):
            col = pf.read(columns=[names[k]]).column(0).to_numpy(zero_copy_only=False)
            unit = _seconds_per_unit(names[k])
            _refuse_dt(args, np.asarray(col, float) * unit, names[k], unit)
        return
    head = header(path, args.delimiter, decimal=args.decimal)
    table, row_units = units_row(first_rows(path, head, _CHECK_ROWS), args.decimal)
    _check_dt(args, table, row_units, used)


#: rows at the start of a file read in blocks on which a --dt is checked against its time
#: column (the median spacing of the whole column is the same on a uniformly sampled record)
_CHECK_ROWS = 2000


def _streamed_time_scale(args: argparse.Namespace, path: Path, name: str) -> float:
    """Seconds per unit of the time column ``name`` of a file read in blocks (1 when it holds
    date-time stamps, which the block reader returns in seconds; a Parquet file has no
    units row)."""
    if path.suffix.lower() in (".parquet", ".pq"):
        return _seconds_per_unit(name)
    head = header(path, args.delimiter, decimal=args.decimal)
    table, row_units = units_row(first_rows(path, head, 3), args.decimal)
    k = head.names.index(name)
    if table.rows and k < len(table.rows[0]) and stamps_ns([table.rows[0][k]])[0] is not None:
        return 1.0
    return _seconds_per_unit(name, row_units.get(k, ""))


def _find_time(args: argparse.Namespace, names: list[str], used: list[int],
               say: Callable[[str], None]) -> None:
    """Without --time or --dt: the file's time column (``time``, ``t``, ``Time [s]``, ...;
    not an input or output) gives the sample time, said on stderr; without one, dt = 1 s
    is assumed with a warning (a silent dt = 1 made every frequency, time constant and
    continuous-time model of the report wrong by the true sample time)."""
    if args.time is not None or args.dt is not None:
        return
    k = time_column(names, used)
    if k is not None:
        args.time = names[k]
        say(f"sample time from the time column {names[k]!r} (--time names another; a --dt "
            "must agree with it)")
        return
    # printed as the command's warnings are (--quiet silences progress, not this)
    print(f"sysid: warning: {Path(args.data).name} has no time column (time, t, Time [s], "
          "timestamp, ...) and no --dt or --time was given: assuming a sample time of 1 s "
          "(the report's frequencies and time constants are then per sample); pass --dt "
          "SECONDS or --time COLUMN", file=sys.stderr)


def _bars(args: argparse.Namespace) -> bool | None:
    """Progress bars: asked (--progress), silenced (--quiet), else on a terminal only."""
    return True if args.progress else False if args.quiet else None


def _header(path: Path, delimiter: str | None, decimal: str = ".") -> list[str]:
    """The column names of a file read in blocks (a text table's as ``read_table`` names
    them: ``"0", "1", ...`` without a header)."""
    if path.suffix.lower() in (".parquet", ".pq"):
        import pyarrow.parquet as pq

        return list(pq.ParquetFile(path).schema_arrow.names)
    return header(path, delimiter, decimal=decimal).names


def _identify(args: argparse.Namespace) -> int:
    from .subspace.estimator import _method

    auto = args.method == "auto" and args.order == "auto"
    if not auto:
        _method("moesp" if args.method == "auto" else args.method)  # before reading anything
    _check_report_dir(args.report)
    if args.horizon is not None and args.horizon < 1:
        raise DataError(f"--horizon must be a positive integer, got {args.horizon}")
    say = _Progress(args.quiet)
    names, ui, yi, u, y, t = _load(args, say)
    from .identify.command import refuse_still_part, uniform_time

    pre: dict[str, Any] = {"file": str(args.data), "inputs": [names[i] for i in ui],
                           "outputs": [names[i] for i in yi]}
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
        from .analysis.report_page import reissue
        from .identify.command import prepare, write_leaderboard

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
                from .models.serialize import save_model

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
        from .models.serialize import save_model

        save_model(_raw_model(out["model"], pre, trend), out["files"]["model"])
    _print_summary(out)
    return 0


def _line_trend(coef_u: np.ndarray, coef_y: np.ndarray, dt: float, t0: float) -> Any:
    """The lines ``offset + slope * sample index`` (``coef_*``: rows offset, slope; a column
    per channel) fitted on the estimation part, as a :class:`sysid.Trend` that applies to
    other data: ``offset + slope / dt * t``, ``t`` seconds from the record's start ``t0``
    (what :func:`sysid.detrend` with ``"linear"`` returns)."""
    from .data.trend import Trend

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
    from .identify.result import IdentifiedModel

    u0 = np.zeros(model.ninputs) + np.asarray(u_offset, float)
    y0 = np.zeros(model.noutputs) + np.asarray(y_offset, float)
    if trend is not None:
        from .data.trend import Trend
        from .models.trended import TrendedModel

        line = Trend([], [], trend.u_scale, trend.y_scale, kind="linear",
                     offsets=(trend.u_offset + u0, trend.y_offset + y0),
                     slopes=(trend.u_slope, trend.y_slope), dt=trend.dt, t0=trend.t0)
        return TrendedModel(model, line)
    if "removed_means" in pre:
        u0 = u0 + np.asarray(pre["removed_means"]["inputs"], float)
        y0 = y0 + np.asarray(pre["removed_means"]["outputs"], float)
    return IdentifiedModel(model, u0, y0)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="sysid", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="identify the bundled hair-dryer record")
    demo.add_argument("--report", default="report", help="report directory (default ./report)")
    demo.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    demo.set_defaults(func=_demo)
    ide = sub.add_parser("identify", help="identify a model from a CSV file")
    ide.add_argument("data", help="CSV file (header row of column names, numeric rows) or "
                     "Parquet file; files over 8 MB are read in blocks with a progress bar")
    ide.add_argument("--inputs", default="", help="input columns, comma separated")
    ide.add_argument("--outputs", required=True, help="output columns, comma separated")
    ide.add_argument("--order", default="auto", help="model order or 'auto' (default)")
    ide.add_argument("--method", default="auto",
                     help="auto (default: sysid.identify chooses the family, order and "
                          "feedthrough on held-out parts of the estimation data, when --order "
                          "is auto and neither --horizon nor --uncertainty bootstrap is given "
                          "and there are --inputs; else moesp, and the progress says so), or "
                          "one subspace method: moesp, ordinary-moesp, pi-moesp, n4sid, cva; "
                          "closed loop: pbsid or ssarx")
    ide.add_argument("--feedthrough", choices=("no", "yes", "auto"), default=None,
                     help="with a subspace --method: estimate D (yes), not (no) or decide "
                          "from held-out parts of the estimation data (auto); default, as "
                          "every sysid estimator: no with a given --order, auto with --order "
                          "auto; --method auto decides it itself")
    ide.add_argument("--horizon", type=int, default=None, help="past/future horizon")
    ide.add_argument("--split", default="0.5",
                     help="estimation part: fraction (0.5) or sample count (500); 1 = all")
    ide.add_argument("--dt", type=float, default=None,
                     help="sample time in seconds (a time column of the file must agree)")
    ide.add_argument("--time", default=None,
                     help="time column (sample time from its steps, in the unit of its "
                          "header, units row or name: Time [ms], time_ms; seconds without)")
    ide.add_argument("--resample", default=None, metavar="median|SECONDS",
                     help="a time column with gaps or jitter (a logger's stamps): interpolate "
                          "the record linearly onto a uniform grid of this sample time (median: "
                          "the stamps' median spacing); noted in the report")
    ide.add_argument("--resample-gap", dest="resample_gap", type=float, default=5.0,
                     help="with --resample: longest interval between stamps bridged, in sample "
                          "times (default 5); a longer one is refused, naming it")
    ide.add_argument("--detrend", choices=("auto", "none", "mean", "linear"), default="auto",
                     help="remove the estimation part's means (or lines) first; recorded in "
                          "the model. auto (default): none when sysid.identify runs (it "
                          "removes the offsets itself and restores them in the saved "
                          "model), else the means (a linear model has no constant term; "
                          "none fits the raw data, as SLICOT, and warns when an offset "
                          "dominates)")
    ide.add_argument("--delimiter", default=None, help="field separator (default: guessed)")
    ide.add_argument("--decimal", choices=(".", ","), default=".",
                     help="decimal mark of the numbers: . (default) or , (decimal commas, as "
                          "European loggers write them: 0,25;1,5 with a semicolon between "
                          "fields)")
    ide.add_argument("--report", required=True, help="output directory")
    ide.add_argument("--uncertainty", choices=("none", "bootstrap"), default="none",
                     help="pole standard deviations in the report from a residual bootstrap")
    ide.add_argument("--n-boot", dest="n_boot", type=int, default=100,
                     help="bootstrap records (default 100)")
    ide.add_argument("--compressor", choices=("auto", "qr", "correlation"), default="auto",
                     help="data compression: auto (default: fast, exact path when the data "
                          "are ill-conditioned), qr (exact), correlation (fast)")
    ide.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    ide.add_argument("--progress", action="store_true",
                     help="progress bars (rate, time left) even when stderr is not a terminal")
    ide.set_defaults(func=_identify)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sysid`` command: errors become one readable line and exit code 2."""
    args = _parser().parse_args(argv)
    try:
        with warnings.catch_warnings():
            _SHOWN.clear()
            warnings.showwarning = _show_warning  # one line each, no source line
            return int(args.func(args))
    except (SysidError, ImportError) as e:
        print(f"sysid: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"sysid: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except Exception as e:  # noqa: BLE001 - every CLI failure is one line and exit 2
        print(f"sysid: error: unexpected {type(e).__name__}: {_one_line(e)} (please report "
              "this with the command line)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # Ctrl-C: the computation stopped, every file written so far is whole (sysid._atomic)
        print("sysid: interrupted (KeyboardInterrupt); files already written are complete",
              file=sys.stderr)
        return 130


#: the warning lines printed by this run: the validation's residual test and the report's
#: both test the same residuals, and a warning said once is enough
_SHOWN: set[str] = set()


def _show_warning(message: Any, category: type[Warning], *_: Any, **__: Any) -> None:
    line = f"sysid: warning: {category.__name__}: {' '.join(str(message).split())}"
    if line not in _SHOWN:
        _SHOWN.add(line)
        print(line, file=sys.stderr)


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
