"""Choosing an ARX structure: ``arxstruc``, ``selstruc`` and ``struc``, as MATLAB's.

``arxstruc(data, na, nb, nk)`` ranks every structure of the ranges by its loss on the
estimation data, from one compression (Rust); MATLAB's own form, ``arxstruc(ze, zv, NN)``
with ``NN = struc(1:10, 1:10, 1:5)``, fits each row of ``NN`` on ``ze`` and scores its
one-step prediction errors on the validation data ``zv``. ``selstruc`` picks one by AIC
or MDL as MATLAB's (``loss (1 + 2 p / N)``, ``loss (1 + p log N / N)``), BIC (``log loss +
p log N / N``) or a number ``c`` (``loss (1 + c p / N)``; ``0``: the lowest loss, the choice
for losses on validation data).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .. import _sysid
from .._checks import as_int, experiment_arrays, require_inputs_vary
from ..data.iodata import as_record
from ..data.offsets import check_offsets
from ..errors import DataError, FeedthroughWarning, StabilityWarning
from ..validation.free_run import skipped

__all__ = ["StructureTable", "arxstruc", "selstruc", "struc"]


class StructureTable(np.ndarray):
    """The array :func:`arxstruc` returns, remembering the number of estimation samples
    (``n_samples``) that :func:`selstruc` needs (MATLAB keeps it in the table too)."""

    n_samples: int | None = None

    def __array_finalize__(self, obj: Any) -> None:
        self.n_samples = getattr(obj, "n_samples", None)


def struc(na: Any, nb: Any = None, nk: Any = None) -> np.ndarray:
    """Every ``[na, nb, nk]`` of the ranges, one per row (MATLAB's ``struc``), for
    ``arxstruc(ze, zv, NN)``; ``struc(na)`` alone: the AR orders ``[na]`` of a time series.

    Examples
    --------
    >>> import sysid
    >>> sysid.struc([1, 2], [1], [0, 1]).tolist()
    [[1, 1, 0], [1, 1, 1], [2, 1, 0], [2, 1, 1]]
    >>> sysid.struc(range(1, 4)).tolist()
    [[1], [2], [3]]
    """
    if nb is None and nk is None:  # a time series: AR orders only
        return np.array([[a] for a in _range(na, "na")], dtype=int)
    if nb is None or nk is None:
        raise DataError("give both nb and nk (the input orders and delays), or neither for "
                        "the AR orders of a time series")
    ra, rb, rk = (_range(v, name) for v, name in ((na, "na"), (nb, "nb"), (nk, "nk")))
    return np.array([[a, b, k] for a in ra for b in rb for k in rk], dtype=int)


def _range(v: Any, name: str) -> list[int]:
    """The whole numbers >= 0 of an order range (a number or a sequence)."""
    return [as_int(int(o) if isinstance(o, (float, np.floating)) and float(o).is_integer()
                   else o, f"every entry of {name}", 0) for o in np.atleast_1d(v).tolist()]


def _single_output(exps: list[Any], data: Any) -> None:
    ny = exps[0][1].shape[1]
    if ny > 1:  # the Rust table sums per-output losses of a diagonal-A model arx does not build
        names = getattr(data, "output_names", None) or [f"y{i}" for i in range(ny)]
        raise DataError(
            f"arxstruc ranks single-output ARX structures, and the data have {ny} outputs "
            f"({', '.join(map(str, names))}): rank one output at a time, "
            f"sysid.arxstruc(data.select(outputs={names[0]!r}), na, nb, nk), or choose a "
            "multi-output model's order with sysid.n4sid(data, order='auto') or "
            "sysid.ssest(data, order='auto')")


def arxstruc(data: Any, na: Any, nb: Any = None, nk: Any = None) -> np.ndarray:
    """Loss of every ARX structure in the ranges, from one compression; or, as MATLAB's
    ``arxstruc(ze, zv, NN)``, of every row ``[na, nb, nk]`` of ``NN`` (:func:`struc`) fitted on
    ``ze`` and scored on the validation data ``zv``.

    Returns rows ``[na, nb, nk, loss, n_parameters]`` (loss: mean squared residual on the
    estimation data, or mean squared one-step prediction error on ``zv``); structures whose
    regression is rank deficient are left out. Single-output data only (as MATLAB's
    ``arxstruc``): rank one output at a time (``data.select(outputs=k)``), or choose a
    multi-output model's order with ``sysid.n4sid(data, order="auto")`` or
    ``sysid.ssest(data, order="auto")``. With ``m`` inputs MATLAB's rows are ``[na, nb1..nbm,
    nk1..nkm]`` and so are the table's (then loss and parameter count): the ranges give every
    input the same ``nb`` and ``nk``, as do rows ``[na, nb, nk]`` of :func:`struc` in
    ``NN``, so ``arx(data, selstruc(table))`` takes the choice as it is. Rows of ``NN`` whose
    ARX model's simulation diverges are scored without a warning (as MATLAB's: their
    one-step predictors, which the table scores, are stable); ``arx`` warns when the chosen
    structure is fitted.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from scipy import signal
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(400)
    >>> e = 0.1 * rng.standard_normal(400)  # equation error: the ARX(1, 1, 1) structure
    >>> y = signal.lfilter([0, 1.0], [1, -0.5], u) + signal.lfilter([1], [1, -0.5], e)
    >>> d = sysid.IOData(u[:, None], y[:, None], 1.0)
    >>> table = sysid.arxstruc(d, [1, 2], [1, 2], [1])
    >>> sysid.selstruc(table, "bic", 400)
    (1, 1, 1)
    >>> v = sysid.arxstruc(d[:200], d[200:], sysid.struc([1, 2], [1, 2], [1]))  # MATLAB's
    >>> sysid.selstruc(v, 0)
    (1, 1, 1)
    """
    data = as_record(data)  # a (u, y) pair, as ssest and compare take
    exps = experiment_arrays(data)
    _single_output(exps, data)
    if hasattr(na, "n_inputs") or (isinstance(na, tuple) and len(na) == 2):
        return _on_validation(data, exps, as_record(na), nb, nk)
    if nb is None or nk is None:
        raise DataError("arxstruc needs the ranges na, nb and nk: arxstruc(data, na, nb, nk), "
                        "or MATLAB's arxstruc(ze, zv, NN) with NN = sysid.struc(na, nb, nk)")
    check_offsets(data)
    rng = [_range(v, name) for v, name in ((na, "na"), (nb, "nb"), (nk, "nk"))]
    require_inputs_vary(exps, "arxstruc", getattr(data, "input_names", None))
    out = _per_input(np.asarray(_sysid.arx_struc(exps, *rng)),
                     exps[0][0].shape[1]).view(StructureTable)
    if not len(out):
        raise DataError("every ARX structure in the ranges has a rank-deficient regression "
                        "(the data do not determine any of them): check that the input "
                        "and the output vary, or try smaller orders")
    out.n_samples = int(sum(y.shape[0] for _, y in exps))
    return out


def _per_input(rows: np.ndarray, m: int) -> np.ndarray:
    """Rows ``[na, nb, nk, ...]`` with one ``nb`` and ``nk`` shared by the ``m`` inputs as
    MATLAB's multi-input rows ``[na, nb1..nbm, nk1..nkm, ...]``, so that :func:`selstruc`'s
    choice goes straight into ``arx`` (it returned three numbers, which ``arx`` refuses for
    several inputs)."""
    if m == 1 or not len(rows):
        return rows
    return np.column_stack([rows[:, :1], np.repeat(rows[:, 1:2], m, axis=1),
                            np.repeat(rows[:, 2:3], m, axis=1), rows[:, 3:]])


def _on_validation(data: Any, exps: list[Any], val: Any, nn: Any, extra: Any) -> np.ndarray:
    """MATLAB's ``arxstruc(ze, zv, NN)``: each row fitted on ``data``, scored on ``val``."""
    from .arx import arx

    if extra is not None:
        raise DataError("arxstruc(ze, zv, NN) takes the structures as one array NN (rows "
                        "[na, nb, nk], sysid.struc(na, nb, nk)), nothing after it")
    vexps = experiment_arrays(val)
    _single_output(vexps, val)
    m = exps[0][0].shape[1]
    if vexps[0][0].shape[1] != m:
        raise DataError(f"the validation data have {vexps[0][0].shape[1]} input(s) and the "
                        f"estimation data {m}: pass records of the same channels")
    width = 1 + 2 * m
    form = "[na, nb, nk]" if m == 1 else (
        f"[na, nb1..nb{m}, nk1..nk{m}] ({width} numbers for {m} inputs)")
    try:
        rows = np.asarray(nn if nn is not None else [], dtype=float)
    except (TypeError, ValueError):
        rows = np.zeros((0, 0))  # ragged or not numbers: refused below
    if rows.ndim == 1 and rows.size in (width, 3):
        rows = rows[None, :]
    if m > 1 and rows.ndim == 2 and rows.shape[1] == 3:  # struc's rows: nb, nk shared
        rows = _per_input(rows, m)
    if (rows.ndim != 2 or rows.shape[1] != width or not len(rows)
            or not np.all(np.isfinite(rows)) or np.any(rows != np.round(rows))
            or np.any(rows < 0)):
        hint = "sysid.struc(na, nb, nk)" if m == 1 else "one row per structure"
        raise DataError(f"NN must hold rows {form} of whole numbers >= 0 ({hint}), got "
                        f"{np.asarray(nn)!r:.80}")
    out = []
    said: dict[tuple[type, str], Any] = {}
    n_val = sum(y.shape[0] for _, y in vexps)
    for row in rows.astype(int).tolist():
        a, b, k = row[0], row[1:1 + m], row[1 + m:]
        if a + sum(b) == 0:
            continue
        try:
            with warnings.catch_warnings(record=True) as caught, skipped():
                warnings.simplefilter("always")
                model = arx(data, a, [b], [k])
        except DataError:
            continue  # a structure the estimation data do not determine
        # a candidate whose simulation diverges says nothing about the table (its one-step
        # predictor, scored here, is stable): the robot arm's 125 rows gave ten such
        # warnings; the others (offsets) once each, not once per row. A row's nk = 1 against
        # a direct term is the table's to show (its nk = 0 rows score it), not a warning
        for w in caught:
            if not issubclass(w.category, (StabilityWarning, FeedthroughWarning)):
                said.setdefault((w.category, str(w.message)), w)
        e = [y - model.predict(u, y, 1) for u, y in vexps]
        loss = float(sum(np.sum(r ** 2) for r in e) / n_val)
        if np.isfinite(loss):
            out.append([*row, loss, a + sum(b)])
    for w in said.values():
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if not out:
        raise DataError("no structure of NN could be fitted and scored: check that the input "
                        "and the output vary, or try smaller orders")
    table = np.asarray(out).view(StructureTable)
    table.n_samples = int(sum(y.shape[0] for _, y in exps))
    return table


