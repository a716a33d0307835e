"""Say when a record the subspace methods refuse for want of excitation is a step test.

A step test (an input switched once or a few times, then held) is a common first record,
and the subspace data matrix cannot use it: its rows of future inputs, from ``past`` samples
on, see a constant or a handful of distinct windows, so the core's rank test refuses it
("use a richer input, a shorter horizon ..."). No horizon helps when the steps come before
the window does; what fits a step test is a model simulated from rest (:func:`sysid.procest`,
:func:`sysid.tfest`, :func:`sysid.oe`). :func:`step_test_note` is what the refusal adds.
"""

from __future__ import annotations

from typing import Any, NoReturn

import numpy as np

from ..data.iodata import IOData
from ..data.oversampling import oversampled_note
from ..errors import ExcitationError

__all__ = ["step_test_note", "step_changes", "stepped_inputs", "refuse_step_test",
           "MAX_STEPS"]

#: at most this many samples where an input changes make a record a step test
MAX_STEPS = 4


def step_changes(experiments: list[Any]) -> list[int] | None:
    """The samples (counted over the experiments laid end to end) where some input
    changes, when there are 1 to :data:`MAX_STEPS` of them (a step test), else ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> step_changes([(np.r_[np.zeros(20), np.ones(80)][:, None], None)])
    [20]
    >>> step_changes([(np.sin(np.arange(100.0))[:, None], None)]) is None
    True
    """
    changes: list[int] = []
    total = 0
    for e in experiments:
        u = np.asarray(e[0])
        if u.ndim != 2 or u.shape[1] == 0 or u.shape[0] < 2:
            return None
        changes += (np.flatnonzero(np.any(np.diff(u, axis=0) != 0, axis=1)) + 1
                    + total).tolist()
        total += u.shape[0]
        if len(changes) > MAX_STEPS:
            return None
    return changes or None


def stepped_inputs(data: Any) -> dict[str, list[int]]:
    """The inputs of record ``data`` that each change at 1 to :data:`MAX_STEPS` samples (a
    step or a pulse), by name, with those samples (:func:`step_changes` of the input alone):
    of several inputs, one may be a step test beside others that are richly excited.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> u = np.c_[np.sin(np.arange(100.0)), np.r_[np.zeros(40), np.ones(60)]]
    >>> stepped_inputs(sysid.IOData(u, np.zeros((100, 1)), 1.0))
    {'u1': [40]}
    """
    out = {}
    for j, name in enumerate(data.input_names):
        c = step_changes([(e[0][:, [j]], None) for e in data.experiments])
        if c is not None:
            out[name] = c
    return out


def step_test_note(experiments: list[Any], past: int) -> str:
    """The sentence an excitation refusal adds for a step test (``""`` for another record):
    where the inputs change, and what fits such a record.

    Examples
    --------
    >>> import numpy as np
    >>> u = np.r_[0.0, np.full(99, 50.0)][:, None]
    >>> step_test_note([(u, np.zeros((100, 1)))], past=8)[:60]
    'the input changes at 1 sample of 100 (index 1), a step test,'
    """
    changes = step_changes(experiments)
    if changes is None:
        return ""
    total = sum(np.asarray(e[0]).shape[0] for e in experiments)
    k = len(changes)
    where = ", ".join(str(c) for c in changes)  # 0-based, as the arrays index them
    early = all(c - off <= past for c, off in _offsets(changes, experiments))
    why = (f"every change comes before the data matrix's rows of future inputs start (sample "
           f"{past}, the past horizon), so no horizon helps" if early else
           "the data matrix's rows of future inputs see only a few distinct windows")
    return (f"the input changes at {k} sample{'s' if k > 1 else ''} of {total} "
            f"(index {where}), a step test, and {why}; fit it with a "
            f"model simulated from rest: sysid.procest(data, 'P1D') (a process model), "
            f"sysid.tfest or sysid.oe, after subtracting the values before the step "
            f"(u - u[0], y - y[0]) rather than the means")


def refuse_step_test(err: ExcitationError, experiments: list[Any], past: int) -> NoReturn:
    """Raise the core's excitation error ``err``; for a step test, with what fits one
    (:func:`step_test_note`), and for inputs that change slowly against the sample time,
    the decimation that helps (:func:`~sysid.data.oversampling.oversampled_note`), in place
    of the core's remedy (``err.remedy``: a richer input, a shorter horizon), which the new
    error's ``remedy`` then holds.

    Examples
    --------
    >>> import numpy as np, sysid
    >>> from sysid.subspace.steptest import refuse_step_test
    >>> u = np.r_[0.0, np.full(99, 50.0)][:, None]
    >>> e = sysid.ExcitationError("the input is not persistently exciting: ...; use a richer "
    ...                           "input")
    >>> e.problem = "the input is not persistently exciting: ..."
    >>> try:
    ...     refuse_step_test(e, [(u, np.zeros((100, 1)))], past=8)
    ... except sysid.ExcitationError as said:
    ...     print(str(said)[:65])
    the input is not persistently exciting: ...: the input changes at
    """
    note = step_test_note(experiments, past) or oversampled_note(
        IOData(u=[e[0] for e in experiments], y=[e[1] for e in experiments]))
    if note and err.problem:  # the core's remedy in the record's terms
        raise err.with_remedy(note) from None
    raise err


def _offsets(changes: list[int], experiments: list[Any]) -> list[tuple[int, int]]:
    """Each change with the first sample index of its experiment."""
    starts = np.cumsum([0] + [np.asarray(e[0]).shape[0] for e in experiments])
    return [(c, int(starts[np.searchsorted(starts, c, side="right") - 1])) for c in changes]
