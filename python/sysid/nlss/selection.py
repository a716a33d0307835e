"""Validation-based choice of a simulation-error search's iterate (``pnlss(validation=)``).

A nonlinear state-space search lowers the training cost at every iteration, but its later
iterates can fit the training record's noise or amplitudes and simulate other data worse
(on the F-16 records the decoupled PNLSS fit's level-2 error rose from iteration 24 on while
its training cost kept falling, ``benches/results/nonlinear.md``). The PNLSS literature
keeps every iterate and returns the one that simulates validation data best (Paduart et
al., Automatica 46, 2010, sec. 5; the PNLSS toolbox's examples select the model "with the
lowest validation error"), as ``nlssest`` stops on its validation error. This module holds
the split of the record (a fraction of each experiment's end, or separate records) and the
choice.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..data.iodata import IOData
from ..errors import DataError, NumericalError
from ..validation.records import validation_record

__all__ = ["ValidationRecords", "select_iterate", "validation_data", "validation_records"]


class ValidationRecords:
    """Records ``(u, y, start)`` in engineering units: each simulated whole from rest, its
    squared errors summed from sample ``start`` on, each output divided by ``scale``.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.nlss.selection import ValidationRecords
    >>> v = ValidationRecords([(np.zeros((4, 1)), np.ones((4, 1)), 2)], np.ones(1))
    >>> v.error(lambda u: np.zeros((4, 1)))
    1.0
    """

    def __init__(self, records: list[tuple[np.ndarray, np.ndarray, int | None]],
                 scale: np.ndarray, settle: Callable[[int], int] | None = None) -> None:
        out = []
        for u, y, start in records:
            if start is None:  # a separate record: scored after its transient from rest
                start = 0 if settle is None else int(settle(u.shape[0]))
            out.append((u, y, int(start)))
        self.records = out
        self.scale = np.asarray(scale, float)

    def error(self, simulate: Callable[[np.ndarray], np.ndarray]) -> float:
        """Mean squared error of the scaled outputs over the scored samples; ``inf`` when a
        simulation diverges."""
        total, count = 0.0, 0
        for u, y, start in self.records:
            try:
                yh = np.asarray(simulate(u), float)
            except (NumericalError, FloatingPointError, OverflowError):
                return float("inf")
            e = (y[start:] - yh[start:]) / self.scale
            if not np.all(np.isfinite(e)):
                return float("inf")
            total += float(np.sum(e * e))
            count += e.size
        return total / max(count, 1)


def validation_data(validation: Any, data: IOData) -> Any:
    """Records (an :class:`IOData` or a ``(u, y)`` pair) checked against ``data``
    (:func:`sysid.validation.records.validation_record`); anything else (a fraction)
    unchanged, for the caller to check."""
    if isinstance(validation, (IOData, tuple)):
        return validation_record(validation, data)
    return validation


def validation_records(data: IOData, validation: Any, periodic: bool
                       ) -> tuple[IOData, list[tuple[np.ndarray, np.ndarray, int | None]]]:
    """The training record and the validation records ``(u, y, start)`` of ``validation``
    (``start`` None for a separate record: its transient is the fit's to set).

    Parameters
    ----------
    data : IOData
        The estimation record.
    validation : float or IOData or (u, y)
        A fraction in ``(0, 0.9]`` of each experiment's end held out of the fit (the
        experiment is simulated whole and its held-out end scored), or separate records
        (each simulated from rest).
    periodic : bool
        Whether the fit uses periods (a held-out fraction would cut them: refused).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.nlss.selection import validation_records
    >>> d = sysid.IOData(u=np.ones(100), y=np.arange(100.0))
    >>> train, recs = validation_records(d, 0.2, periodic=False)
    >>> train.lengths, recs[0][2]
    ([80], 80)
    """
    validation = validation_data(validation, data)
    if isinstance(validation, IOData):
        return data, [(u, y, None) for u, y in validation.experiments]
    if isinstance(validation, bool) or not isinstance(validation, (int, float, np.floating)) \
            or not 0.0 < float(validation) <= 0.9:
        raise DataError(f"validation must be a fraction in (0, 0.9] of each experiment held "
                        f"out of the fit, or validation records (an IOData or a (u, y) "
                        f"pair), got {validation!r}")
    if periodic:
        raise DataError("a held-out fraction would cut the periods of periodic data: pass "
                        "validation records instead (validation=IOData, e.g. another "
                        "realisation or level)")
    us, ys, recs = [], [], []
    for u, y in data.experiments:
        at = int(round(u.shape[0] * (1.0 - float(validation))))
        if at < 2 or at >= u.shape[0]:
            raise DataError(f"validation={validation} leaves {at} of an experiment's "
                            f"{u.shape[0]} samples for the fit and {u.shape[0] - at} to "
                            f"validate on; give a longer record or another fraction")
        us.append(u[:at])
        ys.append(y[:at])
        recs.append((u, y, at))
    train = IOData(us, ys, data.dt, input_names=data.input_names,
                   output_names=data.output_names)
    return train, recs


def select_iterate(build: Callable[[np.ndarray], Any], iterates: np.ndarray,
                   val: ValidationRecords) -> tuple[int, Any, list[float]]:
    """The iterate (a row of ``iterates``, the start first) whose model has the lowest
    validation error (the earliest on a tie), that model and every iterate's error.

    Examples
    --------
    >>> import numpy as np
    >>> from sysid.nlss.selection import ValidationRecords, select_iterate
    >>> val = ValidationRecords([(np.ones((5, 1)), np.full((5, 1), 2.0), 0)], np.ones(1))
    >>> class M:
    ...     def __init__(self, g): self.g = g
    ...     def simulate(self, u): return self.g * u
    >>> k, m, errs = select_iterate(lambda th: M(th[0]), np.array([[0.0], [1.5], [3.0]]), val)
    >>> k, errs
    (1, [4.0, 0.25, 1.0])
    """
    errors = []
    best, best_model = 0, None
    for k, th in enumerate(iterates):
        m = build(np.asarray(th))
        e = val.error(m.simulate)
        errors.append(e)
        if best_model is None or e < errors[best]:
            best, best_model = k, m
    return best, best_model, errors