def selstruc(
    table: np.ndarray, criterion: Any = "aic", n_samples: int | None = None
) -> tuple[int, ...]:
    """Choose ``(na, nb, nk)`` from an :func:`arxstruc` table as MATLAB's ``selstruc(V, c)``,
    with ``V`` the loss, ``d`` the number of parameters and ``N`` ``n_samples``:

    * ``"aic"``: the least ``V (1 + 2 d / N)`` (MATLAB's ``log(V (1 + 2 d / N))``, the same
      choice; Akaike's ``log V + 2 d / N`` to first order);
    * ``"mdl"``: the least ``V (1 + d log N / N)``, Rissanen's MDL as MATLAB's;
    * ``"bic"``: the least ``log V + d log N / N`` (the Bayesian information criterion, as
      MATLAB's ``aic(model, "BIC")`` divided by ``N``; MATLAB's ``selstruc`` has no
      ``"bic"``);
    * a number ``c``: the least ``V (1 + c d / N)``, ``0`` the lowest loss (the choice on a
      table of losses on validation data).

    ``n_samples``: by default the number of estimation samples the table remembers. A table
    of ``m``-input rows gives ``(na, nb1, .., nbm, nk1, .., nkm)``.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> t = np.array([[1, 1, 1, 0.50, 2], [2, 2, 1, 0.49, 4]])
    >>> sysid.selstruc(t, 0), sysid.selstruc(t, "aic", 100)
    ((2, 2, 1), (1, 1, 1))
    """
    if np.ndim(table) != 2 or np.shape(table)[1] < 3:
        raise DataError(f"table must be the 2-D table of sysid.arxstruc (rows [na, nb.., "
                        f"nk.., loss, parameters], or [na, loss, parameters] for a time "
                        f"series), got {type(table).__name__} of shape {np.shape(table)}")
    if np.shape(table)[0] == 0:
        raise DataError("table has no rows, so there is no structure to choose: pass the "
                        "table of sysid.arxstruc with at least one structure (widen the "
                        "ranges of na, nb, nk if every one was left out)")
    loss, p = table[:, -2], table[:, -1]
    if isinstance(criterion, (int, float, np.number)) and not isinstance(criterion, bool):
        c = float(criterion)
        if not (np.isfinite(c) and c >= 0):
            raise DataError(f"a numeric criterion must be a finite number >= 0, got {c}")
        n = getattr(table, "n_samples", None) if n_samples is None else n_samples
        score = loss if c == 0 else loss * (1 + c * p / as_int(n, "n_samples"))
        return _structure(table[int(np.argmin(score))])
    if n_samples is None:
        n_samples = getattr(table, "n_samples", None)
    if n_samples is None:
        raise DataError("selstruc needs n_samples (the number of estimation samples): this "
                        "table does not remember it (pass the one from sysid.arxstruc)")
    n_samples = as_int(n_samples, "n_samples")
    if criterion == "aic":  # MATLAB's log(V (1 + 2 d / N)): the same choice
        score = loss * (1 + 2 * p / n_samples)
    elif criterion == "mdl":  # MATLAB's V (1 + d log N / N)
        score = loss * (1 + p * np.log(n_samples) / n_samples)
    elif criterion == "bic":
        score = np.log(loss) + p * np.log(n_samples) / n_samples
    else:
        raise DataError(f"unknown criterion {criterion!r}; use 'aic', 'bic', 'mdl' or a "
                        "number (0: the lowest loss)")
    return _structure(table[int(np.argmin(score))])


def _structure(row: np.ndarray) -> tuple[int, ...]:
    """The structure of a table row: everything before its loss and parameter count."""
    return tuple(int(v) for v in row[:-2])
