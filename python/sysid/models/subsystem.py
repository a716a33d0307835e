"""Subsystems: some outputs and inputs of a model (MATLAB's ``sys(i, j)``, python-control's
``sys[i, j]``).

``model[outputs, inputs]`` and ``model.select(outputs=..., inputs=...)`` take channel indices,
names, slices or lists of them, as :meth:`sysid.IOData.select` and ``FRD[i, j]`` do. The
result is a model of the same family (state space, continuous state space, transfer function,
process model, polynomial model with uncoupled outputs, ``identify``'s model) whose
uncertainty is the estimate's, seen through the selection. Each family selects its own
channels in a ``_select(iy, iu)`` method; this module holds what is common.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..data.segments import channel_index
from ..errors import DataError


def selection_key(key: Any, output_names: list[str], input_names: list[str],
                  what: str) -> tuple[Any, Any]:
    """``(outputs, inputs)`` of an index ``[outputs, inputs]``: slices and arrays as lists.

    Examples
    --------
    >>> from sysid.models.subsystem import selection_key
    >>> selection_key((0, slice(1, None)), ["y0"], ["u0", "u1", "u2"], "a model")
    (0, [1, 2])
    """
    if not (isinstance(key, tuple) and len(key) == 2):
        raise DataError(f"index {what} with two selections, [outputs, inputs] (use : for "
                        f"all), got {key!r}")
    sel = []
    for k, names, kind in zip(key, (output_names, input_names), ("output", "input")):
        if isinstance(k, slice):
            k = list(range(len(names)))[k]
        elif isinstance(k, np.ndarray):
            k = k.tolist()
        if isinstance(k, list) and not k:
            raise DataError(f"the {kind} selection {key!r} is empty")
        sel.append(k)
    return sel[0], sel[1]


#: the channel rule of records, FRDs and models: one function
channels = channel_index


def subsystem(model: Any, outputs: Any = None, inputs: Any = None) -> Any:
    """The model from the chosen ``inputs`` to the chosen ``outputs`` (names or indices,
    ``None`` for all), its uncertainty carried through.

    Examples
    --------
    >>> import sysid
    >>> m = sysid.StateSpaceModel([[0.5]], [[1.0, 2.0]], [[1.0], [3.0]],
    ...                           input_names=["a", "b"])
    >>> s = sysid.models.subsystem.subsystem(m, outputs=1, inputs="b")
    >>> s.B.ravel(), s.C.ravel(), s.input_names, s.output_names
    (array([2.]), array([3.]), ['b'], ['y1'])
    """
    iy = channels(outputs, list(model.output_names), "output")
    iu = channels(inputs, list(model.input_names), "input")
    if not iy:
        raise DataError("select at least one output")
    select = getattr(model, "_select", None)
    if select is None:
        raise DataError(f"{type(model).__name__} has no channel selection: select the "
                        "channels of the record (data.select(...)) and estimate again")
    out = select(iy, iu)
    out.info = {**dict(getattr(out, "info", None) or {}),  # the family's (its own offsets)
                "subsystem": {"outputs": list(out.output_names),
                              "inputs": list(out.input_names)}}
    unc = getattr(model, "uncertainty", None)
    if unc is not None and getattr(out, "uncertainty", None) is None:
        # the same parameters, seen through the selection
        out.uncertainty = unc.through(lambda m: m._select(iy, iu))
    return out


class ChannelSelection:
    """``select`` and ``[outputs, inputs]`` for a model class with ``input_names``,
    ``output_names`` and its own ``_select(iy, iu)`` (every :class:`sysid.ModelMixin`, and
    ``identify``'s model)."""

    input_names: Any
    output_names: Any

    def select(self, outputs: Any = None, inputs: Any = None) -> Any:
        """The model from some inputs to some outputs (names or indices, ``None`` for all;
        MATLAB's ``sys(i, j)``), of the same family, its uncertainty carried through.

        Examples
        --------
        >>> import sysid
        >>> m = sysid.StateSpaceModel([[0.5]], [[1.0, 2.0]], [[1.0], [3.0]])
        >>> m.select(outputs=1, inputs=[1]).dcgain()
        array([[12.]])
        """
        return subsystem(self, outputs, inputs)

    def __getitem__(self, key: Any) -> Any:
        """``model[outputs, inputs]``: :meth:`select` with indices, names, slices or lists
        (MATLAB's ``sys(i, j)``; ``model[0, :]`` is the first output from every input)."""
        return subsystem(self, *selection_key(key, list(self.output_names),
                                              list(self.input_names), "a model"))


def names(all_names: Any, index: list[int]) -> list[str]:
    """The names at ``index``."""
    return [list(all_names)[i] for i in index]
